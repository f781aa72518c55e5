//! Data parallelism without a thread-pool dependency: scoped std threads
//! natively, plain loops on wasm32 (no threads there). Every parallel
//! stage writes results that do not depend on the split, as in OpenCV.

#[cfg(not(target_arch = "wasm32"))]
std::thread_local! {
    /// Set by [`with_threads`]: the most threads this thread's stages use
    /// (0: no limit but the cores).
    static LIMIT: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Runs `f` with every parallel stage it reaches using at most `n` threads
/// (the calling one included; at least 1). For callers that already keep the
/// cores busy with whole jobs of their own (the odometry detects several
/// frames at once): one frame per core needs no thread start-up or hand-over
/// per stage, and each frame's planes stay in its core's cache.
pub fn with_threads<R>(n: usize, f: impl FnOnce() -> R) -> R {
    #[cfg(not(target_arch = "wasm32"))]
    {
        struct Restore(usize);
        impl Drop for Restore {
            fn drop(&mut self) {
                LIMIT.with(|s| s.set(self.0));
            }
        }
        let _restore = Restore(LIMIT.with(|s| s.replace(n.max(1))));
        f()
    }
    #[cfg(target_arch = "wasm32")]
    {
        let _ = n;
        f()
    }
}

/// [`with_threads`] with one thread: every stage on the calling thread.
pub fn serial<R>(f: impl FnOnce() -> R) -> R {
    with_threads(1, f)
}

/// Number of cores this process may use (1 on wasm32).
pub fn cores() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    {
        // Asked once: on Linux `available_parallelism` reads the affinity
        // mask and three cgroup files on every call, and the parallel stages
        // ask about 50 times a frame (4,809 calls, 14,525 files opened in a
        // 99-frame `view_trajectory`; asking once cut its CPU time by 5.5 %,
        // median of 6 interleaved rounds).
        static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
        *CORES.get_or_init(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1).min(8))
    }
    #[cfg(target_arch = "wasm32")]
    {
        1
    }
}

/// Number of worker threads to use for one stage.
pub fn threads() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    {
        match LIMIT.with(|s| s.get()) {
            0 => cores(),
            n => n.min(cores()),
        }
    }
    #[cfg(target_arch = "wasm32")]
    {
        1
    }
}

/// Fills `out` (split into contiguous chunks of `chunk_len` multiples of
/// `unit` elements) by calling `f(first_unit_index, chunk)` on each chunk.
pub fn for_each_chunk<T: Send>(out: &mut [T], unit: usize, f: impl Fn(usize, &mut [T]) + Sync) {
    let units = out.len().checked_div(unit).unwrap_or(0);
    let n = threads().min(units.max(1));
    // Thread start-up costs more than small planes (the top octaves) take.
    if n <= 1 || units < 2 || std::mem::size_of_val(out) < 256 * 1024 {
        f(0, out);
        return;
    }
    let per = units.div_ceil(n);
    let chunk = per * unit;
    #[cfg(not(target_arch = "wasm32"))]
    std::thread::scope(|s| {
        for (i, a) in out.chunks_mut(chunk).enumerate() {
            let f = &f;
            s.spawn(move || f(i * per, a));
        }
    });
    #[cfg(target_arch = "wasm32")]
    for (i, a) in out.chunks_mut(chunk).enumerate() {
        f(i * per, a);
    }
}

/// Calls `f(first_index, chunk)` on the `chunk_len`-element chunks of `out`,
/// handing them to the threads one at a time: for work whose cost varies a
/// lot between chunks (a descriptor's cost grows with its keypoint's size),
/// where [`for_each_chunk`]'s equal split would leave a thread idle.
pub fn for_each_chunk_dynamic<T: Send>(out: &mut [T], chunk_len: usize, f: impl Fn(usize, &mut [T]) + Sync) {
    let chunk_len = chunk_len.max(1);
    let n = threads().min(out.len().div_ceil(chunk_len));
    if n <= 1 {
        f(0, out);
        return;
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        let queue = std::sync::Mutex::new(out.chunks_mut(chunk_len).enumerate());
        std::thread::scope(|s| {
            for _ in 0..n {
                s.spawn(|| loop {
                    // A poisoned lock means another worker panicked; stop taking work.
                    let next = match queue.lock() {
                        Ok(mut q) => q.next(),
                        Err(_) => None,
                    };
                    let Some((i, chunk)) = next else { break };
                    f(i * chunk_len, chunk);
                });
            }
        });
    }
    #[cfg(target_arch = "wasm32")]
    f(0, out);
}

/// Runs `f(job, out)` over the jobs, taken one at a time by the threads
/// (on scoped threads natively, in order on the calling thread otherwise);
/// each thread appends to its own vector, and these are concatenated into
/// `out` in thread order: for results whose order does not matter (SIFT's
/// keypoints: docs/fidelity.md §SIFT-10 sorts everything).
pub fn collect_jobs<J: Sync, T: Send>(jobs: &[J], f: impl Fn(&J, &mut Vec<T>) + Sync, out: &mut Vec<T>) {
    #[cfg(not(target_arch = "wasm32"))]
    {
        // The cap of `with_threads`: an odometry detection worker,
        // one frame per core, scans on its own thread (before, each scan
        // started threads for every core, four busy threads on two cores).
        let threads = threads().min(jobs.len());
        if threads > 1 {
            let next = std::sync::atomic::AtomicUsize::new(0);
            let parts: Vec<Vec<T>> = std::thread::scope(|s| {
                let handles: Vec<_> = (0..threads)
                    .map(|_| {
                        s.spawn(|| {
                            let mut local = Vec::new();
                            loop {
                                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                                let Some(job) = jobs.get(i) else { break };
                                f(job, &mut local);
                            }
                            local
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap_or_default()).collect()
            });
            for p in parts {
                out.extend(p);
            }
            return;
        }
    }
    for j in jobs {
        f(j, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_runs_every_stage_on_the_calling_thread_and_then_restores() {
        let cores = cores();
        assert_eq!(threads(), cores);
        let caller = std::thread::current().id();
        let (inner, nested, ids) = serial(|| {
            let nested = serial(threads);
            // The stage's chunks all run here (a 1 MB plane is split when not serial).
            let mut plane = vec![0u32; 256 * 1024];
            let ids = std::sync::Mutex::new(Vec::new());
            for_each_chunk(&mut plane, 1024, |_, _| ids.lock().unwrap().push(std::thread::current().id()));
            (threads(), nested, ids.into_inner().unwrap())
        });
        assert_eq!((inner, nested), (1, 1));
        assert_eq!(ids, vec![caller]);
        assert_eq!(threads(), cores, "restored after serial");
        assert_eq!(with_threads(2, || (threads(), serial(threads), threads())), (2.min(cores), 1, 2.min(cores)));
        // Restored on unwinding too.
        let _ = std::panic::catch_unwind(|| serial(|| panic!("stage failed")));
        assert_eq!(threads(), cores);
    }
}
