//! The real roots of a polynomial in one unknown of degree at most 10 by
//! Sturm sequences and bisection, as Nistér's five-point solver finds the
//! roots of its degree-10 polynomial (Nistér 2004, Sec. 3.3): no eigenvalue
//! problem, no complex arithmetic and no allocation, and only the real roots
//! (the ones that give an essential matrix) are ever computed.
//!
//! Sturm's theorem: for the chain `p₀ = p`, `p₁ = p'`, `pₖ₊₁ = -rem(pₖ₋₁, pₖ)`
//! (the negated remainder of the polynomial division) and `V(t)` the number of
//! sign changes in `p₀(t), p₁(t), …`, the number of distinct real roots of p in
//! `(a, b]` is `V(a) - V(b)`. Bisecting an interval until it holds exactly one
//! root isolates every real root; each is then polished by Newton's method,
//! kept inside its bracket by bisection steps.

/// Highest degree handled.
pub(crate) const MAX_DEGREE: usize = 10;

const TERMS: usize = MAX_DEGREE + 1;

/// Upper limit on Sturm-chain evaluations per call (isolation of roots closer
/// than this many halvings of the root bound is given up); a generic
/// degree-10 polynomial needs a few dozen.
const MAX_EVALUATIONS: usize = 400;

/// Polishing takes one last Newton step once a step is below this share of
/// the root (converging quadratically, that step leaves an error near
/// rounding).
const RELATIVE_TOLERANCE: f64 = 1e-9;

/// A polynomial `c₀ + c₁ t + … + c_d t^d` (coefficients in ascending powers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Polynomial {
    coefficients: [f64; TERMS],
    degree: usize,
}

impl Polynomial {
    /// From ascending coefficients (at most 11); the degree is that of the
    /// last non-zero coefficient.
    pub(crate) fn new(ascending: &[f64]) -> Self {
        let mut coefficients = [0.0; TERMS];
        let n = ascending.len().min(TERMS);
        coefficients[..n].copy_from_slice(&ascending[..n]);
        let degree = (0..TERMS)
            .rev()
            .find(|&i| coefficients[i] != 0.0)
            .unwrap_or(0);
        Self {
            coefficients,
            degree,
        }
    }

    /// The value at t (Horner's scheme).
    pub(crate) fn eval(&self, t: f64) -> f64 {
        self.coefficients[..=self.degree]
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * t + c)
    }

    /// The value and the derivative at t.
    fn eval_with_derivative(&self, t: f64) -> (f64, f64) {
        let mut value = 0.0;
        let mut derivative = 0.0;
        for c in self.coefficients[..=self.degree].iter().rev() {
            derivative = derivative * t + value;
            value = value * t + c;
        }
        (value, derivative)
    }

    fn derivative(&self) -> Self {
        let mut coefficients = [0.0; TERMS];
        for i in 1..=self.degree {
            coefficients[i - 1] = i as f64 * self.coefficients[i];
        }
        Self {
            coefficients,
            degree: self.degree.saturating_sub(1),
        }
    }

    /// The largest absolute coefficient.
    fn scale(&self) -> f64 {
        self.coefficients[..=self.degree]
            .iter()
            .fold(0.0f64, |m, c| m.max(c.abs()))
    }

    /// Divided by its largest absolute coefficient (a positive factor, so
    /// every sign, and with them the Sturm counts, stay the same).
    fn normalized(mut self) -> Self {
        let s = self.scale();
        if s > 0.0 {
            for c in &mut self.coefficients {
                *c /= s;
            }
        }
        self
    }

    /// `-rem(self, divisor)` for the Sturm chain, with coefficients below
    /// `1e-12` of the dividend's largest dropped (rounding of what is zero in
    /// exact arithmetic); `None` when the whole remainder is that small (the
    /// divisor is then a common factor: p has a multiple root).
    fn negated_remainder(&self, divisor: &Self) -> Option<Self> {
        let mut r = self.coefficients;
        let n = divisor.degree;
        let lead = divisor.coefficients[n];
        // Long division: cancel the leading term, from the top degree down.
        for top in (n..=self.degree).rev() {
            let q = r[top] / lead;
            for j in 0..=n {
                r[top - n + j] -= q * divisor.coefficients[j];
            }
            r[top] = 0.0;
        }
        let tiny = 1e-12 * self.scale();
        let degree = (0..n).rev().find(|&i| r[i].abs() > tiny)?;
        let mut coefficients = [0.0; TERMS];
        for i in 0..=degree {
            coefficients[i] = -r[i];
        }
        Some(Self {
            coefficients,
            degree,
        })
    }
}

/// A Sturm chain `p₀, p₁, …` (each scaled to a largest coefficient of 1).
struct SturmChain {
    polynomials: [Polynomial; TERMS],
    len: usize,
}

impl SturmChain {
    fn new(p: &Polynomial) -> Self {
        let p0 = p.normalized();
        let mut polynomials = [p0; TERMS];
        polynomials[1] = p0.derivative().normalized();
        let mut len = 2;
        while len < TERMS && polynomials[len - 1].degree > 0 {
            match polynomials[len - 2].negated_remainder(&polynomials[len - 1]) {
                Some(r) => {
                    polynomials[len] = r.normalized();
                    len += 1;
                }
                None => break,
            }
        }
        Self { polynomials, len }
    }

    /// `V(t)`: sign changes along the chain at t, zeros skipped.
    fn sign_changes(&self, t: f64) -> usize {
        let mut changes = 0;
        let mut last = 0.0f64;
        for p in &self.polynomials[..self.len] {
            let v = p.eval(t);
            if v != 0.0 {
                if last != 0.0 && (v < 0.0) != (last < 0.0) {
                    changes += 1;
                }
                last = v;
            }
        }
        changes
    }
}

/// Fujiwara's bound: every root has `|t| < 2 max_i |c_{d-i} / c_d|^{1/i}` (the
/// last term with `c₀ / 2`), tighter than Cauchy's `1 + max |cᵢ / c_d|` when
/// the coefficients differ widely in size. Each i-th root is rounded up to a
/// power of two from the ratio's binary exponent (`ratio < 2^(e+1)`, so its
/// i-th root is below `2^⌈(e+1)/i⌉`), which needs no `powf`: at most twice
/// the exact bound, and the bisection's midpoints are then exact.
fn root_bound(p: &Polynomial) -> f64 {
    let d = p.degree;
    let lead = p.coefficients[d].abs();
    let mut exponent = i32::MIN;
    for i in 1..=d {
        let mut ratio = p.coefficients[d - i].abs() / lead;
        if i == d {
            ratio /= 2.0;
        }
        if ratio > 0.0 {
            // The IEEE 754 exponent field: floor(log2(ratio)) for normal numbers.
            let e = ((ratio.to_bits() >> 52) & 0x7ff) as i32 - 1023;
            let i = i as i32;
            let ceil_div = (e + 1).div_euclid(i) + i32::from((e + 1).rem_euclid(i) != 0);
            exponent = exponent.max(ceil_div);
        }
    }
    if exponent == i32::MIN {
        // Only the leading coefficient: every root is 0.
        return f64::MIN_POSITIVE;
    }
    2.0f64.powi(exponent.saturating_add(1))
}

/// The distinct real roots of p in ascending order, in the first `count`
/// entries; none for a constant or a non-finite polynomial.
pub(crate) fn real_roots(p: &Polynomial) -> ([f64; MAX_DEGREE], usize) {
    let mut roots = [0.0; MAX_DEGREE];
    let mut count = 0;
    if p.degree == 0 || p.coefficients.iter().any(|c| !c.is_finite()) {
        return (roots, 0);
    }
    let chain = SturmChain::new(p);
    let bound = root_bound(p);
    if !bound.is_finite() {
        return (roots, 0);
    }
    // Intervals (lo, hi] with their sign changes, holding at least one root;
    // at most one per root is open at a time. Processed low half first, so
    // the roots come out ascending.
    let mut stack = [(0.0, 0.0, 0usize, 0usize); MAX_DEGREE + 1];
    stack[0] = (
        -bound,
        bound,
        chain.sign_changes(-bound),
        chain.sign_changes(bound),
    );
    let mut open = 1;
    let mut evaluations = 2;
    while open > 0 && count < MAX_DEGREE {
        open -= 1;
        let (lo, hi, v_lo, v_hi) = stack[open];
        let inside = v_lo.saturating_sub(v_hi);
        if inside == 0 {
            continue;
        }
        let mid = 0.5 * (lo + hi);
        let too_narrow = !(mid > lo && mid < hi) || evaluations >= MAX_EVALUATIONS;
        if inside == 1 || too_narrow {
            roots[count] = if inside == 1 {
                polish(p, &chain, lo, hi, v_lo)
            } else {
                // Roots closer than the arithmetic can separate: one of them.
                mid
            };
            count += 1;
            continue;
        }
        let v_mid = chain.sign_changes(mid);
        evaluations += 1;
        // Push the upper half first so the lower one is processed first.
        for interval in [(mid, hi, v_mid, v_hi), (lo, mid, v_lo, v_mid)] {
            if interval.2 > interval.3 && open < stack.len() {
                stack[open] = interval;
                open += 1;
            }
        }
    }
    (roots, count)
}

/// The one root of p in `(lo, hi]`: safeguarded Newton (Press et al.,
/// "rtsafe") while p changes sign across the bracket, else (a double root
/// touching zero) bisection on the Sturm count.
fn polish(p: &Polynomial, chain: &SturmChain, mut lo: f64, mut hi: f64, v_lo: usize) -> f64 {
    let f_lo = p.eval(lo);
    let f_hi = p.eval(hi);
    if f_hi == 0.0 {
        return hi;
    }
    if (f_lo < 0.0) == (f_hi < 0.0) {
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if !(mid > lo && mid < hi) {
                break;
            }
            if chain.sign_changes(mid) < v_lo {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        return 0.5 * (lo + hi);
    }
    let lo_negative = f_lo < 0.0;
    let mut t = 0.5 * (lo + hi);
    // The step before last: Newton's step is taken only while it at least
    // halves it, so a far start (where Newton crawls by a tenth of the
    // distance per step on a degree-10 polynomial) is bisected instead.
    let mut older_step = hi - lo;
    let mut step = older_step;
    for _ in 0..100 {
        let (f, df) = p.eval_with_derivative(t);
        if f == 0.0 {
            return t;
        }
        if (f < 0.0) == lo_negative {
            lo = t;
        } else {
            hi = t;
        }
        let newton = t - f / df;
        let next = if newton > lo && newton < hi && (2.0 * (newton - t)).abs() <= older_step.abs() {
            newton
        } else {
            0.5 * (lo + hi)
        };
        older_step = step;
        step = next - t;
        t = next;
        if !(hi - lo > 2.0 * f64::EPSILON * t.abs()) {
            break;
        }
        if step.abs() <= RELATIVE_TOLERANCE * t.abs() {
            // Close: one more Newton step squares the error.
            let (f, df) = p.eval_with_derivative(t);
            let newton = t - f / df;
            if newton >= lo && newton <= hi {
                t = newton;
            }
            break;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The product of `(t - rᵢ)` and `(t² + q)` factors, ascending.
    fn from_roots(real: &[f64], complex_q: &[f64]) -> Polynomial {
        let mut c = vec![1.0];
        let mut times = |factor: &[f64]| {
            let mut out = vec![0.0; c.len() + factor.len() - 1];
            for (i, a) in c.iter().enumerate() {
                for (j, b) in factor.iter().enumerate() {
                    out[i + j] += a * b;
                }
            }
            c = out;
        };
        for r in real {
            times(&[-r, 1.0]);
        }
        for q in complex_q {
            times(&[*q, 0.0, 1.0]);
        }
        Polynomial::new(&c)
    }

    #[test]
    fn sturm_roots_are_the_known_roots() {
        let real = [-2.0, -0.1, 0.5, 1.0, 3.0, 10.0];
        let p = from_roots(&real, &[1.0, 4.0]);
        assert_eq!(p.degree, 10);
        let (roots, count) = real_roots(&p);
        assert_eq!(count, 6);
        for (found, expected) in roots[..count].iter().zip(real) {
            assert!((found - expected).abs() < 1e-12, "{found} {expected}");
        }
        // No real root at all, and close roots that bisection must separate
        // (roots a millionth of the scale apart merge: the chain ends early).
        assert_eq!(real_roots(&from_roots(&[], &[1.0, 2.0, 3.0])).1, 0);
        let close = [0.3, 0.301, 5.0];
        let (roots, count) = real_roots(&from_roots(&close, &[1.0]));
        assert_eq!(count, 3);
        for (found, expected) in roots[..count].iter().zip(close) {
            assert!((found - expected).abs() < 1e-9, "{found} {expected}");
        }
        // Degenerate input: no roots, no panic.
        assert_eq!(real_roots(&Polynomial::new(&[3.0])).1, 0);
        assert_eq!(real_roots(&Polynomial::new(&[f64::NAN, 1.0])).1, 0);
    }

    /// The real eigenvalues of the companion matrix, the way the five-point
    /// solver found the roots before (through the action matrix's eigenvalues).
    fn companion_real_roots(p: &Polynomial) -> Vec<f64> {
        let d = p.degree;
        let mut m = SMatrix::<f64, 10, 10>::zeros();
        for i in 1..d {
            m[(i, i - 1)] = 1.0;
        }
        for i in 0..d {
            m[(i, d - 1)] = -p.coefficients[i] / p.coefficients[d];
        }
        let mut out: Vec<f64> = m
            .complex_eigenvalues()
            .iter()
            .filter(|l| l.im.abs() < 1e-8 * (1.0 + l.re.abs()))
            .map(|l| l.re)
            .collect();
        out.sort_by(f64::total_cmp);
        out
    }

    #[test]
    fn sturm_roots_match_the_companion_matrix_eigenvalues() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..500 {
            let c: Vec<f64> = (0..11).map(|_| rng.random_range(-1.0..1.0)).collect();
            let p = Polynomial::new(&c);
            let expected = companion_real_roots(&p);
            let (roots, count) = real_roots(&p);
            assert_eq!(count, expected.len(), "{c:?}");
            for (found, expected) in roots[..count].iter().zip(&expected) {
                assert!(
                    (found - expected).abs() < 1e-8 * (1.0 + expected.abs()),
                    "{found} {expected}"
                );
                assert!(p.eval(*found).abs() < 1e-10 * (1.0 + found.abs()).powi(10));
            }
        }
    }
}
