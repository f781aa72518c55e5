//! `siftlab`: the lab's `run_odometry.py`, natively.

fn main() {
    keep_freed_memory();
    std::process::exit(siftlab_core::cli::main());
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
