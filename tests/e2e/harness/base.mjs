// What every part of the harness shares: the repository's root, a sleep and the CPU time of
// the processes this test file started (its drivers and browsers).
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// The processes below `root` (this Node process by default: the drivers, and the browsers they
// launched as their children), from Linux's /proc: pid -> its /proc/PID/stat fields after the
// command name (which sits in parentheses and may hold spaces).
export function descendants(root = process.pid) {
  const procs = new Map();
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const stat = fs.readFileSync(`/proc/${d}/stat`, 'utf8');
      procs.set(Number(d), stat.slice(stat.lastIndexOf(')') + 2).split(' '));
    } catch { /* gone */ }
  }
  const below = (pid) => {
    for (let p = Number(procs.get(pid)?.[1]); p; p = Number(procs.get(p)?.[1])) if (p === root) return true;
    return false;
  };
  return new Map([...procs].filter(([pid]) => below(pid)));
}

// The CPU seconds (user + system; USER_HZ 100 on Linux) the processes below this one have used.
export function descendantsCpuSeconds(root = process.pid) {
  let s = 0;
  for (const f of descendants(root).values()) s += (Number(f[11]) + Number(f[12])) / 100;
  return s;
}
