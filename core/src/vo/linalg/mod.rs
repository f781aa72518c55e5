//! The small numeric routines OpenCV's five-point solver, RANSAC and
//! recoverPose run through (docs/fidelity.md §VO-3.3 to §VO-3.7), one module
//! each: `rng` (`cv::RNG`), `svd` (the one-sided Jacobi SVD with its seeded
//! null-space completion, and four 4×4 SVDs in vector lanes), `lu` (the small
//! LU inverse), `poly` (Durand–Kerner `solvePoly`), and `mat3` (the 3×3
//! helpers of the pose arithmetic). All of them live in OpenCV files compiled
//! for the baseline ISA, so every operation here is a plain f64 operation
//! (no FMA).

mod hypot;
mod lu;
mod mat3;
mod poly;
mod svd;

pub use crate::rng::CvRng;
pub use hypot::hypot;
pub use lu::lu_inverse;
pub use mat3::{det3, mat_mul, mat_vec, skew, transpose, Mat3, Vec3, IDENTITY};
pub use poly::solve_poly;
#[cfg(test)]
pub use svd::null_vector_4x4;
pub use svd::{null_vectors_4x4, svd};
