"""siftlab's `vision_tasks_base`: the lab's base class `VisionTasksBase`, for marking.

The student's `vision_tasks.py` subclasses it (`class VisionTasks(VisionTasksBase)`, usually
with `super().__init__(*params)`) and implements dt, nn, nndr and matching_info. The marker
builds `VisionTasks()` with no arguments and calls those four methods directly; what is
here is what a student's file may rely on from the base class: `self.detector` (SIFT for
1500 features), the strategy dispatch (`self.matching_algo`, `self.threshold`) and
`featureMatching` / `featureInfo`. The odometry's feature tracking (Lucas-Kanade) is not
part of the marking and is not offered.
"""

import cv2

NUM_FEATURES = 1500
MATCHING_ALGOS = ("dt", "nn", "nndr")


class VisionTasksBase:
    NUM_FEATURES = NUM_FEATURES
    MATCHING_ALGOS = MATCHING_ALGOS

    def __init__(self, *args, **kwargs):
        """Any arguments are accepted. The lab's command line passes the strategy's name and
        its threshold; when they are given they choose `matching_algo`, else it is None."""
        algo = kwargs.get("matching_algo", args[0] if args else None)
        self.threshold = kwargs.get("threshold", args[1] if len(args) > 1 else None)
        self.matching_algo = None
        if algo in MATCHING_ALGOS:
            self.matching_algo = getattr(self, algo)
        self.detector = cv2.SIFT_create(nfeatures=NUM_FEATURES)

    # the student's four methods

    def dt(self, des1, des2, threshold):
        raise NotImplementedError("VisionTasks.dt is not implemented")

    def nn(self, des1, des2, threshold=None):
        raise NotImplementedError("VisionTasks.nn is not implemented")

    def nndr(self, des1, des2, threshold):
        raise NotImplementedError("VisionTasks.nndr is not implemented")

    def matching_info(self, kp1, kp2, matches):
        raise NotImplementedError("VisionTasks.matching_info is not implemented")

    # what the lab's tools call

    def featureMatching(self, cur_image, prev_image):
        """SIFT on both frames, then the chosen strategy on (previous, current): returns
        (previous keypoints, current keypoints, the list of per-query match lists)."""
        if self.matching_algo is None:
            raise ValueError("no matching algorithm chosen (one of %s)" % ", ".join(MATCHING_ALGOS))
        prev_kp, prev_des = self.detector.detectAndCompute(prev_image, None)
        cur_kp, cur_des = self.detector.detectAndCompute(cur_image, None)
        matches = self.matching_algo(prev_des, cur_des, self.threshold)
        if type(matches) is not list:
            raise TypeError("the matching algorithm must return a list of matches, got %s"
                            % type(matches).__name__)
        return prev_kp, cur_kp, matches

    def featureInfo(self, prev_image, cur_image, feature_id):
        """matching_info of one query feature: ((x, y), [(x, y), ...], [d, ...])."""
        prev_kp, cur_kp, matches = self.featureMatching(cur_image, prev_image)
        if matches:
            info = self.matching_info(prev_kp, cur_kp, matches[feature_id])
        else:
            info = ((0, 0), [], [])
        prev_coord, cur_coords, cur_distances = info
        if type(prev_coord) is not tuple:
            raise TypeError("matching_info must return the feature's coordinates as a tuple")
        if type(cur_coords) is not list:
            raise TypeError("matching_info must return a list of the matches' coordinates")
        if type(cur_distances) is not list:
            raise TypeError("matching_info must return a list of the matches' distances")
        return prev_coord, cur_coords, cur_distances
