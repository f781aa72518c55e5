//! What the stages pass along: OpenCV's `KeyPoint`, the result of
//! `detectAndCompute`, and a refined extremum on its way from the extremum
//! scan to the orientation histogram.

/// A keypoint with OpenCV's fields (`class_id` is always −1 and omitted).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyPoint {
    pub x: f32,
    pub y: f32,
    pub size: f32,
    pub angle: f32,
    pub response: f32,
    /// Packed as OpenCV packs it: `(xi_code << 16) | (layer << 8) | (octave & 255)`.
    pub octave: i32,
}

impl KeyPoint {
    /// The reported octave (−1 for the doubled base), as `unpackOctave` reads it.
    pub fn octave_index(&self) -> i32 {
        let o = self.octave & 255;
        if o >= 128 {
            o - 256
        } else {
            o
        }
    }

    /// The DoG layer (1..=3) within the octave.
    pub fn layer(&self) -> i32 {
        (self.octave >> 8) & 255
    }
}

/// The keypoints of an image and their descriptors, in OpenCV's order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Features {
    pub keypoints: Vec<KeyPoint>,
    /// One row per keypoint; OpenCV stores these integers 0..255 as float32.
    pub descriptors: Vec<[u8; 128]>,
}

/// A refined extremum, before orientation (docs/fidelity.md §SIFT-7): the
/// keypoint fields (angle 0) plus the octave, the integer pixel and the
/// layer the orientation histogram is centred on (§SIFT-8).
pub struct Refined {
    pub kp: KeyPoint,
    pub o: usize,
    pub layer: usize,
    pub r: usize,
    pub c: usize,
}
