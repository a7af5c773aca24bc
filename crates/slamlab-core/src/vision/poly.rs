//! Polynomials of degree at most 3 in three unknowns `x, y, z`, the arithmetic
//! the five-point solver needs to expand the essential-matrix constraints.
//!
//! Monomials are stored in graded order: `1 | x y z | x² xy xz y² yz z² | x³ x²y
//! x²z xy² xyz xz² y³ y²z yz² z³`, so a polynomial of degree d uses the first
//! `[1, 4, 10, 20][d]` coefficients.

/// Exponents `(x, y, z)` of each monomial, in storage order.
pub const MONOMIALS: [(u8, u8, u8); 20] = [
    (0, 0, 0),
    (1, 0, 0),
    (0, 1, 0),
    (0, 0, 1),
    (2, 0, 0),
    (1, 1, 0),
    (1, 0, 1),
    (0, 2, 0),
    (0, 1, 1),
    (0, 0, 2),
    (3, 0, 0),
    (2, 1, 0),
    (2, 0, 1),
    (1, 2, 0),
    (1, 1, 1),
    (1, 0, 2),
    (0, 3, 0),
    (0, 2, 1),
    (0, 1, 2),
    (0, 0, 3),
];

/// Number of monomials of degree at most d.
#[cfg(test)]
const TERMS: [usize; 4] = [1, 4, 10, 20];

/// Marks a product of degree above 3 in [`PRODUCT`].
const NONE: u8 = u8::MAX;

const fn index_of(a: u8, b: u8, c: u8) -> u8 {
    let mut i = 0;
    while i < 20 {
        let m = MONOMIALS[i];
        if m.0 == a && m.1 == b && m.2 == c {
            return i as u8;
        }
        i += 1;
    }
    NONE
}

const fn product_table() -> [[u8; 20]; 20] {
    let mut table = [[NONE; 20]; 20];
    let mut i = 0;
    while i < 20 {
        let mut j = 0;
        while j < 20 {
            let (a, b) = (MONOMIALS[i], MONOMIALS[j]);
            table[i][j] = index_of(a.0 + b.0, a.1 + b.1, a.2 + b.2);
            j += 1;
        }
        i += 1;
    }
    table
}

/// `PRODUCT[i][j]`: the index of monomial i times monomial j (or `NONE`).
pub const PRODUCT: [[u8; 20]; 20] = product_table();

/// A polynomial of degree at most 3 in `x, y, z` (the tests' reference for
/// the five-point solver's fixed-size expansion).
#[cfg(test)]
#[derive(Debug, Clone, Copy)]
pub struct Poly {
    /// Coefficients in [`MONOMIALS`] order.
    pub coefficients: [f64; 20],
    degree: usize,
}

#[cfg(test)]
impl Poly {
    /// `w + x·a + y·b + z·c`.
    pub fn linear(w: f64, a: f64, b: f64, c: f64) -> Self {
        let mut coefficients = [0.0; 20];
        coefficients[..4].copy_from_slice(&[w, a, b, c]);
        Self {
            coefficients,
            degree: 1,
        }
    }

    /// The zero polynomial of the given degree bound.
    fn zero(degree: usize) -> Self {
        Self {
            coefficients: [0.0; 20],
            degree,
        }
    }

    /// The product; terms above degree 3 never arise in the solver (degrees
    /// add to at most 3) and are dropped.
    pub fn mul(&self, other: &Poly) -> Poly {
        let mut out = Poly::zero((self.degree + other.degree).min(3));
        for i in 0..TERMS[self.degree] {
            let a = self.coefficients[i];
            if a == 0.0 {
                continue;
            }
            for j in 0..TERMS[other.degree] {
                let k = PRODUCT[i][j];
                if k != NONE {
                    out.coefficients[k as usize] += a * other.coefficients[j];
                }
            }
        }
        out
    }

    /// `self + s·other`.
    pub fn add_scaled(&self, other: &Poly, s: f64) -> Poly {
        let mut out = *self;
        out.degree = self.degree.max(other.degree);
        for i in 0..TERMS[other.degree] {
            out.coefficients[i] += s * other.coefficients[i];
        }
        out
    }

    /// The value at `(x, y, z)`.
    #[cfg(test)]
    pub fn eval(&self, x: f64, y: f64, z: f64) -> f64 {
        let mut sum = 0.0;
        for (c, &(a, b, d)) in self.coefficients.iter().zip(MONOMIALS.iter()) {
            sum += c * x.powi(a as i32) * y.powi(b as i32) * z.powi(d as i32);
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_matches_evaluation() {
        let p = Poly::linear(0.5, -1.0, 2.0, 0.25);
        let q = Poly::linear(-0.3, 0.7, 0.1, -1.2);
        let r = Poly::linear(1.1, 0.2, -0.4, 0.9);
        let cubic = p.mul(&q).mul(&r).add_scaled(&p, 3.0);
        let (x, y, z) = (0.3, -1.7, 2.2);
        let expected = p.eval(x, y, z) * q.eval(x, y, z) * r.eval(x, y, z) + 3.0 * p.eval(x, y, z);
        assert!((cubic.eval(x, y, z) - expected).abs() < 1e-12);
        assert_eq!(PRODUCT[1][4], 10); // x · x² = x³
        assert_eq!(PRODUCT[4][4], NONE); // x⁴ is out of range
    }
}
