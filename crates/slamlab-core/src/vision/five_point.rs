//! The five-point algorithm for calibrated cameras (thesis `000` Eq. 4.22-4.25):
//! Nistér's problem ("An efficient solution to the five-point relative pose
//! problem", 2004) solved in Stewénius' action-matrix form (Stewénius, Engels
//! and Nistér, "Recent developments on direct relative orientation", 2006).
//!
//! 1. Five matches give five rows `q` of Eq. 4.23; the essential matrix lies in
//!    the four-dimensional null space of the 5x9 matrix Q (Eq. 4.24):
//!    `E = x X + y Y + z Z + W`.
//! 2. Substituting into `det E = 0` and the cubic constraint
//!    `E Eᵀ E − ½ tr(E Eᵀ) E = 0` (Eq. 4.15-4.16) gives ten cubic equations in
//!    `x, y, z`, linear in the 20 monomials of Eq. 4.25.
//! 3. Gauss-Jordan elimination expresses the ten cubic monomials through the
//!    ten monomials of degree at most 2, `b = [1, x, y, z, x², xy, xz, y², yz,
//!    z²]`, which span the quotient ring. Multiplying `b` by `x` then gives the
//!    10x10 action matrix `M` with `M b(s) = x(s) b(s)` at every solution s: its
//!    real eigenvalues are the solutions' `x`, its eigenvectors their `b`.
//!
//! Up to 10 real solutions; the action matrix's eigenvalues are the roots of
//! Nistér's degree-10 polynomial.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::poly::{PRODUCT, Poly};

/// Minimal number of matches of the five-point algorithm.
pub const FIVE: usize = 5;

type Matrix10 = SMatrix<f64, 10, 10>;

/// The up to 10 essential matrices (each with `‖E‖_F = 1`) consistent with five
/// matches in normalized image coordinates (`K⁻¹ [u, v, 1]ᵀ`, third coordinate
/// 1): `x_rᵀ E x_l = 0` for all five. Empty for a degenerate sample.
pub fn essential_five_point(
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
    let mut out = Vec::with_capacity(10);
    for (x, y, z) in real_solutions(&action) {
        let e = x_basis * x + y_basis * y + z_basis * z + w_basis;
        let norm = e.norm();
        if norm > 0.0 && norm.is_finite() {
            out.push(e / norm);
        }
    }
    out
}

/// The four null-space vectors of Q (Eq. 4.22-4.24) as matrices `[X, Y, Z, W]`.
fn null_space_basis(
    left: &[Vector3<f64>; 5],
    right: &[Vector3<f64>; 5],
) -> Option<[Matrix3<f64>; 4]> {
    let mut q = SMatrix::<f64, 9, 9>::zeros();
    for i in 0..FIVE {
        let row = super::eight_point::constraint_row(&left[i], &right[i]);
        for (j, v) in row.iter().enumerate() {
            q[(i, j)] = *v;
        }
    }
    let v_t = q.try_svd(false, true, f64::EPSILON, 500)?.v_t?;
    let as_matrix = |r: usize| {
        let v = v_t.row(r);
        Matrix3::new(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8])
    };
    // Rows 5..9 of Vᵀ belong to the four (zero) smallest singular values.
    let basis = [as_matrix(5), as_matrix(6), as_matrix(7), as_matrix(8)];
    if basis.iter().any(|m| m.iter().any(|v| !v.is_finite())) {
        return None;
    }
    Some(basis)
}

/// The ten cubic constraints as a 10x20 coefficient matrix over [`MONOMIALS`].
fn constraint_matrix(basis: &[Matrix3<f64>; 4]) -> SMatrix<f64, 10, 20> {
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
fn action_matrix(basis: &[Matrix3<f64>; 4]) -> Option<Matrix10> {
    let a = constraint_matrix(basis);
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
fn real_solutions(action: &Matrix10) -> Vec<(f64, f64, f64)> {
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
