// What every part of the harness shares: the repository's root, a sleep and the CPU time of
// the processes this test file started (its drivers and browsers).
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// The CPU seconds (user + system) the processes below this one have used so far: the drivers
// and the browsers they launched, whose processes are their children (Linux /proc).
export function descendantsCpuSeconds(root = process.pid) {
  const tick = 100; // USER_HZ on Linux
  const procs = new Map();
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    let stat;
    try { stat = fs.readFileSync(`/proc/${d}/stat`, 'utf8'); } catch { continue; }
    // The command name is in parentheses and may hold spaces: the fields follow the last ')'.
    const f = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
    procs.set(Number(d), { ppid: Number(f[1]), cpu: (Number(f[11]) + Number(f[12])) / tick });
  }
  const below = (pid) => {
    for (let p = procs.get(pid)?.ppid; p; p = procs.get(p)?.ppid) if (p === root) return true;
    return false;
  };
  let s = 0;
  for (const [pid, p] of procs) if (below(pid)) s += p.cpu;
  return s;
}
