"""The course platforms' containers (Gradescope, PrairieLearn) simulated on this machine, for
platform_check.py and hostile_check.py --in-platform (docs/testing.md).

A simulated container is bubblewrap run as root: the host's top-level folders read-only (links
as links) on bubblewrap's own root, the caller's folders bound over them, a private /dev,
/proc, /tmp, /run and /var/tmp, no network (a loopback of its own), its own PID, IPC and UTS
namespaces, ended with its parent, and **bwrap masked** (/dev/null bound over it: Docker's
default profile forbids the namespaces bubblewrap needs), so a siftlab inside finds no usable
bubblewrap and runs its container tier. /sys is the host's, read-only, as a container's is:
siftlab cannot make its own cgroups there. `Cgroup` holds a container to the platforms'
defaults, 768 MB and half a CPU (cgroup v1 memory and cpu, or v2's memory.max and cpu.max,
made under the hierarchy this process is in; root needed).

Python 3.8+, standard library only; Linux, root, bubblewrap.
"""

import os
import shutil
import time

MEMORY = 768 << 20  # Gradescope's default container memory
CPU = 0.5  # and its default share of a CPU


def container_argv(command, binds=(), tmp=None, ro_binds=(), setenv=(), unsetenv=(), as_pid_1=False):
    """The bwrap command running `command` (a list) in a simulated container.

    binds: (host folder, path inside) pairs, bound writable; a top-level name they take is
    not the host's. tmp: a host folder bound at /tmp (default: a fresh tmpfs). ro_binds:
    host paths bound read-only at the same path, over everything else (a repository or a
    binary under /tmp stays visible). setenv: (name, value) pairs; unsetenv: names. as_pid_1:
    the command is the namespace's init (bubblewrap's own init, which reaps it, is left out:
    the command's CPU time then reaches its caller's, as a child waited for)."""
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        raise OSError("no bwrap on the PATH: the simulation needs bubblewrap (apt install bubblewrap)")
    taken = {"proc", "dev", "tmp", "run"} | {dst.strip("/").split("/")[0] for _, dst in binds}
    cmd = ["bwrap"]
    for name in sorted(os.listdir("/")):
        path = "/" + name
        if name in taken:
            continue
        if os.path.islink(path):
            cmd += ["--symlink", os.readlink(path), path]
        elif os.path.isdir(path):
            cmd += ["--ro-bind", path, path]
    for src, dst in binds:
        cmd += ["--bind", src, dst]
    cmd += ["--dev", "/dev", "--proc", "/proc"]
    cmd += ["--bind", tmp, "/tmp"] if tmp else ["--tmpfs", "/tmp"]
    cmd += ["--tmpfs", "/run", "--tmpfs", "/var/tmp", "--ro-bind", "/dev/null", bwrap,
            "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts", "--die-with-parent"]
    if as_pid_1:
        cmd.append("--as-pid-1")
    for path in ro_binds:
        cmd += ["--ro-bind", path, path]
    for name, value in setenv:
        cmd += ["--setenv", name, value]
    for name in unsetenv:
        cmd += ["--unsetenv", name]
    return cmd + ["--"] + list(command)


class Cgroup:
    """A cgroup of `memory` bytes (no swap) and `cpu` CPUs (None: no quota) for one simulated
    container, where this process may make one; its CPU time counted (v1: cpuacct; v2:
    cpu.stat), as a container's cgroup counts it. join() in the child before exec."""

    def __init__(self, name, memory=MEMORY, cpu=CPU):
        self.dirs, self.memory_dir = [], None
        with open("/proc/self/cgroup") as f:
            own = f.read().splitlines()
        quota = None if cpu is None else str(int(cpu * 100000))
        if os.path.exists("/sys/fs/cgroup/cgroup.controllers"):
            rel = [l.split(":", 2)[2] for l in own if l.startswith("0::")][0].lstrip("/")
            d = os.path.join("/sys/fs/cgroup", rel, name)
            os.mkdir(d)
            self.dirs.append(d)
            self._set(d, "memory.max", str(memory))
            self._set(d, "memory.swap.max", "0", optional=True)
            if quota:
                self._set(d, "cpu.max", quota + " 100000")
            self.memory_dir, self.peak, self.events = d, "memory.peak", "memory.events"
            self.usage = (d, "cpu.stat", "usage_usec ", 1e6)
            return
        for ctrl in ("memory", "cpuacct", "cpu") if quota else ("memory", "cpuacct"):
            rel = [l.split(":", 2)[2] for l in own if ctrl in l.split(":")[1].split(",")][0].lstrip("/")
            d = os.path.join("/sys/fs/cgroup", ctrl, rel, name)
            os.mkdir(d)
            self.dirs.append(d)
            if ctrl == "memory":
                self._set(d, "memory.limit_in_bytes", str(memory))
                self._set(d, "memory.memsw.limit_in_bytes", str(memory), optional=True)
                self.memory_dir, self.peak, self.events = d, "memory.max_usage_in_bytes", "memory.oom_control"
            elif ctrl == "cpuacct":
                self.usage = (d, "cpuacct.usage", "", 1e9)
            else:
                self._set(d, "cpu.cfs_period_us", "100000")
                self._set(d, "cpu.cfs_quota_us", quota)

    @staticmethod
    def _set(d, f, v, optional=False):
        try:
            with open(os.path.join(d, f), "w") as fh:
                fh.write(v)
        except OSError:
            if not optional:
                raise

    def join(self):
        # In the child before exec: everything the container starts is inside.
        for d in self.dirs:
            with open(os.path.join(d, "cgroup.procs"), "w") as fh:
                fh.write("0")

    def _read(self, f, d=None):
        try:
            with open(os.path.join(d or self.memory_dir, f)) as fh:
                return fh.read()
        except OSError:
            return ""

    def cpu_seconds(self):
        """The CPU time of everything that ran in the container, reaped or not (-1: unknown)."""
        d, f, key, unit = self.usage
        for line in self._read(f, d).splitlines():
            if line.startswith(key):
                return int(line[len(key):]) / unit
        return -1.0

    def peak_bytes(self):
        try:
            return int(self._read(self.peak))
        except ValueError:
            return -1

    def oom_kills(self):
        """Processes the kernel's OOM killer ended in the container (-1: not counted here)."""
        for line in self._read(self.events).splitlines():
            if line.startswith("oom_kill "):
                return int(line.split()[1])
        return -1

    def remove(self):
        for d in self.dirs:
            for _ in range(50):
                try:
                    os.rmdir(d)
                    break
                except OSError:
                    time.sleep(0.1)
