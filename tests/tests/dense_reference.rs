//! The EKF-SLAM of `slamlab-core` against a dense textbook EKF-SLAM written out here.
//!
//! The core filter is written for speed: prediction touches only the robot block and
//! the robot-landmark cross terms, the Joseph-form update runs in place as rank-1
//! products over the two rows the measurement involves, and the Jacobians are closed
//! forms with the thesis's errata corrected. The reference below does none of that: it
//! builds the full-state `F` and `H`, takes every Jacobian by central differences of the
//! models themselves, and applies `P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ` with whole
//! matrices. Fed the same commands and measurements, the two must agree to the accuracy
//! of the finite differences, tick after tick, for both motion models.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use nalgebra::{DMatrix, DVector};
use slamlab_core::MotionModel;
use slamlab_core::math;
use slamlab_core::range_bearing::MIN_RANGE;
use slamlab_sim::world::landmarks::LandmarkLayout;
use slamlab_sim::{EstimatorKind, LandmarkScenario, LandmarkSession};
use std::f64::consts::PI;

fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(2.0 * PI);
    if a > PI { a - 2.0 * PI } else { a }
}

/// One motion step, written from the thesis's closed forms (Eq. 2.68 and 2.70).
fn step(model: MotionModel, x: [f64; 3], v: f64, w: f64, dt: f64) -> [f64; 3] {
    let [px, py, th] = x;
    match model {
        MotionModel::Euler => [
            px + v * dt * math::cos(th),
            py + v * dt * math::sin(th),
            th + w * dt,
        ],
        MotionModel::ExactArc if w.abs() < 1e-9 => {
            [px + v * dt * math::cos(th), py + v * dt * math::sin(th), th]
        }
        MotionModel::ExactArc => {
            let r = v / w;
            [
                px + r * (math::sin(th + w * dt) - math::sin(th)),
                py + r * (math::cos(th) - math::cos(th + w * dt)),
                th + w * dt,
            ]
        }
    }
}

/// Central difference of a vector function, angles (rows in `angle_rows`) wrapped.
fn jacobian(f: impl Fn(&[f64]) -> Vec<f64>, at: &[f64], angle_rows: &[usize]) -> DMatrix<f64> {
    const H: f64 = 1e-6;
    let rows = f(at).len();
    let mut jac = DMatrix::zeros(rows, at.len());
    for k in 0..at.len() {
        let (mut a, mut b) = (at.to_vec(), at.to_vec());
        a[k] += H;
        b[k] -= H;
        let (fa, fb) = (f(&a), f(&b));
        for i in 0..rows {
            let d = fa[i] - fb[i];
            jac[(i, k)] = if angle_rows.contains(&i) { wrap(d) } else { d } / (2.0 * H);
        }
    }
    jac
}

struct DenseEkf {
    model: MotionModel,
    mean: DVector<f64>,
    cov: DMatrix<f64>,
    ids: Vec<usize>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
}

impl DenseEkf {
    fn predict(&mut self, v: f64, w: f64, dt: f64) {
        let n = self.mean.len();
        let x = [self.mean[0], self.mean[1], self.mean[2]];
        let model = self.model;
        let fx = jacobian(
            |s| step(model, [s[0], s[1], s[2]], v, w, dt).to_vec(),
            &x,
            &[2],
        );
        let fu = jacobian(|u| step(model, x, u[0], u[1], dt).to_vec(), &[v, w], &[2]);
        // The whole-state Jacobian: identity on the landmarks.
        let mut f = DMatrix::identity(n, n);
        f.view_mut((0, 0), (3, 3)).copy_from(&fx);
        let mut g = DMatrix::zeros(n, 2);
        g.view_mut((0, 0), (3, 2)).copy_from(&fu);
        let next = step(model, x, v, w, dt);
        self.mean[0] = next[0];
        self.mean[1] = next[1];
        self.mean[2] = wrap(next[2]);
        self.cov = &f * &self.cov * f.transpose() + &g * &self.q * g.transpose();
    }

    fn update(&mut self, id: usize, z: [f64; 2]) {
        let n = self.mean.len();
        let Some(slot) = self.ids.iter().position(|&i| i == id) else {
            if z[0] < MIN_RANGE {
                return; // no distance: the landmark waits for its next sighting
            }
            // Inverse observation model l = g(x, z), its Jacobians by differences.
            let place = |x: &[f64], z: &[f64]| {
                let a = x[2] + z[1];
                vec![x[0] + z[0] * math::cos(a), x[1] + z[0] * math::sin(a)]
            };
            let robot = [self.mean[0], self.mean[1], self.mean[2]];
            let gx = jacobian(|x| place(x, &z), &robot, &[]);
            let gz = jacobian(|zz| place(&robot, zz), &z, &[]);
            let mut gfull = DMatrix::zeros(2, n);
            gfull.view_mut((0, 0), (2, 3)).copy_from(&gx);
            let p_ll = &gfull * &self.cov * gfull.transpose() + &gz * &self.r * gz.transpose();
            let p_lx = &gfull * &self.cov;
            let mut cov = DMatrix::zeros(n + 2, n + 2);
            cov.view_mut((0, 0), (n, n)).copy_from(&self.cov);
            cov.view_mut((n, 0), (2, n)).copy_from(&p_lx);
            cov.view_mut((0, n), (n, 2)).copy_from(&p_lx.transpose());
            cov.view_mut((n, n), (2, 2)).copy_from(&p_ll);
            let l = place(&robot, &z);
            self.mean = self.mean.clone().insert_rows(n, 2, 0.0);
            self.mean[n] = l[0];
            self.mean[n + 1] = l[1];
            self.cov = cov;
            self.ids.push(id);
            return;
        };
        let j = 3 + 2 * slot;
        let h = |m: &[f64]| {
            let (dx, dy) = (m[j] - m[0], m[j + 1] - m[1]);
            vec![math::hypot(dx, dy), wrap(math::atan2(dy, dx) - m[2])]
        };
        let at = self.mean.as_slice().to_vec();
        let hm = jacobian(h, &at, &[1]);
        let predicted = h(&at);
        let innovation = DVector::from_vec(vec![z[0] - predicted[0], wrap(z[1] - predicted[1])]);
        let s = &hm * &self.cov * hm.transpose() + &self.r;
        let k = &self.cov * hm.transpose() * s.try_inverse().expect("S is invertible");
        self.mean += &k * innovation;
        self.mean[2] = wrap(self.mean[2]);
        let i_kh = DMatrix::identity(n, n) - &k * &hm;
        self.cov = &i_kh * &self.cov * i_kh.transpose() + &k * &self.r * k.transpose();
    }
}

/// Runs the lesson's session and the dense reference side by side and returns the
/// largest differences seen in the mean and (relative to its size) the covariance.
fn compare(scenario: LandmarkScenario, ticks: u64) -> (f64, f64, usize) {
    let mut session = LandmarkSession::new(LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf],
        ..scenario
    });
    let config = session.scenario().filter_config();
    let start = session.scenario().start_pose();
    let dt = session.scenario().dt;
    let noise = config.noise;
    let mut dense = DenseEkf {
        model: config.motion_model,
        mean: DVector::from_vec(vec![start.x, start.y, start.theta]),
        cov: DMatrix::zeros(3, 3),
        ids: Vec::new(),
        q: DMatrix::from_diagonal(&nalgebra::dvector![
            noise.v_std * noise.v_std,
            noise.w_std * noise.w_std
        ]),
        r: DMatrix::from_diagonal(&nalgebra::dvector![
            noise.range_std * noise.range_std,
            noise.bearing_std * noise.bearing_std
        ]),
    };
    let (mut worst_mean, mut worst_cov) = (0.0_f64, 0.0_f64);
    for _ in 0..ticks {
        session.step_tick();
        let command = session.command();
        dense.predict(command.v, command.w, dt);
        for o in session.observations() {
            dense.update(o.id, [o.measurement.range, o.measurement.bearing]);
        }
        let filter = session.filters()[0].filter();
        assert_eq!(filter.landmark_ids(), dense.ids.as_slice());
        let Some(filter) = filter.gaussian() else {
            panic!("the EKF keeps a joint Gaussian");
        };
        let mut diff = filter.mean() - &dense.mean;
        diff[2] = wrap(diff[2]);
        worst_mean = worst_mean.max(diff.amax());
        let scale = dense.cov.amax().max(1.0);
        worst_cov = worst_cov.max((filter.covariance() - &dense.cov).amax() / scale);
    }
    (worst_mean, worst_cov, dense.ids.len())
}

#[test]
fn the_fast_ekf_equals_a_dense_textbook_ekf_on_the_lesson() {
    for (model, seed) in [(MotionModel::ExactArc, 1), (MotionModel::Euler, 2)] {
        let (mean, cov, landmarks) = compare(
            LandmarkScenario {
                motion: model,
                seed,
                ..LandmarkScenario::default()
            },
            200,
        );
        println!(
            "{model:?}: {landmarks} landmarks, means within {mean:.1e}, covariances {cov:.1e}"
        );
        assert!(
            landmarks >= 18,
            "{model:?}: only {landmarks} mapped in a lap"
        );
        assert!(mean < 1e-6, "{model:?}: means differ by {mean:e}");
        assert!(
            cov < 1e-6,
            "{model:?}: covariances differ by {cov:e} (relative)"
        );
    }
}

#[test]
fn the_fast_ekf_equals_a_dense_textbook_ekf_with_many_landmarks_all_around() {
    // A random world seen all around: every update involves a long state.
    let (mean, cov, landmarks) = compare(
        LandmarkScenario {
            layout: LandmarkLayout::Random,
            landmarks: 40,
            fov: 2.0 * PI,
            max_range: 6.0,
            seed: 5,
            ..LandmarkScenario::default()
        },
        120,
    );
    println!("random, 360°: {landmarks} landmarks, means within {mean:.1e}, covariances {cov:.1e}");
    assert!(landmarks >= 20, "only {landmarks} landmarks mapped");
    assert!(mean < 1e-6, "means differ by {mean:e}");
    assert!(cov < 1e-6, "covariances differ by {cov:e} (relative)");
}
