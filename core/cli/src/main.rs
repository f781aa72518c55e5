//! `siftlab`: the lab's `run_odometry.py`, natively.

/// The CLI is native only; a wasm32 build (`wasm-pack test` builds every
/// target of the crate) gets an empty program.
#[cfg(target_arch = "wasm32")]
fn main() {}

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    in_huge_pages();
    keep_freed_memory();
    std::process::exit(siftlab_cli::main());
}

/// Tells glibc's allocator to keep freed memory for reuse instead of giving
/// it back to the kernel. By default it serves blocks above its (adaptive)
/// mmap threshold with fresh mappings and trims the top of each heap as
/// soon as 2× that threshold is free there, so `view_trajectory`'s per-frame
/// buffers (the LK pyramids and derivative images, 2 MB each) came back
/// from the kernel as new zero pages every frame: 100,000 page faults and
/// 0.8 s of system time over 99 frames. With the thresholds fixed high the
/// run takes 33,000 faults, all in its first frames; peak memory is the
/// same, as every freed block is reused by the next frame.
#[cfg(not(target_arch = "wasm32"))]
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn mallopt(param: i32, value: i32) -> i32;
        }
        // <malloc.h>: M_TRIM_THRESHOLD −1, M_TOP_PAD −2, M_MMAP_THRESHOLD −3.
        const M_TRIM_THRESHOLD: i32 = -1;
        const M_TOP_PAD: i32 = -2;
        const M_MMAP_THRESHOLD: i32 = -3;
        // SAFETY: mallopt only changes allocator tuning parameters; it is
        // called before any other thread exists. A refused value (return 0)
        // leaves glibc's default, which is also correct.
        unsafe {
            mallopt(M_MMAP_THRESHOLD, 256 << 20);
            mallopt(M_TRIM_THRESHOLD, 256 << 20);
            mallopt(M_TOP_PAD, 64 << 20);
        }
    }
}

/// Runs the program again with glibc's allocator asking the kernel for
/// transparent huge pages (`GLIBC_TUNABLES=glibc.malloc.hugetlb=1`, glibc
/// 2.35 and later), unless it already does.
///
/// A SIFT frame's planes are 7.5 MB each and its passes read many rows of
/// them at once (a blur's column pass 28 rows, an orientation histogram
/// 35): rows 10 KB apart each sit in a page of their own, so in 4 KB pages
/// nearly every row read is a TLB miss and a page walk. Kernels set to give
/// huge pages only where asked (`transparent_hugepage=madvise`, this
/// machine's and a common default) then need the allocator to ask, and only
/// glibc's own tunable asks for its heaps before their first touch; a
/// `madvise` on each large block as it is handed out came too late for the
/// page holding glibc's block header and covered half as much. With it,
/// `view_trajectory 99` holds 133 of its 141 MB in huge pages and takes
/// 3–4 % less CPU time (medians of 6 and of 8 interleaved rounds, the same
/// binary with `glibc.malloc.hugetlb=0` against it). The tunable is read
/// only at start-up, hence the `exec` (about a millisecond); if it fails,
/// the program simply goes on as it is.
#[cfg(not(target_arch = "wasm32"))]
fn in_huge_pages() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::os::unix::process::CommandExt;
        const TUNABLE: &str = "glibc.malloc.hugetlb";
        let current = std::env::var("GLIBC_TUNABLES").unwrap_or_default();
        if current.contains(TUNABLE) {
            return;
        }
        let Ok(exe) = std::env::current_exe() else { return };
        let tunables = if current.is_empty() { format!("{TUNABLE}=1") } else { format!("{current}:{TUNABLE}=1") };
        let mut args = std::env::args_os();
        let arg0 = args.next().unwrap_or_else(|| exe.clone().into_os_string());
        // Returns only if the exec failed.
        let _ = std::process::Command::new(&exe).arg0(arg0).args(args).env("GLIBC_TUNABLES", tunables).exec();
    }
}
