//! `cv2.SIFT_create`'s parameters (docs/fidelity.md §SIFT-1) and OpenCV's
//! SIMD width (§SIFT-13).

/// `cv2.SIFT_create` parameters. `opencv_lanes` is the SIMD width OpenCV's
/// dispatched SIFT kernels ran with on the reference machine (8 on AVX2, 16
/// on AVX-512 CPUs, docs/fidelity.md §SIFT-13); it changes angles and descriptors at the ulp
/// level only.
#[derive(Clone, Debug, PartialEq)]
pub struct SiftParams {
    pub nfeatures: usize,
    pub n_octave_layers: usize,
    pub contrast_threshold: f64,
    pub edge_threshold: f64,
    pub sigma: f64,
    pub opencv_lanes: usize,
}

impl Default for SiftParams {
    /// The lab's `cv2.SIFT_create(nfeatures=1500)` as run on an AVX2 CPU.
    fn default() -> Self {
        SiftParams {
            nfeatures: 1500,
            n_octave_layers: 3,
            contrast_threshold: 0.04,
            edge_threshold: 10.0,
            sigma: 1.6,
            opencv_lanes: 8,
        }
    }
}

impl SiftParams {
    /// The lab's parameters with OpenCV's SIMD width as it would be on the
    /// CPU this runs on, so results equal OpenCV's on the same machine.
    pub fn for_host() -> Self {
        SiftParams { opencv_lanes: host_opencv_lanes(), ..Self::default() }
    }
}

/// OpenCV 4.8 dispatches its SIFT kernels to AVX512_SKX when the CPU has
/// AVX-512 F, CD, BW, DQ and VL, else to AVX2.
pub fn host_opencv_lanes() -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512cd")
            && std::is_x86_feature_detected!("avx512bw")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx512vl")
        {
            return 16;
        }
    }
    8
}
