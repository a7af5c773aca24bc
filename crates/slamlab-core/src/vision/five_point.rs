//! The five-point algorithm for calibrated cameras (thesis `000` Eq. 4.22-4.25):
//! Nistér's solver ("An efficient solution to the five-point relative pose
//! problem", 2004).
//!
//! 1. Five matches give five rows `q` of Eq. 4.23; the essential matrix lies in
//!    the four-dimensional null space of the 5x9 matrix Q (Eq. 4.24), found by
//!    a Householder QR factorization: `E = x X + y Y + z Z + W`.
//! 2. Substituting into `det E = 0` and the cubic constraint
//!    `E Eᵀ E − ½ tr(E Eᵀ) E = 0` (Eq. 4.15-4.16) gives ten cubic equations in
//!    `x, y, z`, linear in the 20 monomials of Eq. 4.25.
//! 3. Gauss-Jordan elimination expresses ten monomials (`x³ y³ x²y xy² x²z x²
//!    y²z y² xyz xy`) through the other ten, which are `x`, `y` and `1` times
//!    powers of z. Three differences of eliminated rows, `⟨x²z⟩ − z⟨x²⟩`,
//!    `⟨y²z⟩ − z⟨y²⟩` and `⟨xyz⟩ − z⟨xy⟩`, cancel every eliminated monomial
//!    and leave `B(z) [x, y, 1]ᵀ = 0` with B a 3x3 matrix of polynomials in
//!    z of degrees 3, 3 and 4 by column ("hiding" z).
//! 4. A solution needs `det B(z) = 0`: a polynomial of degree 10 in z, whose
//!    real roots come from Sturm sequences and bisection ([`super::sturm`]);
//!    for each root, `[x, y, 1]` is the null vector of `B(z)` (a cross
//!    product of two rows).
//!
//! Up to 10 real solutions. Before 2026-11-26 the solver found them as the real
//! eigenvalues of a 10x10 action matrix (Stewénius, Engels and Nistér,
//! "Recent developments on direct relative orientation", 2006); the tests
//! keep that solver as the reference the new one must agree with.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::linear::null_space;
use super::poly::PRODUCT;
use super::sturm::{Polynomial, real_roots};

/// Minimal number of matches of the five-point algorithm.
pub const FIVE: usize = 5;

type Matrix10 = SMatrix<f64, 10, 10>;

/// Most essential matrices five matches can give.
pub const MAX_SOLUTIONS: usize = 10;

/// The up to 10 essential matrices (each with `‖E‖_F = 1`) consistent with five
/// matches in normalized image coordinates (`K⁻¹ [u, v, 1]ᵀ`, third coordinate
/// 1): `x_rᵀ E x_l = 0` for all five. Empty for a degenerate sample.
pub fn essential_five_point(
    left: &[Vector3<f64>; 5],
    right: &[Vector3<f64>; 5],
) -> Vec<Matrix3<f64>> {
    let (solutions, count) = essential_five_point_array(left, right);
    solutions[..count].to_vec()
}

/// [`essential_five_point`] without allocation, for RANSAC's loop: the
/// solutions in the first `count` entries, ordered by z.
pub fn essential_five_point_array(
    left: &[Vector3<f64>; 5],
    right: &[Vector3<f64>; 5],
) -> ([Matrix3<f64>; MAX_SOLUTIONS], usize) {
    let mut out = [Matrix3::zeros(); MAX_SOLUTIONS];
    let mut count = 0;
    let Some(basis) = null_space_basis(left, right) else {
        return (out, 0);
    };
    let Some(b) = hidden_variable_matrix(&basis) else {
        return (out, 0);
    };
    let (roots, n) = real_roots(&determinant(&b));
    let [x_basis, y_basis, z_basis, w_basis] = basis;
    for &z in &roots[..n] {
        let Some((x, y)) = null_vector_at(&b, z) else {
            continue;
        };
        let (x, y, z) = polish(&b, x, y, z);
        let e = x_basis * x + y_basis * y + z_basis * z + w_basis;
        let norm = e.norm();
        if norm > 0.0 && norm.is_finite() {
            out[count] = e / norm;
            count += 1;
        }
    }
    (out, count)
}

/// The four null-space vectors of Q (Eq. 4.22-4.24) as matrices `[X, Y, Z, W]`,
/// by Householder QR ([`null_space`]); `None` if the five rows are not
/// independent (repeated matches).
fn null_space_basis(
    left: &[Vector3<f64>; 5],
    right: &[Vector3<f64>; 5],
) -> Option<[Matrix3<f64>; 4]> {
    let rows: [[f64; 9]; FIVE] =
        std::array::from_fn(|i| super::eight_point::constraint_row(&left[i], &right[i]));
    let (null, rank) = null_space::<FIVE, 4>(&rows);
    if !(rank > 1e-12) {
        return None;
    }
    let basis = null.map(|v| Matrix3::new(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]));
    if basis.iter().any(|m| m.iter().any(|v| !v.is_finite())) {
        return None;
    }
    Some(basis)
}

/// Indices (into [`super::poly::MONOMIALS`]) of the ten monomials Gauss-Jordan
/// eliminates, in Nistér's order: `x³ y³ x²y xy² x²z x² y²z y² xyz xy`.
const ELIMINATED: [usize; 10] = [10, 16, 11, 13, 12, 4, 17, 7, 14, 5];

/// The ten that remain: `xz² xz x | yz² yz y | z³ z² z 1`, that is x, y and 1
/// times powers of z.
const KEPT: [usize; 10] = [15, 6, 1, 18, 8, 2, 19, 9, 3, 0];

/// A polynomial in z, ascending coefficients, degree at most 4.
type InZ = [f64; 5];

/// Nistér's `B(z)` (Sec. 3.2, his `⟨k⟩, ⟨l⟩, ⟨m⟩`): row i holds the
/// polynomials in z multiplying x, y and 1 in one equation
/// `bx(z) x + by(z) y + b1(z) = 0`.
///
/// After elimination, `G = C⁻¹ D` (C: the constraint matrix's columns of the
/// eliminated monomials, D: the kept ones) gives for each eliminated monomial
/// `m = −G_m · kept`. Since `x²z = z · x²`, the row `G_{x²z} − z G_{x²}`
/// applied to the kept monomials is zero: a polynomial in x, y, z without any
/// eliminated monomial. Likewise for `y²z, y²` and `xyz, xy`.
fn hidden_variable_matrix(basis: &[Matrix3<f64>; 4]) -> Option<[[InZ; 3]; 3]> {
    let a = constraint_matrix(basis);
    let c = Matrix10::from_fn(|i, j| a[(i, ELIMINATED[j])]);
    let d = Matrix10::from_fn(|i, j| a[(i, KEPT[j])]);
    // Gauss-Jordan elimination with partial pivoting (Nistér), as an LU
    // solve of C G = D.
    let g = c.lu().solve(&d)?;
    if g.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // Rows 4..9 of G: x²z, x², y²z, y², xyz, xy.
    let row = |upper: usize, lower: usize| -> [InZ; 3] {
        let e = |k: usize| g[(upper, k)];
        let f = |k: usize| g[(lower, k)];
        [
            // x (z² + z + 1 terms of e) − z (same of f): degree 3.
            [e(2), e(1) - f(2), e(0) - f(1), -f(0), 0.0],
            // y: degree 3.
            [e(5), e(4) - f(5), e(3) - f(4), -f(3), 0.0],
            // 1 (z³ z² z 1 terms): degree 4.
            [e(9), e(8) - f(9), e(7) - f(8), e(6) - f(7), -f(6)],
        ]
    };
    Some([row(4, 5), row(6, 7), row(8, 9)])
}

/// The product of two polynomials in z (degrees adding to at most 10).
fn times(a: &[f64], b: &[f64]) -> [f64; 11] {
    let mut out = [0.0; 11];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            if i + j < 11 {
                out[i + j] += x * y;
            }
        }
    }
    out
}

/// `det B(z)`, Nistér's degree-10 polynomial, by cofactors along the first
/// row (x column degree 3, y column degree 3, 1 column degree 4).
fn determinant(b: &[[InZ; 3]; 3]) -> Polynomial {
    let minor = |r: usize, s: usize, c: usize, d: usize| -> [f64; 11] {
        // b[1][r] b[2][s] − b[1][c] b[2][d]
        let p = times(&b[1][r], &b[2][s]);
        let q = times(&b[1][c], &b[2][d]);
        std::array::from_fn(|i| p[i] - q[i])
    };
    let m0 = minor(1, 2, 2, 1);
    let m1 = minor(0, 2, 2, 0);
    let m2 = minor(0, 1, 1, 0);
    let t0 = times(&b[0][0], &m0);
    let t1 = times(&b[0][1], &m1);
    let t2 = times(&b[0][2], &m2);
    let det: [f64; 11] = std::array::from_fn(|i| t0[i] - t1[i] + t2[i]);
    Polynomial::new(&det)
}

/// One Newton step on the three equations `B(z) [x, y, 1]ᵀ = 0` in the three
/// unknowns: the root z of the degree-10 polynomial and the cross product
/// each carry rounding, which this removes (Nistér's "root polishing").
fn polish(b: &[[InZ; 3]; 3], x: f64, y: f64, z: f64) -> (f64, f64, f64) {
    let at = |p: &InZ| p.iter().rev().fold(0.0, |acc, c| acc * z + c);
    let slope = |p: &InZ| {
        p.iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(0.0, |acc, (i, c)| acc * z + i as f64 * c)
    };
    let residual = Vector3::from_fn(|i, _| at(&b[i][0]) * x + at(&b[i][1]) * y + at(&b[i][2]));
    let jacobian = Matrix3::from_fn(|i, j| match j {
        0 => at(&b[i][0]),
        1 => at(&b[i][1]),
        _ => slope(&b[i][0]) * x + slope(&b[i][1]) * y + slope(&b[i][2]),
    });
    match jacobian.try_inverse() {
        Some(inverse) => {
            let step = inverse * residual;
            if step.iter().all(|v| v.is_finite()) {
                (x - step.x, y - step.y, z - step.z)
            } else {
                (x, y, z)
            }
        }
        None => (x, y, z),
    }
}

/// `(x, y)` at a root z: `[x, y, 1]` is orthogonal to every row of `B(z)`, so
/// it is the cross product of two of them (the longest of the three, for
/// accuracy), scaled to a third entry of 1. `None` if that entry vanishes.
fn null_vector_at(b: &[[InZ; 3]; 3], z: f64) -> Option<(f64, f64)> {
    let at = |p: &InZ| p.iter().rev().fold(0.0, |acc, c| acc * z + c);
    let rows: [Vector3<f64>; 3] =
        std::array::from_fn(|i| Vector3::new(at(&b[i][0]), at(&b[i][1]), at(&b[i][2])));
    let candidates = [
        rows[0].cross(&rows[1]),
        rows[0].cross(&rows[2]),
        rows[1].cross(&rows[2]),
    ];
    let v = candidates
        .iter()
        .max_by(|a, b| a.norm_squared().total_cmp(&b.norm_squared()))?;
    if !(v.z.abs() > 1e-14 * v.norm()) {
        return None;
    }
    Some((v.x / v.z, v.y / v.z))
}

/// The coefficients of a polynomial of degree 1 in `x, y, z` over the first
/// four [`super::poly::MONOMIALS`] (`1, x, y, z`).
type Linear = [f64; 4];

/// `out += s · a · b`, with `a` of degree 1 or 2 (its first 4 or 10
/// coefficients) and `b` linear; `out` holds the product's degree (10 or 20
/// coefficients). [`PRODUCT`] says where each pair of monomials lands.
fn add_product(out: &mut [f64], a: &[f64], b: &Linear, s: f64) {
    for (i, ai) in a.iter().enumerate() {
        let sa = s * ai;
        for (j, bj) in b.iter().enumerate() {
            out[PRODUCT[i][j] as usize] += sa * bj;
        }
    }
}

/// The ten cubic constraints as a 10x20 coefficient matrix over
/// [`super::poly::MONOMIALS`]: rows 0-8 the entries of `E Eᵀ E − ½ tr(E Eᵀ) E`
/// (Eq. 4.16), row 9 `det E` (Eq. 4.15), with `E = x X + y Y + z Z + W`.
fn constraint_matrix(basis: &[Matrix3<f64>; 4]) -> SMatrix<f64, 10, 20> {
    let [x, y, z, w] = basis;
    let e: [[Linear; 3]; 3] = std::array::from_fn(|r| {
        std::array::from_fn(|c| [w[(r, c)], x[(r, c)], y[(r, c)], z[(r, c)]])
    });
    // E Eᵀ (degree 2, symmetric) and its trace.
    let mut eet = [[[0.0; 10]; 3]; 3];
    for i in 0..3 {
        for j in i..3 {
            let mut q = [0.0; 10];
            for k in 0..3 {
                add_product(&mut q, &e[i][k], &e[j][k], 1.0);
            }
            eet[i][j] = q;
            eet[j][i] = q;
        }
    }
    let trace: [f64; 10] = std::array::from_fn(|m| eet[0][0][m] + eet[1][1][m] + eet[2][2][m]);
    let mut a = SMatrix::<f64, 10, 20>::zeros();
    let mut set_row = |row: usize, cubic: &[f64; 20]| {
        for (k, c) in cubic.iter().enumerate() {
            a[(row, k)] = *c;
        }
    };
    // E Eᵀ E − ½ tr(E Eᵀ) E = 0 (Eq. 4.16): nine equations.
    for i in 0..3 {
        for j in 0..3 {
            let mut cubic = [0.0; 20];
            for k in 0..3 {
                add_product(&mut cubic, &eet[i][k], &e[k][j], 1.0);
            }
            add_product(&mut cubic, &trace, &e[i][j], -0.5);
            set_row(3 * i + j, &cubic);
        }
    }
    // det E = 0 (Eq. 4.15), by cofactors along the first row.
    let minor = |p: usize, q: usize, r: usize, s: usize| {
        let mut m = [0.0; 10];
        add_product(&mut m, &e[1][p], &e[2][q], 1.0);
        add_product(&mut m, &e[1][r], &e[2][s], -1.0);
        m
    };
    let mut det = [0.0; 20];
    add_product(&mut det, &minor(1, 2, 2, 1), &e[0][0], 1.0);
    add_product(&mut det, &minor(0, 2, 2, 0), &e[0][1], -1.0);
    add_product(&mut det, &minor(0, 1, 1, 0), &e[0][2], 1.0);
    set_row(9, &det);
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The solver before 2026-11-26: the eigenvalues of Stewénius' action
    /// matrix, here as the reference for Nistér's polynomial.
    mod action_matrix_reference {
        use super::super::*;
        use crate::vision::poly::{PRODUCT, Poly};

        /// The constraint matrix expanded with the general polynomial type.
        pub(super) fn constraint_matrix_by_poly(basis: &[Matrix3<f64>; 4]) -> SMatrix<f64, 10, 20> {
            let [x, y, z, w] = basis;
            let e: [[Poly; 3]; 3] = std::array::from_fn(|r| {
                std::array::from_fn(|c| Poly::linear(w[(r, c)], x[(r, c)], y[(r, c)], z[(r, c)]))
            });
            // E Eᵀ (degree 2) and its trace.
            let eet: [[Poly; 3]; 3] = std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    e[i][0]
                        .mul(&e[j][0])
                        .add_scaled(&e[i][1].mul(&e[j][1]), 1.0)
                        .add_scaled(&e[i][2].mul(&e[j][2]), 1.0)
                })
            });
            let trace = eet[0][0]
                .add_scaled(&eet[1][1], 1.0)
                .add_scaled(&eet[2][2], 1.0);
            let mut rows: Vec<Poly> = Vec::with_capacity(10);
            // E Eᵀ E − ½ tr(E Eᵀ) E = 0 (Eq. 4.16): nine equations.
            for i in 0..3 {
                for j in 0..3 {
                    let mut p = eet[i][0].mul(&e[0][j]);
                    p = p.add_scaled(&eet[i][1].mul(&e[1][j]), 1.0);
                    p = p.add_scaled(&eet[i][2].mul(&e[2][j]), 1.0);
                    p = p.add_scaled(&trace.mul(&e[i][j]), -0.5);
                    rows.push(p);
                }
            }
            // det E = 0 (Eq. 4.15), by cofactors along the first row.
            let minor = |a: usize, b: usize, c: usize, d: usize| {
                e[1][a]
                    .mul(&e[2][b])
                    .add_scaled(&e[1][c].mul(&e[2][d]), -1.0)
            };
            let det = e[0][0]
                .mul(&minor(1, 2, 2, 1))
                .add_scaled(&e[0][1].mul(&minor(0, 2, 2, 0)), -1.0)
                .add_scaled(&e[0][2].mul(&minor(0, 1, 1, 0)), 1.0);
            rows.push(det);
            let mut a = SMatrix::<f64, 10, 20>::zeros();
            for (i, p) in rows.iter().enumerate() {
                for k in 0..20 {
                    a[(i, k)] = p.coefficients[k];
                }
            }
            a
        }

        /// The action matrix of multiplication by `x` on `b = [1, x, y, z, x², xy, xz,
        /// y², yz, z²]`: row j expresses `x · b_j` in `b`, using the eliminated
        /// constraints for the cubic monomials. `None` if the elimination is singular.
        pub(super) fn action_matrix(basis: &[Matrix3<f64>; 4]) -> Option<Matrix10> {
            let a = constraint_matrix_by_poly(basis);
            let cubic: Matrix10 = a.fixed_columns::<10>(10).into_owned();
            let lower: Matrix10 = a.fixed_columns::<10>(0).into_owned();
            // cubic · m₃ + lower · b = 0  ⇒  m₃ = −cubic⁻¹ lower · b (Gauss-Jordan).
            let reduced = -cubic.full_piv_lu().solve(&lower)?;
            let mut action = Matrix10::zeros();
            for j in 0..10 {
                let product = PRODUCT[1][j] as usize; // x · b_j
                if product < 10 {
                    action[(j, product)] = 1.0;
                } else {
                    action.set_row(j, &reduced.row(product - 10));
                }
            }
            if action.iter().any(|v| !v.is_finite()) {
                return None;
            }
            Some(action)
        }

        /// The real eigenpairs of the action matrix, read as `(x, y, z)`.
        pub(super) fn real_solutions(action: &Matrix10) -> Vec<(f64, f64, f64)> {
            let Some(schur) = nalgebra::Schur::try_new(*action, f64::EPSILON, 1000) else {
                return Vec::new();
            };
            let scale = action.amax().max(1.0);
            let mut out = Vec::with_capacity(10);
            for lambda in schur.complex_eigenvalues().iter() {
                if lambda.im.abs() > 1e-8 * (scale + lambda.re.abs()) {
                    continue;
                }
                if let Some(b) = eigenvector(action, lambda.re)
                    && b[0].abs() > 1e-12 * b.amax()
                {
                    out.push((b[1] / b[0], b[2] / b[0], b[3] / b[0]));
                }
            }
            out
        }

        /// The eigenvector of eigenvalue `lambda` by inverse iteration: a few solves
        /// with `M − (λ + δ) I`, the shift δ tiny so that the system is invertible.
        fn eigenvector(action: &Matrix10, lambda: f64) -> Option<SMatrix<f64, 10, 1>> {
            let shift = lambda + 1e-10 * (1.0 + lambda.abs());
            let shifted = action - Matrix10::identity() * shift;
            let lu = shifted.lu();
            let mut v = SMatrix::<f64, 10, 1>::from_element(1.0);
            for _ in 0..3 {
                let next = lu.solve(&v)?;
                let norm = next.norm();
                if !(norm > 0.0 && norm.is_finite()) {
                    return None;
                }
                v = next / norm;
            }
            Some(v)
        }

        /// The reference solver's essential matrices.
        pub(super) fn solve(
            left: &[Vector3<f64>; 5],
            right: &[Vector3<f64>; 5],
        ) -> Vec<Matrix3<f64>> {
            let Some(basis) = null_space_basis(left, right) else {
                return Vec::new();
            };
            let Some(action) = action_matrix(&basis) else {
                return Vec::new();
            };
            let [x_basis, y_basis, z_basis, w_basis] = basis;
            real_solutions(&action)
                .into_iter()
                .map(|(x, y, z)| {
                    let e = x_basis * x + y_basis * y + z_basis * z + w_basis;
                    e / e.norm()
                })
                .collect()
        }
    }

    fn sign_free_distance(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
        (a - b).norm().min((a + b).norm())
    }

    #[test]
    fn constraint_matrix_matches_the_general_polynomial_expansion() {
        let mut rng = ChaCha8Rng::seed_from_u64(23);
        for _ in 0..20 {
            let basis: [Matrix3<f64>; 4] =
                std::array::from_fn(|_| Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0)));
            let fast = constraint_matrix(&basis);
            let general = action_matrix_reference::constraint_matrix_by_poly(&basis);
            assert!(
                (fast - general).amax() < 1e-13,
                "{}",
                (fast - general).amax()
            );
        }
    }

    #[test]
    fn nister_polynomial_finds_the_action_matrix_solutions() {
        // Random bearings: generic samples (no noise-free geometry needed,
        // five matches always have solutions to the equations).
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let mut total = 0;
        for _ in 0..300 {
            let mut point = || {
                Vector3::new(
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-0.45..0.45),
                    1.0,
                )
            };
            let left: [Vector3<f64>; 5] = std::array::from_fn(|_| point());
            let right: [Vector3<f64>; 5] = std::array::from_fn(|_| point());
            let new = essential_five_point(&left, &right);
            let old = action_matrix_reference::solve(&left, &right);
            assert_eq!(new.len(), old.len(), "{new:?} {old:?}");
            for e in &old {
                let nearest = new
                    .iter()
                    .map(|n| sign_free_distance(n, e))
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest < 1e-6, "{nearest}");
            }
            total += new.len();
        }
        // Four real solutions a sample on average, of at most ten.
        assert!(total > 300, "{total}");
    }
}
