//! The five-point essential-matrix kernel OpenCV 4.8's `findEssentialMat`
//! runs inside RANSAC (Bo Li's implementation of Nistér's solver,
//! docs/fidelity.md §VO-3.4): null space of the 5×9 design matrix by OpenCV's
//! Jacobi SVD (with its seeded completion), the ten cubic constraints, the
//! Gauss–Jordan elimination by the small LU inverse, the 3×13 matrix B, its
//! degree-10 determinant, Durand–Kerner roots, and back-substitution.

use super::linalg::{lu_inverse, solve_poly, svd, Mat3};

/// Exponents (x, y, z) of the 20 monomials, in the column order of OpenCV's
/// coefficient matrix: `x³, y³, x²y, xy², x²z, x², y²z, y², xyz, xy | xz², xz,
/// x, yz², yz, y, z³, z², z, 1`.
const CUBIC: [(u8, u8, u8); 20] = [
    (3, 0, 0),
    (0, 3, 0),
    (2, 1, 0),
    (1, 2, 0),
    (2, 0, 1),
    (2, 0, 0),
    (0, 2, 1),
    (0, 2, 0),
    (1, 1, 1),
    (1, 1, 0),
    (1, 0, 2),
    (1, 0, 1),
    (1, 0, 0),
    (0, 1, 2),
    (0, 1, 1),
    (0, 1, 0),
    (0, 0, 3),
    (0, 0, 2),
    (0, 0, 1),
    (0, 0, 0),
];
/// A linear form `a·x + b·y + c·z + d`.
const LIN: [(u8, u8, u8); 4] = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)];
/// Monomials of degree ≤ 2.
const QUAD: [(u8, u8, u8); 10] =
    [(2, 0, 0), (1, 1, 0), (1, 0, 1), (1, 0, 0), (0, 2, 0), (0, 1, 1), (0, 1, 0), (0, 0, 2), (0, 0, 1), (0, 0, 0)];

const fn find(table: &[(u8, u8, u8)], e: (u8, u8, u8)) -> usize {
    let mut i = 0;
    while i < table.len() {
        if table[i].0 == e.0 && table[i].1 == e.1 && table[i].2 == e.2 {
            return i;
        }
        i += 1;
    }
    usize::MAX
}

/// `t[i][j]`: where in `product` the monomial `left[i]·right[j]` stands.
const fn product_table<const A: usize, const B: usize>(
    left: &[(u8, u8, u8); A],
    right: &[(u8, u8, u8); B],
    product: &[(u8, u8, u8)],
) -> [[usize; B]; A] {
    let mut t = [[0; B]; A];
    let mut i = 0;
    while i < A {
        let mut j = 0;
        while j < B {
            let (a, b) = (left[i], right[j]);
            t[i][j] = find(product, (a.0 + b.0, a.1 + b.1, a.2 + b.2));
            j += 1;
        }
        i += 1;
    }
    t
}

const LL: [[usize; 4]; 4] = product_table(&LIN, &LIN, &QUAD);
const QL: [[usize; 4]; 10] = product_table(&QUAD, &LIN, &CUBIC);

type Lin = [f64; 4];
type Quad = [f64; 10];
type Cubic = [f64; 20];

fn mul_ll(a: &Lin, b: &Lin) -> Quad {
    let mut q = [0.0; 10];
    for i in 0..4 {
        for j in 0..4 {
            q[LL[i][j]] += a[i] * b[j];
        }
    }
    q
}

fn mul_ql(a: &Quad, b: &Lin) -> Cubic {
    let mut c = [0.0; 20];
    for i in 0..10 {
        for j in 0..4 {
            c[QL[i][j]] += a[i] * b[j];
        }
    }
    c
}

fn add_q(a: &Quad, b: &Quad) -> Quad {
    std::array::from_fn(|i| a[i] + b[i])
}

fn sub_q(a: &Quad, b: &Quad) -> Quad {
    std::array::from_fn(|i| a[i] - b[i])
}

/// The 10×20 constraint matrix for `E = x·Ea + y·Eb + z·Ec + Ed`: the nine
/// entries of `2·E·Eᵀ·E − trace(E·Eᵀ)·E` and `det E` (§VO-3.4 allows any row
/// order and scaling; this is the exact-arithmetic construction of §VO-3.8).
fn constraints(basis: &[[f64; 9]; 4]) -> [[f64; 20]; 10] {
    let e: [[Lin; 3]; 3] =
        std::array::from_fn(|r| std::array::from_fn(|c| std::array::from_fn(|k| basis[k][r * 3 + c])));
    let mut eet = [[[0.0; 10]; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let mut acc = [0.0; 10];
            for (a, b) in e[i].iter().zip(&e[j]) {
                acc = add_q(&acc, &mul_ll(a, b));
            }
            eet[i][j] = acc;
        }
    }
    let trace = add_q(&add_q(&eet[0][0], &eet[1][1]), &eet[2][2]);
    let mut m = [[0.0; 20]; 10];
    for i in 0..3 {
        for j in 0..3 {
            let mut row = [0.0; 20];
            for k in 0..3 {
                let p = mul_ql(&eet[i][k], &e[k][j]);
                for (r, v) in row.iter_mut().zip(p) {
                    *r += 2.0 * v;
                }
            }
            let t = mul_ql(&trace, &e[i][j]);
            for (r, v) in row.iter_mut().zip(t) {
                *r -= v;
            }
            m[i * 3 + j] = row;
        }
    }
    // det E by the first row.
    let minor =
        |a: usize, b: usize, c: usize, d: usize| sub_q(&mul_ll(&e[1][a], &e[2][b]), &mul_ll(&e[1][c], &e[2][d]));
    let d0 = mul_ql(&minor(1, 2, 2, 1), &e[0][0]);
    let d1 = mul_ql(&minor(0, 2, 2, 0), &e[0][1]);
    let d2 = mul_ql(&minor(0, 1, 1, 0), &e[0][2]);
    m[9] = std::array::from_fn(|k| d0[k] - d1[k] + d2[k]);
    m
}

/// Multiplies polynomials in z given by ascending coefficients.
fn pmul(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

fn psub(a: &[f64], b: &[f64]) -> Vec<f64> {
    let n = a.len().max(b.len());
    (0..n).map(|i| a.get(i).copied().unwrap_or(0.0) - b.get(i).copied().unwrap_or(0.0)).collect()
}

fn padd(a: &[f64], b: &[f64]) -> Vec<f64> {
    let n = a.len().max(b.len());
    (0..n).map(|i| a.get(i).copied().unwrap_or(0.0) + b.get(i).copied().unwrap_or(0.0)).collect()
}

/// All essential matrices consistent with five normalized correspondences
/// (`p2ᵀ·E·p1 = 0`), each with unit Frobenius norm, in OpenCV's root order.
pub fn five_point(p1: &[[f64; 2]; 5], p2: &[[f64; 2]; 5]) -> Vec<Mat3> {
    // Design matrix rows [x1x2, y1x2, x2, x1y2, y1y2, y2, x1, y1, 1].
    let mut q = [0.0; 45];
    for i in 0..5 {
        let ([x1, y1], [x2, y2]) = (p1[i], p2[i]);
        q[i * 9..i * 9 + 9].copy_from_slice(&[x1 * x2, y1 * x2, x2, x1 * y2, y1 * y2, y2, x1, y1, 1.0]);
    }
    let s = svd(&q, 5, 9, true);
    let basis: [[f64; 9]; 4] = std::array::from_fn(|k| std::array::from_fn(|c| s.vt[(5 + k) * 9 + c]));

    let m = constraints(&basis);
    let mut left = [0.0; 100];
    for r in 0..10 {
        left[r * 10..r * 10 + 10].copy_from_slice(&m[r][..10]);
    }
    let Some(inv) = lu_inverse(&left, 10) else {
        // OpenCV would continue with an all-zero inverse, which only yields
        // NaN models that no point can support; returning none is equivalent.
        return Vec::new();
    };
    // M' = inv(M[:, :10]) · M[:, 10:], a plain f64 product.
    let mut mp = [[0.0; 10]; 10];
    for r in 0..10 {
        for c in 0..10 {
            let mut acc = 0.0;
            for k in 0..10 {
                acc += inv[r * 10 + k] * m[k][10 + c];
            }
            mp[r][c] = acc;
        }
    }

    // B: three rows, columns 0..3 (x, cubic), 4..7 (y, cubic), 8..12 (1, quartic),
    // descending powers of z.
    let mut b = [[0.0; 13]; 3];
    for i in 0..3 {
        let (u, v) = (&mp[4 + 2 * i], &mp[5 + 2 * i]);
        b[i] = [
            -v[0],
            u[0] - v[1],
            u[1] - v[2],
            u[2],
            -v[3],
            u[3] - v[4],
            u[4] - v[5],
            u[5],
            -v[6],
            u[6] - v[7],
            u[7] - v[8],
            u[8] - v[9],
            u[9],
        ];
    }
    // Ascending coefficient vectors of the nine entries.
    let asc =
        |row: &[f64; 13], from: usize, len: usize| -> Vec<f64> { (0..len).map(|k| row[from + len - 1 - k]).collect() };
    let bx: Vec<Vec<f64>> = b.iter().map(|r| asc(r, 0, 4)).collect();
    let by: Vec<Vec<f64>> = b.iter().map(|r| asc(r, 4, 4)).collect();
    let bc: Vec<Vec<f64>> = b.iter().map(|r| asc(r, 8, 5)).collect();
    let det = padd(
        &psub(
            &pmul(&bx[0], &psub(&pmul(&by[1], &bc[2]), &pmul(&bc[1], &by[2]))),
            &pmul(&by[0], &psub(&pmul(&bx[1], &bc[2]), &pmul(&bc[1], &bx[2]))),
        ),
        &pmul(&bc[0], &psub(&pmul(&bx[1], &by[2]), &pmul(&by[1], &bx[2]))),
    );
    let mut coeffs = [0.0; 11];
    for (c, d) in coeffs.iter_mut().zip(&det) {
        *c = *d;
    }

    let roots = solve_poly(&coeffs, 300);
    let mut out = Vec::new();
    for root in roots {
        if root.im.abs() > 1e-10 {
            continue;
        }
        let z = root.re;
        let (z2, z3);
        z2 = z * z;
        z3 = z2 * z;
        let z4 = z3 * z;
        let mut bz = [0.0; 9];
        for j in 0..3 {
            let r = &b[j];
            bz[j * 3] = r[0] * z3 + r[1] * z2 + r[2] * z + r[3];
            bz[j * 3 + 1] = r[4] * z3 + r[5] * z2 + r[6] * z + r[7];
            bz[j * 3 + 2] = r[8] * z4 + r[9] * z3 + r[10] * z2 + r[11] * z + r[12];
        }
        let sv = svd(&bz, 3, 3, false);
        let v = [sv.vt[6], sv.vt[7], sv.vt[8]];
        if v[2].abs() < 1e-10 {
            continue;
        }
        let x = v[0] / v[2];
        let y = v[1] / v[2];
        let mut e = [0.0; 9];
        for k in 0..9 {
            e[k] = ((x * basis[0][k] + y * basis[1][k]) + z * basis[2][k]) + basis[3][k];
        }
        let mut n2 = 0.0;
        for v in e {
            n2 += v * v;
        }
        let inv_norm = 1.0 / n2.sqrt();
        out.push(std::array::from_fn(|r| std::array::from_fn(|c| e[r * 3 + c] * inv_norm)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vo::testing::{distance_up_to_scale, rodrigues};

    fn epipolar_residual(e: &Mat3, a: [f64; 2], b: [f64; 2]) -> f64 {
        let p1 = [a[0], a[1], 1.0];
        let p2 = [b[0], b[1], 1.0];
        let mut s = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                s += p2[i] * e[i][j] * p1[j];
            }
        }
        s.abs()
    }

    /// One scene of `testdata/five_point_golden.txt` and OpenCV's solutions.
    #[derive(Default)]
    struct FivePointCase {
        rvec: [f64; 3],
        t: [f64; 3],
        p1: [[f64; 2]; 5],
        p2: [[f64; 2]; 5],
        opencv: Vec<[f64; 9]>,
    }

    /// Reads the goldens (format in the file's header; the numbers are
    /// Python's shortest round-trip reprs, so they parse to the same f64s).
    fn cases() -> Vec<FivePointCase> {
        let points = |v: Vec<f64>| -> [[f64; 2]; 5] {
            assert_eq!(v.len(), 10);
            std::array::from_fn(|i| [v[2 * i], v[2 * i + 1]])
        };
        let text = include_str!("testdata/five_point_golden.txt");
        let mut cases = Vec::new();
        for paragraph in text.split("\n\n") {
            let mut case = FivePointCase::default();
            for line in paragraph.lines().filter(|l| !l.starts_with('#')) {
                let (key, numbers) = line.split_once(' ').unwrap();
                let v: Vec<f64> = numbers.split(' ').map(|x| x.parse().unwrap()).collect();
                match key {
                    "rvec" => case.rvec = v.try_into().unwrap(),
                    "t" => case.t = v.try_into().unwrap(),
                    "p1" => case.p1 = points(v),
                    "p2" => case.p2 = points(v),
                    "E" => case.opencv.push(v.try_into().unwrap()),
                    _ => panic!("unknown line {line:?}"),
                }
            }
            cases.push(case);
        }
        cases
    }

    #[test]
    fn matches_opencvs_solutions_and_finds_the_true_motion() {
        let mut worst_vs_opencv = 0f64;
        let (mut close, mut total) = (0, 0);
        let cases = cases();
        assert_eq!(cases.len(), 4);
        for (n, case) in cases.iter().enumerate() {
            let r = rodrigues(case.rvec);
            let sols = five_point(&case.p1, &case.p2);
            // Same number of solutions, same order and sign as OpenCV.
            assert_eq!(sols.len(), case.opencv.len(), "case {n}");
            for (k, (e, cv)) in sols.iter().zip(&case.opencv).enumerate() {
                let d = (0..9).map(|i| (e[i / 3][i % 3] - cv[i]).abs()).fold(0.0, f64::max);
                worst_vs_opencv = worst_vs_opencv.max(d);
                // Measured: 16 of 20 within 3e-12; the 4 others (near-double
                // roots, where Durand–Kerner is sensitive) 7e-8 .. 1.3e-6.
                assert!(d < 1e-5, "case {n} solution {k}: |E - E_cv| = {d:e}");
                if d < 1e-11 {
                    close += 1;
                }
                total += 1;
                let norm: f64 = e.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
                assert!((norm - 1.0).abs() < 1e-14);
                for i in 0..5 {
                    let res = epipolar_residual(e, case.p1[i], case.p2[i]);
                    assert!(res < 1e-10, "case {n} solution {k}: residual {res:e}");
                }
            }
            // The true E = [t]x R is one of them (case 1 is ill-conditioned:
            // OpenCV itself is 3.5e-8 away there).
            let best = sols.iter().map(|e| distance_up_to_scale(e, &r, case.t)).fold(f64::INFINITY, f64::min);
            let tol = if n == 1 { 1e-7 } else { 1e-9 };
            assert!(best < tol, "case {n}: true E not found, best distance {best:e}");
        }
        assert_eq!(total, 20);
        assert!(close >= 16, "only {close} of {total} solutions within 1e-11 of OpenCV's");
        assert!(worst_vs_opencv < 2e-6, "{worst_vs_opencv:e}");
    }
}
