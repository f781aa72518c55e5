//! The seccomp filter bubblewrap installs in the sandbox (`--seccomp FD`,
//! docs/marking.md, "The sandbox"): a classic BPF program, built here so
//! that no library sits between siftlab and the kernel's format (it is a
//! few dozen fixed instructions). Everything is allowed but what a student's
//! file never needs and what widens the kernel's attack surface: new
//! namespaces, tracing other processes, the kernel's keyrings, eBPF,
//! performance counters, mounts, modules, kexec, swap, reboot, the clock,
//! io_uring. A denied call fails with EPERM (clone3 with ENOSYS, so the C
//! library falls back to clone, whose flags the filter can read). A call
//! from another architecture's ABI (i386 or x32 on x86_64) is denied whole,
//! since its numbers mean other calls.

/// seccomp's return values: run the call, or fail it with an errno.
const RET_ALLOW: u32 = 0x7fff_0000;
const RET_ERRNO: u32 = 0x0005_0000;

/// Namespaces a clone may not create (CLONE_NEW*: NS, CGROUP, UTS, IPC,
/// USER, PID, NET).
pub const CLONE_NEW: u32 =
    0x0002_0000 | 0x0200_0000 | 0x0400_0000 | 0x0800_0000 | 0x1000_0000 | 0x2000_0000 | 0x4000_0000;

/// Calls denied whole, by name (the tables below, in this order).
#[cfg(test)]
const DENIED: [&str; 44] = [
    "unshare",
    "setns",
    "ptrace",
    "process_vm_readv",
    "process_vm_writev",
    "kcmp",
    "pidfd_getfd",
    "keyctl",
    "add_key",
    "request_key",
    "bpf",
    "perf_event_open",
    "userfaultfd",
    "fanotify_init",
    "mount",
    "umount2",
    "pivot_root",
    "chroot",
    "open_tree",
    "move_mount",
    "fsopen",
    "fsconfig",
    "fsmount",
    "fspick",
    "mount_setattr",
    "name_to_handle_at",
    "open_by_handle_at",
    "kexec_load",
    "kexec_file_load",
    "init_module",
    "finit_module",
    "delete_module",
    "swapon",
    "swapoff",
    "reboot",
    "acct",
    "settimeofday",
    "clock_settime",
    "clock_adjtime",
    "adjtimex",
    "syslog",
    "io_uring_setup",
    "io_uring_enter",
    "io_uring_register",
];

/// An architecture's audit id and syscall numbers (`name`, number).
pub struct Arch {
    pub audit: u32,
    /// Numbers at or over this are another ABI (x32 on x86_64).
    pub abi_bit: Option<u32>,
    pub clone: u32,
    pub clone3: u32,
    /// socket(2): denied whole in the container tier (no network namespace
    /// hides the network there); its pipes are all the harness needs.
    pub socket: u32,
    pub numbers: &'static [(&'static str, u32)],
}

pub const X86_64: Arch = Arch {
    audit: 0xc000_003e,
    abi_bit: Some(0x4000_0000),
    clone: 56,
    clone3: 435,
    socket: 41,
    numbers: &[
        ("unshare", 272),
        ("setns", 308),
        ("ptrace", 101),
        ("process_vm_readv", 310),
        ("process_vm_writev", 311),
        ("kcmp", 312),
        ("pidfd_getfd", 438),
        ("keyctl", 250),
        ("add_key", 248),
        ("request_key", 249),
        ("bpf", 321),
        ("perf_event_open", 298),
        ("userfaultfd", 323),
        ("fanotify_init", 300),
        ("mount", 165),
        ("umount2", 166),
        ("pivot_root", 155),
        ("chroot", 161),
        ("open_tree", 428),
        ("move_mount", 429),
        ("fsopen", 430),
        ("fsconfig", 431),
        ("fsmount", 432),
        ("fspick", 433),
        ("mount_setattr", 442),
        ("name_to_handle_at", 303),
        ("open_by_handle_at", 304),
        ("kexec_load", 246),
        ("kexec_file_load", 320),
        ("init_module", 175),
        ("finit_module", 313),
        ("delete_module", 176),
        ("swapon", 167),
        ("swapoff", 168),
        ("reboot", 169),
        ("acct", 163),
        ("settimeofday", 164),
        ("clock_settime", 227),
        ("clock_adjtime", 305),
        ("adjtimex", 159),
        ("syslog", 103),
        ("io_uring_setup", 425),
        ("io_uring_enter", 426),
        ("io_uring_register", 427),
    ],
};

pub const AARCH64: Arch = Arch {
    audit: 0xc000_00b7,
    abi_bit: None,
    clone: 220,
    clone3: 435,
    socket: 198,
    numbers: &[
        ("unshare", 97),
        ("setns", 268),
        ("ptrace", 117),
        ("process_vm_readv", 270),
        ("process_vm_writev", 271),
        ("kcmp", 272),
        ("pidfd_getfd", 438),
        ("keyctl", 219),
        ("add_key", 217),
        ("request_key", 218),
        ("bpf", 280),
        ("perf_event_open", 241),
        ("userfaultfd", 282),
        ("fanotify_init", 262),
        ("mount", 40),
        ("umount2", 39),
        ("pivot_root", 41),
        ("chroot", 51),
        ("open_tree", 428),
        ("move_mount", 429),
        ("fsopen", 430),
        ("fsconfig", 431),
        ("fsmount", 432),
        ("fspick", 433),
        ("mount_setattr", 442),
        ("name_to_handle_at", 264),
        ("open_by_handle_at", 265),
        ("kexec_load", 104),
        ("kexec_file_load", 294),
        ("init_module", 105),
        ("finit_module", 273),
        ("delete_module", 106),
        ("swapon", 224),
        ("swapoff", 225),
        ("reboot", 142),
        ("acct", 89),
        ("settimeofday", 170),
        ("clock_settime", 112),
        ("clock_adjtime", 266),
        ("adjtimex", 171),
        ("syslog", 116),
        ("io_uring_setup", 425),
        ("io_uring_enter", 426),
        ("io_uring_register", 427),
    ],
};

/// The architecture siftlab was built for, if the filter knows it.
pub fn native() -> Option<&'static Arch> {
    if cfg!(target_arch = "x86_64") {
        Some(&X86_64)
    } else if cfg!(target_arch = "aarch64") {
        Some(&AARCH64)
    } else {
        None
    }
}

// Classic BPF opcodes (linux/filter.h).
const LD_W_ABS: u16 = 0x20;
const JEQ_K: u16 = 0x15;
const JGE_K: u16 = 0x35;
const JSET_K: u16 = 0x45;
const RET_K: u16 = 0x06;
/// Offsets in `struct seccomp_data`: nr, arch, args[0] (low half, little-endian).
const OFF_NR: u32 = 0;
const OFF_ARCH: u32 = 4;
const OFF_ARG0: u32 = 16;

/// The program for `arch`, as the bytes of `struct sock_filter[]` that
/// bubblewrap reads from `--seccomp FD`; with `no_sockets` (the container
/// tier, container.rs) socket(2) is denied too.
pub fn program(arch: &Arch, no_sockets: bool) -> Vec<u8> {
    // (code, jt, jf, k); jumps are counted from the next instruction.
    let mut p: Vec<(u16, u8, u8, u32)> = Vec::new();
    let mut denied: Vec<u32> = arch.numbers.iter().map(|(_, n)| *n).collect();
    if no_sockets {
        denied.push(arch.socket);
    }
    // Layout after the checks: [ALLOW] [clone: LD arg0, JSET, ALLOW] [EPERM] [ENOSYS].
    // Each jump's distance is from its own position to these labels.
    let checks = 3 + usize::from(arch.abi_bit.is_some()) + denied.len() + 2;
    let allow = checks;
    let clone_at = allow + 1;
    let eperm = clone_at + 3;
    let enosys = eperm + 1;
    let to = |from: usize, label: usize| (label - from - 1) as u8;
    p.push((LD_W_ABS, 0, 0, OFF_ARCH));
    p.push((JEQ_K, 0, to(1, eperm), arch.audit));
    p.push((LD_W_ABS, 0, 0, OFF_NR));
    if let Some(bit) = arch.abi_bit {
        let i = p.len();
        p.push((JGE_K, to(i, eperm), 0, bit));
    }
    for n in denied {
        let i = p.len();
        p.push((JEQ_K, to(i, eperm), 0, n));
    }
    let i = p.len();
    p.push((JEQ_K, to(i, enosys), 0, arch.clone3));
    let i = p.len();
    p.push((JEQ_K, to(i, clone_at), 0, arch.clone));
    debug_assert_eq!(p.len(), allow);
    p.push((RET_K, 0, 0, RET_ALLOW));
    p.push((LD_W_ABS, 0, 0, OFF_ARG0));
    // A namespace flag set: over the ALLOW to EPERM.
    p.push((JSET_K, 1, 0, CLONE_NEW));
    p.push((RET_K, 0, 0, RET_ALLOW));
    debug_assert_eq!(p.len(), eperm);
    p.push((RET_K, 0, 0, RET_ERRNO | libc::EPERM as u32));
    p.push((RET_K, 0, 0, RET_ERRNO | libc::ENOSYS as u32));
    let mut bytes = Vec::with_capacity(p.len() * 8);
    for (code, jt, jf, k) in p {
        bytes.extend_from_slice(&code.to_ne_bytes());
        bytes.push(jt);
        bytes.push(jf);
        bytes.extend_from_slice(&k.to_ne_bytes());
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_name_every_denied_call_once() {
        for arch in [&X86_64, &AARCH64] {
            let names: Vec<&str> = arch.numbers.iter().map(|(n, _)| *n).collect();
            assert_eq!(names, DENIED);
            let mut nums: Vec<u32> = arch.numbers.iter().map(|(_, n)| *n).collect();
            nums.extend([arch.clone, arch.clone3]);
            nums.sort_unstable();
            nums.dedup();
            assert_eq!(nums.len(), DENIED.len() + 2);
        }
    }

    /// The host's numbers as libc knows them: the table for this build's
    /// architecture must agree.
    #[test]
    // c_long is i64 here but i32 on 32-bit targets: the casts are for those.
    #[allow(clippy::unnecessary_cast)]
    fn the_native_table_agrees_with_libc() {
        let Some(arch) = native() else { return };
        let libc_numbers: &[(&str, libc::c_long)] = &[
            ("unshare", libc::SYS_unshare),
            ("setns", libc::SYS_setns),
            ("ptrace", libc::SYS_ptrace),
            ("keyctl", libc::SYS_keyctl),
            ("add_key", libc::SYS_add_key),
            ("request_key", libc::SYS_request_key),
            ("bpf", libc::SYS_bpf),
            ("perf_event_open", libc::SYS_perf_event_open),
            ("mount", libc::SYS_mount),
            ("umount2", libc::SYS_umount2),
            ("pivot_root", libc::SYS_pivot_root),
            ("kexec_load", libc::SYS_kexec_load),
            ("kexec_file_load", libc::SYS_kexec_file_load),
            ("init_module", libc::SYS_init_module),
            ("finit_module", libc::SYS_finit_module),
            ("delete_module", libc::SYS_delete_module),
            ("swapon", libc::SYS_swapon),
            ("swapoff", libc::SYS_swapoff),
            ("reboot", libc::SYS_reboot),
            ("process_vm_readv", libc::SYS_process_vm_readv),
            ("userfaultfd", libc::SYS_userfaultfd),
            ("open_by_handle_at", libc::SYS_open_by_handle_at),
            ("clock_settime", libc::SYS_clock_settime),
            ("io_uring_setup", libc::SYS_io_uring_setup),
            ("fsopen", libc::SYS_fsopen),
            ("mount_setattr", libc::SYS_mount_setattr),
            ("pidfd_getfd", libc::SYS_pidfd_getfd),
            ("acct", libc::SYS_acct),
            ("syslog", libc::SYS_syslog),
        ];
        for (name, n) in libc_numbers {
            let ours = arch.numbers.iter().find(|(x, _)| x == name).map(|(_, v)| i64::from(*v));
            assert_eq!(ours, Some(*n as i64), "{name}");
        }
        assert_eq!(i64::from(arch.clone), libc::SYS_clone as i64);
        assert_eq!(i64::from(arch.clone3), libc::SYS_clone3 as i64);
        assert_eq!(i64::from(arch.socket), libc::SYS_socket as i64);
    }

    #[test]
    fn every_jump_lands_inside_the_program() {
        for (arch, no_sockets) in [(&X86_64, false), (&AARCH64, false), (&X86_64, true), (&AARCH64, true)] {
            let p = program(arch, no_sockets);
            assert_eq!(p.len() % 8, 0);
            let n = p.len() / 8;
            for (i, ins) in p.chunks(8).enumerate() {
                let code = u16::from_ne_bytes([ins[0], ins[1]]);
                if code & 0x07 == 0x05 {
                    assert!(i + 1 + (ins[2] as usize) < n && i + 1 + (ins[3] as usize) < n, "jump at {i}");
                }
            }
            // The last two return EPERM and ENOSYS.
            let k = |i: usize| u32::from_ne_bytes([p[i * 8 + 4], p[i * 8 + 5], p[i * 8 + 6], p[i * 8 + 7]]);
            assert_eq!(k(n - 2), RET_ERRNO | libc::EPERM as u32);
            assert_eq!(k(n - 1), RET_ERRNO | libc::ENOSYS as u32);
            // socket(2) is compared (and so denied) only in the container tier's program.
            let compares_socket =
                (0..n).any(|i| u16::from_ne_bytes([p[i * 8], p[i * 8 + 1]]) == JEQ_K && k(i) == arch.socket);
            assert_eq!(compares_socket, no_sockets);
        }
    }
}
