//! The lab's LK loop, one frame per [`Odometry::step`]: track the previous
//! frame's points with LK, findEssentialMat and recoverPose on them, the
//! lab's update, re-detection when too few points survive; and the same
//! loop as an iterator ([`Steps`]).

use super::step::{apply_motion, lab_scale, StepDetail, StepResult};
use crate::camera::Camera;
use crate::dataset::PoseRow;
use crate::sift::{detect, SiftParams};
use crate::vo::linalg::{Mat3, Vec3, IDENTITY};
use crate::vo::lk::{calc_optical_flow_pyr_lk_pyramids, LkParams, Pyramid};
use crate::vo::ransac::{find_essential_mat, EssentialResult, RansacParams};
use crate::vo::recover_pose::{recover_pose, Pose};
use crate::{Error, GrayImage, Result};

/// Returns the points the loop tracks (the lab: SIFT keypoint positions, in
/// detector order).
/// Shared by the threads of [`run`](super::run), which detect several frames at once.
pub type Detector = Box<dyn Fn(&GrayImage) -> Vec<[f32; 2]> + Send + Sync>;

/// The lab's detector: `cv2.SIFT_create(nfeatures=1500).detect(img)` positions.
pub fn sift_detector(params: SiftParams) -> Detector {
    Box::new(move |img| detect(img, &params).iter().map(|k| [k.x, k.y]).collect())
}

/// The lab's loop, one frame per [`Odometry::step`].
pub struct Odometry {
    cam: Camera,
    lk: LkParams,
    ransac: RansacParams,
    /// Re-detect when fewer points than this survive tracking (nfeatures).
    pub min_points: usize,
    pub(super) detector: Detector,
    pub(super) frame: usize,
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

    /// The loop as it stood after frame `frame`, a frame it (re-)detected on:
    /// `img` is that frame and `refs` the points detected there. Stepping on
    /// from here gives each later frame's counts and [`StepDetail`] exactly as
    /// the original run did (tracking, RANSAC and recoverPose depend only on
    /// the images and the points carried since the last detection), which is
    /// how a long run's old frames are shown without keeping their points. The
    /// pose restarts at the identity, so positions are not the run's.
    pub fn resume(
        cam: Camera,
        detector: Detector,
        frame: usize,
        img: &GrayImage,
        refs: Vec<[f32; 2]>,
        gt: Option<&PoseRow>,
    ) -> Result<Odometry> {
        let mut odo = Odometry::with_detector(cam, detector)?;
        odo.frame = frame;
        odo.check_frame(img)?;
        odo.refs = refs;
        odo.last = Some(((img.width(), img.height()), Pyramid::new(img, odo.lk.max_level)));
        odo.prev_gt = gt.copied();
        odo.frame = frame + 1;
        Ok(odo)
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
    ess: EssentialResult,
    pose: Pose,
}
