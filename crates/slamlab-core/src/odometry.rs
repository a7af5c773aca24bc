//! The odometry motion model, sampling form: Probabilistic Robotics Table 5.6
//! (`sample_motion_model_odometry`), in two variants ([`OdometryModel`]):
//!
//! - [`OdometryModel::DiffCorrected`] (the default): the noise terms below are
//!   *variances*, as in Table 5.6. This is ROS 1 amcl's `diff-corrected`
//!   (`ODOM_MODEL_DIFF_CORRECTED`) and Nav2's `DifferentialMotionModel`.
//! - [`OdometryModel::Diff`]: ROS 1 amcl's `diff` (`ODOM_MODEL_DIFF`, its
//!   default `odom_model_type`), which passes the same sums to
//!   `pf_ran_gaussian` as *standard deviations*: `σ = α1 δrot1² + α2 δtrans²`.
//!   amcl kept it for backwards compatibility; for motions under a metre it is
//!   far tighter than the variance form with the same alphas (`0.2 x 0.2²` =
//!   0.008 m against `sqrt(0.2 x 0.2²)` = 0.089 m for 0.2 m of travel).
//!
//! Both share the rest of amcl's rules described below.
//!
//! The motion between two odometry poses is split into a rotation `δrot1`
//! towards the direction of travel, a translation `δtrans` and a second rotation
//! `δrot2`. Each is perturbed by zero-mean Gaussian noise whose *variance* is
//!
//! - `δrot1`: `α1 δrot1² + α2 δtrans²`
//! - `δtrans`: `α3 δtrans² + α4 (δrot1² + δrot2²)`
//! - `δrot2`: `α1 δrot2² + α2 δtrans²`
//!
//! (amcl's `odom_alpha1..4`: rotation from rotation, rotation from translation,
//! translation from translation, translation from rotation). As in amcl, a
//! translation below 1 cm has `δrot1 = 0` (the heading of a tiny displacement is
//! noise), and the rotation noise uses the smaller of `|δrot|` and `|δrot − π|`,
//! so driving backwards is not mistaken for a half turn.

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Which form of the odometry model's noise (amcl `odom_model_type`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OdometryModel {
    /// Variances `α1 δrot1² + α2 δtrans²` … (Probabilistic Robotics Table 5.6;
    /// amcl `diff-corrected`; Nav2).
    #[default]
    DiffCorrected,
    /// Standard deviations `α1 δrot1² + α2 δtrans²` … (ROS 1 amcl `diff`).
    Diff,
}

impl OdometryModel {
    /// amcl's name: `diff-corrected` or `diff`.
    pub fn name(self) -> &'static str {
        match self {
            OdometryModel::DiffCorrected => "diff-corrected",
            OdometryModel::Diff => "diff",
        }
    }
}

/// The four noise parameters of the odometry model (amcl `odom_alpha1..4`;
/// defaults 0.2 as in ROS 1 amcl).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryNoise {
    /// Rotation noise from rotation.
    pub alpha1: f64,
    /// Rotation noise from translation.
    pub alpha2: f64,
    /// Translation noise from translation.
    pub alpha3: f64,
    /// Translation noise from rotation.
    pub alpha4: f64,
}

impl Default for OdometryNoise {
    fn default() -> Self {
        Self {
            alpha1: 0.2,
            alpha2: 0.2,
            alpha3: 0.2,
            alpha4: 0.2,
        }
    }
}

impl OdometryNoise {
    /// The same noise with every alpha made finite and non-negative (NaN and
    /// negative values become 0).
    pub fn sanitized(self) -> Self {
        let f = |a: f64| if a > 0.0 && a.is_finite() { a } else { 0.0 };
        Self {
            alpha1: f(self.alpha1),
            alpha2: f(self.alpha2),
            alpha3: f(self.alpha3),
            alpha4: f(self.alpha4),
        }
    }
}

/// The odometry increment between two odometry poses, decomposed as
/// `(δrot1, δtrans, δrot2)` (Probabilistic Robotics Table 5.6, lines 2-4; amcl's
/// 1 cm rule for `δrot1`).
pub fn odometry_increment(previous: Pose2, current: Pose2) -> (f64, f64, f64) {
    let dx = current.x - previous.x;
    let dy = current.y - previous.y;
    let trans = math::hypot(dx, dy);
    let rot1 = if trans < 0.01 {
        0.0
    } else {
        wrap_angle(math::atan2(dy, dx) - previous.theta)
    };
    let rot2 = wrap_angle(current.theta - previous.theta - rot1);
    (rot1, trans, rot2)
}

/// `min(|δ|, |δ − π|)` with both wrapped: the rotation that the noise scales with
/// (amcl), so that reversing is not a half turn.
fn rotation_for_noise(rot: f64) -> f64 {
    wrap_angle(rot).abs().min(wrap_angle(rot - PI).abs())
}

/// Draws a successor of `pose` for the odometry motion from `odom_previous` to
/// `odom_current` (Probabilistic Robotics Table 5.6; amcl `ODOM_MODEL_DIFF`).
pub fn sample_motion_model_odometry<R: Rng + ?Sized>(
    pose: Pose2,
    odom_previous: Pose2,
    odom_current: Pose2,
    noise: &OdometryNoise,
    rng: &mut R,
) -> Pose2 {
    let (rot1, trans, rot2) = odometry_increment(odom_previous, odom_current);
    sample_increment(pose, rot1, trans, rot2, noise, rng)
}

/// [`sample_motion_model_odometry`] for an increment already decomposed by
/// [`odometry_increment`] (a filter moving many particles decomposes once).
#[inline]
pub fn sample_increment<R: Rng + ?Sized>(
    pose: Pose2,
    rot1: f64,
    trans: f64,
    rot2: f64,
    noise: &OdometryNoise,
    rng: &mut R,
) -> Pose2 {
    sample_increment_with(
        OdometryModel::DiffCorrected,
        pose,
        rot1,
        trans,
        rot2,
        noise,
        rng,
    )
}

/// [`sample_increment`] with the noise form `model`: the sums are variances
/// (`diff-corrected`) or standard deviations (ROS 1 amcl `diff`).
#[inline]
pub fn sample_increment_with<R: Rng + ?Sized>(
    model: OdometryModel,
    pose: Pose2,
    rot1: f64,
    trans: f64,
    rot2: f64,
    noise: &OdometryNoise,
    rng: &mut R,
) -> Pose2 {
    let r1 = rotation_for_noise(rot1);
    let r2 = rotation_for_noise(rot2);
    let t2 = trans * trans;
    let v_rot1 = noise.alpha1 * r1 * r1 + noise.alpha2 * t2;
    let v_trans = noise.alpha3 * t2 + noise.alpha4 * (r1 * r1 + r2 * r2);
    let v_rot2 = noise.alpha1 * r2 * r2 + noise.alpha2 * t2;
    let (sd_rot1, sd_trans, sd_rot2) = match model {
        OdometryModel::DiffCorrected => (v_rot1.sqrt(), v_trans.sqrt(), v_rot2.sqrt()),
        OdometryModel::Diff => (v_rot1, v_trans, v_rot2),
    };
    let n1: f64 = crate::random::standard_normal(rng);
    let n2: f64 = crate::random::standard_normal(rng);
    let n3: f64 = crate::random::standard_normal(rng);
    let rot1_hat = rot1 - sd_rot1 * n1;
    let trans_hat = trans - sd_trans * n2;
    let rot2_hat = rot2 - sd_rot2 * n3;
    let (s, c) = math::sin_cos(pose.theta + rot1_hat);
    Pose2::new(
        pose.x + trans_hat * c,
        pose.y + trans_hat * s,
        pose.theta + rot1_hat + rot2_hat,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn moments(samples: &[[f64; 3]]) -> ([f64; 3], [[f64; 3]; 3]) {
        let n = samples.len() as f64;
        let mut mean = [0.0; 3];
        for s in samples {
            for k in 0..3 {
                mean[k] += s[k] / n;
            }
        }
        let mut cov = [[0.0; 3]; 3];
        for s in samples {
            for a in 0..3 {
                for b in 0..3 {
                    cov[a][b] += (s[a] - mean[a]) * (s[b] - mean[b]) / (n - 1.0);
                }
            }
        }
        (mean, cov)
    }

    #[test]
    fn straight_motion_has_the_analytic_mean_and_covariance() {
        // Forward by d from the origin: δrot1 = δrot2 = 0, so
        // r1 ~ N(0, s²), t ~ N(d, a3 d²), r2 ~ N(0, s²) with s² = α2 d², and
        // x = t cos r1, y = t sin r1, θ = r1 + r2. With E[cos r1] = e^{-s²/2},
        // E[sin² r1] = (1 − e^{-2s²})/2, E[r1 sin r1] = s² e^{-s²/2}:
        let noise = OdometryNoise {
            alpha1: 0.3,
            alpha2: 0.05,
            alpha3: 0.04,
            alpha4: 0.1,
        };
        let d = 1.0;
        let s2 = noise.alpha2 * d * d;
        let t_var = noise.alpha3 * d * d;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let samples: Vec<[f64; 3]> = (0..200_000)
            .map(|_| {
                let p = sample_motion_model_odometry(
                    Pose2::IDENTITY,
                    Pose2::new(3.0, 1.0, 0.5),
                    Pose2::new(3.0 + d * math::cos(0.5), 1.0 + d * math::sin(0.5), 0.5),
                    &noise,
                    &mut rng,
                );
                [p.x, p.y, p.theta]
            })
            .collect();
        let (mean, cov) = moments(&samples);
        let e_cos = math::exp(-s2 / 2.0);
        let e_t2 = d * d + t_var;
        let mean_x = d * e_cos;
        let var_x = e_t2 * (1.0 + math::exp(-2.0 * s2)) / 2.0 - mean_x * mean_x;
        let var_y = e_t2 * (1.0 - math::exp(-2.0 * s2)) / 2.0;
        let cov_y_theta = d * s2 * e_cos;
        let var_theta = 2.0 * s2;
        // Standard errors with 200,000 samples are below 1e-3 for every entry.
        let tol = 3e-3;
        assert!((mean[0] - mean_x).abs() < tol, "{mean:?}");
        assert!(mean[1].abs() < tol && mean[2].abs() < tol, "{mean:?}");
        assert!((cov[0][0] - var_x).abs() < tol, "{} vs {var_x}", cov[0][0]);
        assert!((cov[1][1] - var_y).abs() < tol, "{} vs {var_y}", cov[1][1]);
        assert!(
            (cov[2][2] - var_theta).abs() < tol,
            "{} vs {var_theta}",
            cov[2][2]
        );
        assert!(
            (cov[1][2] - cov_y_theta).abs() < tol,
            "{} vs {cov_y_theta}",
            cov[1][2]
        );
        assert!(cov[0][1].abs() < tol && cov[0][2].abs() < tol, "{cov:?}");
    }

    #[test]
    fn amcl_diff_uses_the_sums_as_standard_deviations() {
        // Forward d = 0.5 m. Translation noise alone (α3 = 0.2): diff-corrected
        // draws δtrans with variance α3 d² (sd 0.2236 m), ROS 1 amcl's diff with
        // standard deviation α3 d² (0.05 m). Rotation noise alone (α2 = 0.05):
        // δrot1 and δrot2 each with sd sqrt(α2 d²) = 0.1118 or α2 d² = 0.0125,
        // so θ with sd √2 times that.
        let d: f64 = 0.5;
        let translation = OdometryNoise {
            alpha1: 0.0,
            alpha2: 0.0,
            alpha3: 0.2,
            alpha4: 0.0,
        };
        let rotation = OdometryNoise {
            alpha2: 0.05,
            alpha3: 0.0,
            ..translation
        };
        let sd = |model: OdometryModel, noise: &OdometryNoise, pick: fn(Pose2) -> f64| {
            let mut rng = ChaCha8Rng::seed_from_u64(11);
            let n = 40_000;
            let v: Vec<f64> = (0..n)
                .map(|_| {
                    pick(sample_increment_with(
                        model,
                        Pose2::IDENTITY,
                        0.0,
                        d,
                        0.0,
                        noise,
                        &mut rng,
                    ))
                })
                .collect();
            let mean = v.iter().sum::<f64>() / n as f64;
            (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
        };
        let sqrt2 = std::f64::consts::SQRT_2;
        for (model, sd_t, sd_theta) in [
            (
                OdometryModel::DiffCorrected,
                (0.2 * d * d).sqrt(),
                sqrt2 * (0.05 * d * d).sqrt(),
            ),
            (OdometryModel::Diff, 0.2 * d * d, sqrt2 * 0.05 * d * d),
        ] {
            // Relative standard error of a sample sd with 40,000 draws: 0.35%.
            let t = sd(model, &translation, |p| p.x);
            assert!((t / sd_t - 1.0).abs() < 0.02, "{model:?}: {t} vs {sd_t}");
            let r = sd(model, &rotation, |p| p.theta);
            assert!(
                (r / sd_theta - 1.0).abs() < 0.02,
                "{model:?}: {r} vs {sd_theta}"
            );
        }
        assert_eq!(OdometryModel::default().name(), "diff-corrected");
    }

    #[test]
    fn rotation_in_place_and_reversing() {
        // A pure rotation by φ (no translation): θ ~ N(φ, α1 φ²), position fixed
        // except for the α4 translation noise, variance α4 φ².
        let noise = OdometryNoise {
            alpha1: 0.1,
            alpha2: 0.0,
            alpha3: 0.0,
            alpha4: 0.02,
        };
        let phi = 1.2;
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let samples: Vec<[f64; 3]> = (0..100_000)
            .map(|_| {
                let p = sample_motion_model_odometry(
                    Pose2::new(1.0, 2.0, 0.0),
                    Pose2::IDENTITY,
                    Pose2::new(0.0, 0.0, phi),
                    &noise,
                    &mut rng,
                );
                [p.x, p.y, p.theta]
            })
            .collect();
        let (mean, cov) = moments(&samples);
        assert!((mean[2] - phi).abs() < 2e-3, "{mean:?}");
        assert!(
            (cov[2][2] - noise.alpha1 * phi * phi).abs() < 2e-3,
            "{cov:?}"
        );
        assert!(
            (cov[0][0] - noise.alpha4 * phi * phi).abs() < 1e-3,
            "{cov:?}"
        );
        // Backwards by 1 m: δrot1 = π but its noise is computed from 0.
        let (rot1, trans, rot2) = odometry_increment(Pose2::IDENTITY, Pose2::new(-1.0, 0.0, 0.0));
        assert!((rot1.abs() - PI).abs() < 1e-12 && (trans - 1.0).abs() < 1e-12);
        assert!((rot2.abs() - PI).abs() < 1e-12);
        assert!(rotation_for_noise(rot1) < 1e-12);
        let quiet = OdometryNoise {
            alpha1: 1.0,
            alpha2: 0.0,
            alpha3: 0.0,
            alpha4: 0.0,
        };
        let p = sample_motion_model_odometry(
            Pose2::IDENTITY,
            Pose2::IDENTITY,
            Pose2::new(-1.0, 0.0, 0.0),
            &quiet,
            &mut rng,
        );
        assert!(
            (p.x + 1.0).abs() < 1e-9 && p.y.abs() < 1e-9 && p.theta.abs() < 1e-9,
            "{p:?}"
        );
    }
}
