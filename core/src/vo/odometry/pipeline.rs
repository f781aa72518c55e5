//! A whole run of the LK loop over frames `0..n` ([`run`]): one thread reads
//! the frames, detection threads find each frame's points ahead, this thread
//! tracks frame after frame; on wasm32 the frames one by one.

use super::step::StepResult;
#[cfg(not(target_arch = "wasm32"))]
use super::tracker::Detector;
use super::tracker::Odometry;
use crate::dataset::PoseRow;
#[cfg(not(target_arch = "wasm32"))]
use crate::Error;
use crate::{GrayImage, Result};

/// Runs the loop over frames `0..n`, loading each with `load(i)`; `progress`
/// gets (done, total) after every frame. Returns the per-frame results.
pub fn run(
    odo: &mut Odometry,
    n: usize,
    poses: &[PoseRow],
    load: impl FnMut(usize) -> Result<GrayImage> + Send,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<StepResult>> {
    run_with_workers(odo, n, poses, load, progress, crate::par::cores().clamp(1, 4))
}

/// [`run`] with `workers` detection threads natively (ignored on wasm32).
pub(super) fn run_with_workers(
    odo: &mut Odometry,
    n: usize,
    poses: &[PoseRow],
    mut load: impl FnMut(usize) -> Result<GrayImage> + Send,
    progress: &mut dyn FnMut(usize, usize),
    workers: usize,
) -> Result<Vec<StepResult>> {
    let mut out = Vec::with_capacity(n);
    #[cfg(not(target_arch = "wasm32"))]
    {
        // A pipeline: one thread reads and decodes the frames; `workers`
        // threads detect the keypoints of frames ahead, frame i on worker
        // i % workers, each on its share of the cores (`par::with_threads`:
        // one core each on a 2-core machine); this thread tracks frame after
        // frame, taking the workers' results in frame order.
        // Detection needs only the image, so running it ahead changes no
        // result. A whole frame per core beats sharing every stage of one
        // frame between the cores: no hand-over per stage, and each frame's
        // planes stay in its own core's cache.
        let first = odo.frame;
        let detector: Detector = std::mem::replace(&mut odo.detector, Box::new(|_| Vec::new()));
        let workers = workers.max(1);
        // The cores shared out: one each on this 2-core machine.
        let per_worker = (crate::par::cores() / workers).max(1);
        let detector_ref = &detector;
        let result = std::thread::scope(|s| -> Result<()> {
            let mut to_workers = Vec::with_capacity(workers);
            let mut from_workers = Vec::with_capacity(workers);
            for _ in 0..workers {
                let (tx_img, rx_img) = std::sync::mpsc::sync_channel::<(usize, Result<GrayImage>)>(1);
                let (tx_det, rx_det) = std::sync::mpsc::sync_channel(1);
                to_workers.push(tx_img);
                from_workers.push(rx_det);
                s.spawn(move || {
                    for (i, frame) in rx_img {
                        // Frame 1 never re-detects (§VO-5: it only sets R, t).
                        let item = frame.map(|img| {
                            let points =
                                (first + i != 1).then(|| crate::par::with_threads(per_worker, || detector_ref(&img)));
                            (img, points)
                        });
                        let failed = item.is_err();
                        if tx_det.send(item).is_err() || failed {
                            break;
                        }
                    }
                });
            }
            s.spawn(move || {
                for i in 0..n {
                    let frame = load(i);
                    let failed = frame.is_err();
                    if to_workers[i % workers].send((i, frame)).is_err() || failed {
                        break;
                    }
                }
            });
            let track = || -> Result<()> {
                for i in 0..n {
                    let (img, points) = from_workers[i % workers]
                        .recv()
                        .map_err(|_| Error::Odometry(format!("frame {i} could not be read")))??;
                    out.push(odo.step_detected(&img, poses.get(i), points)?);
                    progress(i + 1, n);
                }
                Ok(())
            };
            let tracked = crate::par::with_threads(per_worker, track);
            // Unblock and stop the other stages (a worker blocked on a send
            // sees its receiver gone; the reader then sees the workers gone).
            drop(from_workers);
            tracked
        });
        odo.detector = detector;
        result?;
    }
    #[cfg(target_arch = "wasm32")]
    let _ = workers;
    #[cfg(target_arch = "wasm32")]
    for i in 0..n {
        let img = load(i)?;
        out.push(odo.step(&img, poses.get(i))?);
        progress(i + 1, n);
    }
    Ok(out)
}
