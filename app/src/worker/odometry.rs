//! A tracking worker's job: the lab's `view_trajectory` loop (or the loop
//! driven by a strategy's matches), one frame per request, in frame order.

use crate::platform::now_ms;
use crate::protocol::odometry::{StepCounts, Tracker, VoReply, VoRequest};
use siftlab_core::vo::Camera;
use siftlab_core::GrayImage;

/// Handles one request of the worker's odometry run, posting its steps, its
/// metrics and its end, or why it failed (which ends the run).
pub fn handle(req: VoRequest, post: &dyn Fn(VoReply)) {
    match req {
        VoRequest::Start { id, total, poses, camera, tracker } => {
            let started = VoSession::start(id, total as usize, &poses, camera).and_then(|v| match tracker {
                Tracker::Lk => Ok(v),
                Tracker::Matched(s) => v.with_matcher(s),
            });
            let failed = started.as_ref().err().cloned();
            SESSION.with(|s| *s.borrow_mut() = started.ok());
            if let Some(message) = failed {
                post(VoReply::Failed { id, message });
            }
        }
        VoRequest::Frame { id, frame, bytes, points } => {
            on_session(id, post, |session| session.frame(frame as usize, Input::Image(&bytes, points), post))
        }
        VoRequest::Features { id, frame, features } => {
            on_session(id, post, |session| session.frame(frame as usize, Input::Features(features), post))
        }
        VoRequest::Replay { token, from, frame, frames, refs, detected, features } => {
            let detail = SESSION.with(|s| match s.borrow().as_ref() {
                Some(session) => session.replay(from as usize, frame as usize, &frames, refs, detected, features),
                None => {
                    Err("the run is over (it was stopped or failed): run the odometry again to see this frame".into())
                }
            });
            post(VoReply::Replayed { token, frame, detail })
        }
    }
}

/// Runs `f` on the worker's odometry session `id`; an error ends the session.
fn on_session(id: u32, post: &dyn Fn(VoReply), f: impl FnOnce(&mut VoSession) -> Result<(), String>) {
    let r = SESSION.with(|s| match s.borrow_mut().as_mut() {
        Some(session) if session.id == id => f(session),
        _ => Err("no odometry run is going on (it was stopped or failed)".into()),
    });
    if let Err(message) = r {
        SESSION.with(|s| *s.borrow_mut() = None);
        post(VoReply::Failed { id, message });
    }
}

/// What a tracking worker gets for its next frame: the image (and the
/// keypoints a SIFT worker found in it, if any), or a matcher-driven run's
/// SIFT features.
enum Input<'a> {
    Image(&'a [u8], Option<Vec<[f32; 2]>>),
    Features(siftlab_core::sift::Features),
}

thread_local! {
    /// The odometry run this worker tracks for, between `VoFrame` messages.
    static SESSION: std::cell::RefCell<Option<VoSession>> = const { std::cell::RefCell::new(None) };
}

/// The lab's `view_trajectory` loop, a frame at a time: the odometry state,
/// the ground truth and the positions so far.
struct VoSession {
    id: u32,
    total: usize,
    poses: Vec<siftlab_core::dataset::PoseRow>,
    /// The sequence's camera (its calib.txt, or the lab's 00 camera).
    camera: Camera,
    odo: siftlab_core::vo::Odometry,
    /// Set for a run driven by the student's matcher (`odo` then unused).
    matched: Option<siftlab_core::vo::MatchedOdometry>,
    /// The poses so far, scored after the last frame.
    record: siftlab_core::vo::Record,
    t0: f64,
}

impl VoSession {
    /// Checks the poses before any frame is read, as the CLI does.
    fn start(id: u32, total: usize, poses: &str, camera: Camera) -> Result<Self, String> {
        use siftlab_core::dataset::parse_poses_in;
        use siftlab_core::vo::Odometry;
        let t0 = now_ms();
        let poses = parse_poses_in(poses, "the poses file").map_err(|e| e.to_string())?;
        siftlab_core::dataset::check_pose_count("the poses file", poses.len(), total).map_err(|e| e.to_string())?;
        let mut odo = Odometry::new(camera).map_err(|e| e.to_string())?;
        // The page draws each frame's points (the odometry's own view).
        odo.record_detail = true;
        Ok(VoSession { id, total, poses, camera, odo, matched: None, record: siftlab_core::vo::Record::default(), t0 })
    }

    /// The same session tracking with `strategy`'s matches instead of LK.
    fn with_matcher(mut self, strategy: siftlab_core::matching::Strategy) -> Result<Self, String> {
        use siftlab_core::vo::MatchedOdometry;
        let mut m = MatchedOdometry::new(self.camera, strategy).map_err(|e| e.to_string())?;
        m.record_detail = true;
        self.matched = Some(m);
        Ok(self)
    }

    /// What the run did with frame `frame`, recomputed from frame `from` (see
    /// [`VoRequest::Replay`]) without touching the run: the core's `resume`
    /// gives the same points and masks as the run's own step.
    fn replay(
        &self,
        from: usize,
        frame: usize,
        frames: &[Vec<u8>],
        refs: Vec<[f32; 2]>,
        detected: Option<Vec<[f32; 2]>>,
        mut features: Vec<siftlab_core::sift::Features>,
    ) -> Result<Option<Box<siftlab_core::vo::StepDetail>>, String> {
        use siftlab_core::vo::{sift_detector, MatchedOdometry, Odometry, StepDetail};
        if frame >= self.record.len() || from > frame {
            return Err(format!("frame {frame} is not among the run's frames so far"));
        }
        let gt = |i: usize| self.poses.get(i);
        let e = |e: siftlab_core::Error| e.to_string();
        if let Some(m) = &self.matched {
            if frame == 0 {
                return Ok(None);
            }
            let (Some(cur), Some(prev)) = (features.pop(), features.pop()) else {
                return Err("a matched run's frame is replayed from two frames' features".into());
            };
            let mut odo =
                MatchedOdometry::resume(self.camera, *m.strategy(), frame - 1, prev, gt(frame - 1)).map_err(e)?;
            odo.record_detail = true;
            return Ok(odo.step_features(cur, gt(frame)).map_err(e)?.detail);
        }
        if frames.len() != frame - from + 1 {
            return Err(format!("frames {from} … {frame} are {} files, not {}", frames.len(), frame - from + 1));
        }
        let decode = |k: usize| GrayImage::decode(&frames[k]).map_err(|e| format!("frame {}: {e}", from + k));
        if frame == from {
            return Ok(Some(Box::new(StepDetail { detected: refs, ..StepDetail::default() })));
        }
        // Re-detection between `from` and `frame` does not happen (`from` is the
        // last detection); at `frame` it uses the points the page sent.
        let detector = sift_detector(siftlab_core::sift::SiftParams::for_host());
        let mut odo = Odometry::resume(self.camera, detector, from, &decode(0)?, refs, gt(from)).map_err(e)?;
        let last = frames.len() - 1;
        for k in 1..last {
            odo.step(&decode(k)?, gt(from + k)).map_err(e)?;
        }
        odo.record_detail = true;
        Ok(odo.step_detected(&decode(last)?, gt(frame), detected).map_err(e)?.detail)
    }

    /// Frame `i` (the next one): one step, posted; after the last, the
    /// trajectory error and the lab's window as PNG. `points`: the frame's
    /// keypoints if detected elsewhere (else detected here when the loop
    /// re-detects).
    fn frame(&mut self, i: usize, input: Input, post: &dyn Fn(VoReply)) -> Result<(), String> {
        use siftlab_core::dataset::position;
        use siftlab_core::render::{encode_png, trajectory_window, TrajectoryStyle};
        if i != self.record.len() || i >= self.total {
            return Err(format!("frame {i} arrived out of order (expected frame {})", self.record.len()));
        }
        let decode = |bytes: &[u8]| GrayImage::decode(bytes).map_err(|e| format!("frame {i}: {e}"));
        let gt = self.poses.get(i);
        let step = match (self.matched.as_mut(), input) {
            (Some(m), Input::Features(f)) => m.step_features(f, gt),
            (Some(m), Input::Image(bytes, _)) => m.step(&decode(bytes)?, gt),
            (None, Input::Image(bytes, points)) => self.odo.step_detected(&decode(bytes)?, gt, points),
            (None, Input::Features(_)) => {
                return Err(format!("frame {i}: the Lucas–Kanade loop needs the image, not only its features"))
            }
        }
        .map_err(|e| e.to_string())?;
        let mut step = step;
        let detail = step.detail.take();
        self.record.push(&step);
        let gt = step.gt_position.or_else(|| self.poses.get(i).map(position));
        post(VoReply::Step {
            id: self.id,
            frame: i as u32,
            total: self.total as u32,
            position: step.position,
            truth: gt,
            counts: StepCounts::of(&step),
            detail,
        });
        if i + 1 == self.total {
            let end = self.record.finish(&self.poses).map_err(|e| e.to_string())?;
            let window = trajectory_window(&end.truth, &self.record.positions(), &TrajectoryStyle::default());
            let png = encode_png(&window).map_err(|e| e.to_string())?;
            post(VoReply::Metrics { id: self.id, metrics: end.metrics.to_array() });
            let kitti = siftlab_core::vo::kitti_text(self.record.poses());
            post(VoReply::Done { id: self.id, ate: end.ate, png, ms: now_ms() - self.t0, kitti });
        }
        Ok(())
    }
}
