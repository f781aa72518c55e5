//! The lab's trajectory loop (docs/fidelity.md §VO-5) as a step API: feed frames
//! in order with their ground-truth pose, get the position after each one.
//!
//! ```text
//! frame 0:  ref = SIFT keypoint positions
//! frame i:  cur = LK(last, img, ref), keep status 1
//!           E = findEssentialMat(cur, ref); Ri, ti = recoverPose(E, cur, ref)
//!           i == 1: R, t = Ri, ti (unscaled)
//!           else:   scale = |gt_i − gt_{i−1}|; if scale > 0.1: t += scale·R·ti; R = Ri·R
//!                   if #tracked < 1500: cur = SIFT positions of img
//!           ref = cur
//! ```

use super::linalg::{mat_mul, mat_vec, Mat3, Vec3, IDENTITY};
use super::lk::{calc_optical_flow_pyr_lk_pyramids, LkParams, Pyramid};
use super::ransac::{find_essential_mat, RansacParams};
use super::recover_pose::recover_pose;
use crate::camera::Camera;
use crate::dataset::{dist3, position, PoseRow};
use crate::sift::{detect, SiftParams};
use crate::{Error, GrayImage, Result};

/// Returns the points the loop tracks (the lab: SIFT keypoint positions, in
/// detector order).
/// Shared by the threads of [`run`], which detect several frames at once.
pub type Detector = Box<dyn Fn(&GrayImage) -> Vec<[f32; 2]> + Send + Sync>;

/// The lab's detector: `cv2.SIFT_create(nfeatures=1500).detect(img)` positions.
pub fn sift_detector(params: SiftParams) -> Detector {
    Box::new(move |img| detect(img, &params).iter().map(|k| [k.x, k.y]).collect())
}

/// What one frame did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepResult {
    pub frame: usize,
    /// The position the lab draws after this frame: t for i ≥ 2, else 0.
    pub position: Vec3,
    /// Ground-truth position of this frame, if given.
    pub gt_position: Option<Vec3>,
    /// Accumulated rotation after this frame.
    pub rotation: Mat3,
    /// Points given to LK / tracked with status 1 (0 for frame 0).
    pub points_in: usize,
    pub tracked: usize,
    /// findEssentialMat inliers and RANSAC iterations, recoverPose inliers.
    pub essential_inliers: usize,
    pub ransac_iterations: usize,
    pub pose_inliers: usize,
    /// GT scale used (frames ≥ 2) and whether it passed the 0.1 test.
    pub scale: Option<f64>,
    pub updated: bool,
    /// Whether the points were re-detected (frame 0 counts as detected).
    pub redetected: bool,
    /// Points carried to the next frame.
    pub points_out: usize,
    /// The points themselves, when the loop was asked to record them
    /// ([`Odometry::record_detail`]): what the app draws on the frame.
    pub detail: Option<Box<StepDetail>>,
}

/// One frame's points, as the loop used them: each tracked (or matched)
/// point where it was in the previous frame and where it is in this one
/// (the `points2`, `points1` of findEssentialMat), whether RANSAC kept it
/// (findEssentialMat's mask) and whether recoverPose counted it (its mask:
/// in front of both cameras), and the points re-detected on this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepDetail {
    pub prev: Vec<[f32; 2]>,
    pub cur: Vec<[f32; 2]>,
    pub essential_mask: Vec<bool>,
    pub pose_mask: Vec<bool>,
    /// The detector's points on this frame when the loop re-detected (frame 0
    /// included); empty otherwise.
    pub detected: Vec<[f32; 2]>,
}

impl StepResult {
    /// Frame `frame` before anything happened: the pose so far, no counts.
    pub fn start(frame: usize, gt: Option<&PoseRow>, rotation: Mat3) -> StepResult {
        StepResult {
            frame,
            position: [0.0; 3],
            gt_position: gt.map(position),
            rotation,
            points_in: 0,
            tracked: 0,
            essential_inliers: 0,
            ransac_iterations: 0,
            pose_inliers: 0,
            scale: None,
            updated: false,
            redetected: false,
            points_out: 0,
            detail: None,
        }
    }
}

/// The lab's scale for frame `i`: `math.dist` of the true positions of frames
/// i−1 and i, from frame 2 on (frame 1 keeps recoverPose's unit translation).
pub(crate) fn lab_scale(i: usize, prev_gt: Option<&PoseRow>, gt: Option<&PoseRow>) -> Result<Option<f64>> {
    if i < 2 {
        return Ok(None);
    }
    let (Some(prev), Some(cur)) = (prev_gt, gt) else {
        return Err(Error::Odometry(format!(
            "frame {i} needs the ground-truth poses of frames {} and {i} for its scale \
             (poses/00.txt is missing lines)",
            i - 1
        )));
    };
    Ok(Some(dist3(&position(prev), &position(cur))))
}

/// The lab's update with a scale that passed its `> 0.1` test:
/// t += s·R·t_rel, then R = R_rel·R.
pub(crate) fn apply_motion(r: &mut Mat3, t: &mut Vec3, pose_r: &Mat3, pose_t: &Vec3, s: f64) {
    let rt = mat_vec(r, pose_t);
    *t = [t[0] + s * rt[0], t[1] + s * rt[1], t[2] + s * rt[2]];
    *r = mat_mul(pose_r, r);
}

/// The lab's loop, one frame per [`Odometry::step`].
pub struct Odometry {
    cam: Camera,
    lk: LkParams,
    ransac: RansacParams,
    /// Re-detect when fewer points than this survive tracking (nfeatures).
    pub min_points: usize,
    detector: Detector,
    frame: usize,
    /// Size and pyramid of the previous frame (built once, when it was the
    /// `next` image of LK).
    last: Option<((usize, usize), Pyramid)>,
    refs: Vec<[f32; 2]>,
    r: Mat3,
    t: Vec3,
    prev_gt: Option<PoseRow>,
    /// Fill [`StepResult::detail`] (off by default: a long run would keep
    /// every frame's points).
    pub record_detail: bool,
}

impl Odometry {
    /// The lab's pipeline with SIFT (nfeatures = 1500, OpenCV's SIMD width of
    /// this CPU so the keypoints equal the wheel's on the same machine).
    pub fn new(cam: Camera) -> Result<Odometry> {
        Odometry::with_detector(cam, sift_detector(SiftParams::for_host()))
    }

    /// The same loop with another point source (tests, or precomputed points).
    pub fn with_detector(cam: Camera, detector: Detector) -> Result<Odometry> {
        cam.validate()?;
        Ok(Odometry {
            cam,
            lk: LkParams::default(),
            ransac: RansacParams::default(),
            min_points: 1500,
            detector,
            frame: 0,
            last: None,
            refs: Vec::new(),
            r: IDENTITY,
            t: [0.0; 3],
            prev_gt: None,
            record_detail: false,
        })
    }

    /// Index of the frame the next `step` expects.
    pub fn next_frame(&self) -> usize {
        self.frame
    }

    pub fn camera(&self) -> &Camera {
        &self.cam
    }

    /// The current estimate (R, t) of the lab's accumulation.
    pub fn pose(&self) -> (Mat3, Vec3) {
        (self.r, self.t)
    }

    fn check_frame(&self, img: &GrayImage) -> Result<()> {
        let (w, h) = (img.width(), img.height());
        if let Some(((lw, lh), _)) = &self.last {
            if (*lw, *lh) != (w, h) {
                return Err(Error::Odometry(format!(
                    "frame {} is {w}x{h} but the previous frames are {lw}x{lh}: every frame of a \
                     sequence must have the same size",
                    self.frame
                )));
            }
        }
        if !(self.cam.cx >= 0.0 && self.cam.cx < w as f64 && self.cam.cy >= 0.0 && self.cam.cy < h as f64) {
            return Err(Error::Odometry(format!(
                "frame {} is {w}x{h}, too small for the camera (principal point ({}, {})); \
                 KITTI 00 frames are 1241x376 — use frames of the sequence the intrinsics are for",
                self.frame, self.cam.cx, self.cam.cy
            )));
        }
        if w < 2 || h < 2 {
            return Err(Error::Odometry(format!("frame {} is {w}x{h}: too small to track", self.frame)));
        }
        Ok(())
    }

    /// Processes the next frame with its ground-truth pose (needed from frame
    /// 1 on: the scale of frame i is the GT distance between i−1 and i). On
    /// error the state is unchanged, so the caller keeps what it had.
    pub fn step(&mut self, img: &GrayImage, gt: Option<&PoseRow>) -> Result<StepResult> {
        self.step_detected(img, gt, None)
    }

    /// [`Odometry::step`] with the detector's points for `img` already
    /// computed elsewhere (`detected`, used if the loop re-detects; `None`:
    /// detect here if needed).
    pub fn step_detected(
        &mut self,
        img: &GrayImage,
        gt: Option<&PoseRow>,
        mut detected: Option<Vec<[f32; 2]>>,
    ) -> Result<StepResult> {
        let i = self.frame;
        self.check_frame(img)?;
        let mut res = StepResult::start(i, gt, self.r);
        let Some(last) = &self.last else {
            let refs = match detected {
                Some(points) => points,
                None => (self.detector)(img),
            };
            res.redetected = true;
            res.points_out = refs.len();
            if self.record_detail {
                res.detail = Some(Box::new(StepDetail { detected: refs.clone(), ..StepDetail::default() }));
            }
            self.refs = refs;
            self.last = Some(((img.width(), img.height()), Pyramid::new(img, self.lk.max_level)));
            self.prev_gt = gt.copied();
            self.frame = 1;
            return Ok(res);
        };
        let scale = lab_scale(i, self.prev_gt.as_ref(), gt)?;

        let Odometry { refs: prev_refs, cam, lk, ransac, .. } = self;
        let track = || -> Result<Tracked> {
            let pyr = Pyramid::new(img, lk.max_level);
            let flow = calc_optical_flow_pyr_lk_pyramids(&last.1, &pyr, prev_refs, lk);
            let mut refs = Vec::with_capacity(prev_refs.len());
            let mut cur = Vec::with_capacity(prev_refs.len());
            for ((r, c), &ok) in prev_refs.iter().zip(&flow.next_pts).zip(&flow.status) {
                if ok {
                    refs.push(*r);
                    cur.push(*c);
                }
            }
            if cur.len() < 5 {
                return Err(Error::Odometry(format!(
                    "frame {i}: only {} of {} points could be tracked from frame {}; the motion \
                     needs at least 5 (are the frames consecutive?)",
                    cur.len(),
                    prev_refs.len(),
                    i - 1
                )));
            }
            // points1 = current frame, points2 = previous frame, as the lab calls it.
            let ess =
                find_essential_mat(&cur, &refs, cam, ransac).map_err(|e| Error::Odometry(format!("frame {i}: {e}")))?;
            let e = ess.essential().map_err(|e| Error::Odometry(format!("frame {i}: {e}")))?;
            let pose = recover_pose(e, &cur, &refs, cam).map_err(|e| Error::Odometry(format!("frame {i}: {e}")))?;
            Ok(Tracked { pyr, refs, cur, ess, pose })
        };
        // `run` detects on another thread ahead of this one; a caller of
        // `step` gets the detection below, only when the loop needs it.
        let Tracked { pyr, refs, cur, ess, pose } = track()?;
        res.points_in = self.refs.len();
        res.tracked = cur.len();
        res.essential_inliers = ess.inliers;
        res.ransac_iterations = ess.iterations;
        res.pose_inliers = pose.inliers;
        let mut detail = self.record_detail.then(|| {
            Box::new(StepDetail {
                prev: refs.clone(),
                cur: cur.clone(),
                essential_mask: ess.mask.clone(),
                pose_mask: pose.mask.clone(),
                detected: Vec::new(),
            })
        });

        let (mut r, mut t) = (self.r, self.t);
        let mut next_refs = cur;
        match scale {
            None => {
                // Frame 1: the raw unit translation, kept in every later position.
                r = pose.r;
                t = pose.t;
            }
            Some(s) => {
                res.scale = Some(s);
                if s > 0.1 {
                    apply_motion(&mut r, &mut t, &pose.r, &pose.t, s);
                    res.updated = true;
                }
                if refs.len() < self.min_points {
                    next_refs = match detected.take() {
                        Some(points) => points,
                        None => (self.detector)(img),
                    };
                    res.redetected = true;
                    if let Some(d) = &mut detail {
                        d.detected = next_refs.clone();
                    }
                }
            }
        }
        res.detail = detail;
        self.r = r;
        self.t = t;
        res.rotation = r;
        res.position = if i >= 2 { t } else { [0.0; 3] };
        res.points_out = next_refs.len();
        self.refs = next_refs;
        self.last = Some(((img.width(), img.height()), pyr));
        self.prev_gt = gt.copied();
        self.frame += 1;
        Ok(res)
    }
}

/// The loop as an iterator: one [`StepResult`] per frame the source yields
/// (frame image and its ground-truth pose). Stops being useful after the
/// first error, which it reports as an item.
pub struct Steps<'a, I> {
    odo: &'a mut Odometry,
    frames: I,
}

impl<I: Iterator<Item = Result<(GrayImage, Option<PoseRow>)>>> Iterator for Steps<'_, I> {
    type Item = Result<StepResult>;

    fn next(&mut self) -> Option<Self::Item> {
        let frame = self.frames.next()?;
        Some(frame.and_then(|(img, gt)| self.odo.step(&img, gt.as_ref())))
    }
}

impl Odometry {
    /// Iterates the loop over `frames` (e.g. decoded files of a picked folder).
    pub fn steps<I>(&mut self, frames: I) -> Steps<'_, I::IntoIter>
    where
        I: IntoIterator<Item = Result<(GrayImage, Option<PoseRow>)>>,
    {
        Steps { odo: self, frames: frames.into_iter() }
    }
}

/// What tracking one frame produced.
struct Tracked {
    pyr: Pyramid,
    refs: Vec<[f32; 2]>,
    cur: Vec<[f32; 2]>,
    ess: super::ransac::EssentialResult,
    pose: super::recover_pose::Pose,
}

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
fn run_with_workers(
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

/// A KITTI pose line for (R, t): `R00 R01 R02 t0 R10 ... t2`.
pub fn pose_row(r: &Mat3, t: &Vec3) -> PoseRow {
    [r[0][0], r[0][1], r[0][2], t[0], r[1][0], r[1][1], r[1][2], t[1], r[2][0], r[2][1], r[2][2], t[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A textured "road" image seen by a camera displaced by `dz` forward:
    /// a pure zoom about the principal point of a far plane approximates it.
    fn frame(w: usize, h: usize, zoom: f64, cam: &Camera) -> GrayImage {
        let mut d = vec![0u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let u = (x as f64 - cam.cx) / zoom;
                let v = (y as f64 - cam.cy) / zoom;
                let val = 128.0
                    + 45.0 * (u * 0.11 + v * 0.05).sin()
                    + 40.0 * (v * 0.13 - u * 0.07).sin()
                    + 30.0 * (u * 0.031).cos() * (v * 0.027).sin();
                d[y * w + x] = val.round().clamp(0.0, 255.0) as u8;
            }
        }
        GrayImage::new(w, h, d).unwrap()
    }

    fn grid(img: &GrayImage) -> Vec<[f32; 2]> {
        let mut p = Vec::new();
        for y in (20..img.height() - 20).step_by(12) {
            for x in (20..img.width() - 20).step_by(12) {
                p.push([x as f32 + 0.5, y as f32 + 0.5]);
            }
        }
        p
    }

    fn gt(z: f64) -> PoseRow {
        [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, z]
    }

    #[test]
    fn loop_follows_the_lab_rules() {
        let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
        let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
        odo.min_points = 10_000;
        let r0 = odo.step(&frame(320, 240, 1.0, &cam), Some(&gt(0.0))).unwrap();
        assert!(r0.redetected && r0.points_out > 300);
        assert_eq!(r0.position, [0.0; 3]);
        let r1 = odo.step(&frame(320, 240, 1.02, &cam), Some(&gt(1.0))).unwrap();
        // Frame 1: position drawn as 0, never re-detects.
        assert_eq!(r1.position, [0.0; 3]);
        assert!(!r1.redetected && r1.scale.is_none());
        assert!(r1.tracked > 250, "{}", r1.tracked);
        // Frame 2 with a GT step of 0.05 (≤ 0.1): no update, but re-detection.
        let before = odo.pose();
        let r2 = odo.step(&frame(320, 240, 1.04, &cam), Some(&gt(1.05))).unwrap();
        assert_eq!(r2.scale, Some(0.050000000000000044));
        assert!(!r2.updated && r2.redetected);
        assert_eq!(odo.pose(), before);
        assert_eq!(r2.position, before.1);
        // Frame 3 with a GT step of 2: t += 2·R·ti.
        let r3 = odo.step(&frame(320, 240, 1.06, &cam), Some(&gt(3.05))).unwrap();
        assert!(r3.updated);
        let moved: f64 = (0..3).map(|k| (r3.position[k] - r2.position[k]).powi(2)).sum::<f64>().sqrt();
        assert!((moved - 2.0).abs() < 1e-9, "moved {moved}");
    }

    /// The recorded points are the ones the counts count, and recording
    /// changes nothing else.
    #[test]
    fn detail_matches_the_counts() {
        let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
        let (mut plain, mut rec) = (
            Odometry::with_detector(cam, Box::new(grid)).unwrap(),
            Odometry::with_detector(cam, Box::new(grid)).unwrap(),
        );
        plain.min_points = 10_000;
        rec.min_points = 10_000;
        rec.record_detail = true;
        for k in 0..4 {
            let img = frame(320, 240, 1.0 + 0.02 * k as f64, &cam);
            let a = plain.step(&img, Some(&gt(k as f64))).unwrap();
            let mut b = rec.step(&img, Some(&gt(k as f64))).unwrap();
            let d = b.detail.take().expect("recorded");
            assert_eq!(a, b, "frame {k}");
            let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
            assert_eq!((d.prev.len(), d.cur.len()), (a.tracked, a.tracked));
            assert_eq!(count(&d.essential_mask), a.essential_inliers);
            assert_eq!(count(&d.pose_mask), a.pose_inliers);
            assert_eq!(d.detected.len(), if a.redetected { a.points_out } else { 0 });
            assert!(
                d.pose_mask.iter().zip(&d.essential_mask).all(|(&p, &e)| !p || e),
                "recoverPose counts RANSAC inliers only"
            );
        }
    }

    #[test]
    fn iterator_yields_one_result_per_frame() {
        let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
        let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
        let frames = (0..4).map(|k| Ok((frame(320, 240, 1.0 + 0.02 * k as f64, &cam), Some(gt(k as f64)))));
        let out: Vec<StepResult> = odo.steps(frames).collect::<Result<_>>().unwrap();
        assert_eq!(out.iter().map(|r| r.frame).collect::<Vec<_>>(), vec![0, 1, 2, 3]);
        assert_eq!(out[3].scale, Some(1.0));
        assert!(out[2].updated && out[3].updated);
        assert_eq!(odo.next_frame(), 4);
    }

    #[test]
    fn errors_leave_the_state_unchanged() {
        let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
        let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
        odo.step(&frame(320, 240, 1.0, &cam), Some(&gt(0.0))).unwrap();
        let e = odo.step(&frame(300, 240, 1.0, &cam), Some(&gt(1.0))).unwrap_err();
        assert!(e.to_string().contains("frame 1 is 300x240 but the previous frames are 320x240"), "{e}");
        assert_eq!(odo.next_frame(), 1);
        odo.step(&frame(320, 240, 1.02, &cam), Some(&gt(1.0))).unwrap();
        let e = odo.step(&frame(320, 240, 1.04, &cam), None).unwrap_err();
        assert!(e.to_string().contains("frame 2 needs the ground-truth poses"), "{e}");
        assert_eq!(odo.next_frame(), 2);
        // KITTI intrinsics on a small frame.
        let mut kitti = Odometry::with_detector(Camera::default(), Box::new(grid)).unwrap();
        let e = kitti.step(&frame(320, 240, 1.0, &cam), None).unwrap_err();
        assert!(e.to_string().contains("too small for the camera"), "{e}");
    }

    /// `run`'s pipeline (detection ahead on another thread) gives exactly
    /// what stepping frame by frame gives, keeps the detector, and stops at
    /// a frame that cannot be read with the earlier results kept in `odo`.
    #[test]
    fn pipelined_run_equals_stepping() {
        let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
        let poses: Vec<PoseRow> = (0..6).map(|k| gt(0.7 * k as f64)).collect();
        let img = |k: usize| frame(320, 240, 1.0 + 0.015 * k as f64, &cam);
        let mut stepped = Odometry::with_detector(cam, Box::new(grid)).unwrap();
        stepped.min_points = 10_000;
        let want: Vec<StepResult> = (0..6).map(|k| stepped.step(&img(k), Some(&poses[k])).unwrap()).collect();
        // One detection thread, two (this machine's usual) and three: each
        // takes every n-th frame, and the results come back in frame order.
        for workers in 1..=3 {
            let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
            odo.min_points = 10_000;
            let mut seen = Vec::new();
            let got =
                run_with_workers(&mut odo, 6, &poses, |k| Ok(img(k)), &mut |d, n| seen.push((d, n)), workers).unwrap();
            assert_eq!(got, want, "{workers} workers");
            assert!(got[2..].iter().all(|r| r.redetected));
            assert_eq!(seen, (1..=6).map(|d| (d, 6)).collect::<Vec<_>>());
            assert_eq!(odo.pose(), stepped.pose());
            // The detector is back in place: a further step detects with it.
            let r = odo.step(&img(6), Some(&gt(4.9))).unwrap();
            assert!(r.redetected && r.points_out > 300);

            // A frame that cannot be read stops the run with its error, on
            // whichever worker it lands, after the frames before it.
            for broken in [1, 3, 4] {
                let mut failing = Odometry::with_detector(cam, Box::new(grid)).unwrap();
                let load = |k: usize| {
                    if k == broken {
                        Err(Error::Odometry(format!("frame {k} is broken")))
                    } else {
                        Ok(img(k))
                    }
                };
                let e = run_with_workers(&mut failing, 6, &poses, load, &mut |_, _| {}, workers).unwrap_err();
                assert!(e.to_string().contains(&format!("frame {broken} is broken")), "{e}");
                assert_eq!(failing.next_frame(), broken, "{workers} workers");
            }
        }
    }
}
