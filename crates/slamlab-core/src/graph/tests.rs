//! Tests of the pose graph: Jacobians against central differences, a noise-free
//! graph solved exactly, LM's monotone cost, gauge errors, patterns, covariances.

use super::edge::*;
use super::*;
use crate::geometry::{Pose2, wrap_angle};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use std::f64::consts::PI;

const H: f64 = 1e-6;

/// Central difference of `f` with respect to coordinate `k` of `x`, with the
/// angle difference wrapped.
fn central(f: &dyn Fn(&[f64]) -> Vec<f64>, x: &[f64], k: usize, angle_rows: &[usize]) -> Vec<f64> {
    let mut p = x.to_vec();
    let mut m = x.to_vec();
    p[k] += H;
    m[k] -= H;
    let (fp, fm) = (f(&p), f(&m));
    fp.iter()
        .zip(&fm)
        .enumerate()
        .map(|(r, (a, b))| {
            let d = if angle_rows.contains(&r) {
                wrap_angle(a - b)
            } else {
                a - b
            };
            d / (2.0 * H)
        })
        .collect()
}

fn check(
    name: &str,
    analytic: &[Vec<f64>],
    f: &dyn Fn(&[f64]) -> Vec<f64>,
    x: &[f64],
    angles: &[usize],
) {
    for (k, col) in analytic.iter().enumerate() {
        let numeric = central(f, x, k, angles);
        for (r, (a, n)) in col.iter().zip(&numeric).enumerate() {
            assert!(
                (a - n).abs() < 1e-6 * (1.0 + n.abs()),
                "{name}: d e[{r}] / d x[{k}] analytic {a} numeric {n} at {x:?}"
            );
        }
    }
}

fn pose(v: &[f64]) -> Pose2 {
    // No wrapping here: the difference quotient must see the raw perturbation.
    Pose2 {
        x: v[0],
        y: v[1],
        theta: v[2],
    }
}

/// Headings near ±π (where the angle wraps) and ordinary ones.
fn headings() -> [f64; 5] {
    [0.3, PI - 1e-4, -PI + 1e-4, PI, -2.0]
}

#[test]
fn pose_pose_jacobians_match_central_differences_near_and_away_from_pi() {
    for &ti in &headings() {
        for &tz in &[0.1, PI - 2e-4, -PI + 3e-4] {
            let z = Pose2::new(0.7, -0.4, tz);
            let xi = [1.0, 2.0, ti];
            let xj = [1.9, 1.1, wrap_angle(ti + tz + 0.05)];
            let x: Vec<f64> = xi.iter().chain(&xj).copied().collect();
            let f = |v: &[f64]| -> Vec<f64> {
                pose_pose_error(&pose(&v[0..3]), &pose(&v[3..6]), &z)
                    .iter()
                    .copied()
                    .collect()
            };
            let (a, b) = pose_pose_jacobians(&pose(&xi), &pose(&xj), &z);
            let cols: Vec<Vec<f64>> = (0..3)
                .map(|c| a.column(c).iter().copied().collect())
                .chain((0..3).map(|c| b.column(c).iter().copied().collect()))
                .collect();
            check("pose-pose", &cols, &f, &x, &[2]);
        }
    }
}

#[test]
fn pose_point_and_range_bearing_jacobians_match_central_differences() {
    for &ti in &headings() {
        let xi = [0.5, -1.0, ti];
        let l = [3.0, 1.5];
        let x: Vec<f64> = xi.iter().chain(&l).copied().collect();
        let z = Vector2::new(1.0, 2.0);
        let f = |v: &[f64]| -> Vec<f64> {
            pose_point_error(&pose(&v[0..3]), &Vector2::new(v[3], v[4]), &z)
                .iter()
                .copied()
                .collect()
        };
        let (a, b) = pose_point_jacobians(&pose(&xi), &Vector2::new(l[0], l[1]));
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|c| a.column(c).iter().copied().collect())
            .chain((0..2).map(|c| b.column(c).iter().copied().collect()))
            .collect();
        check("pose-point", &cols, &f, &x, &[]);

        // A bearing measurement near ±π so the error wraps.
        let (range, bearing) = (3.0, PI - 1e-3);
        let g = |v: &[f64]| -> Vec<f64> {
            range_bearing_error(&pose(&v[0..3]), &Vector2::new(v[3], v[4]), range, bearing)
                .iter()
                .copied()
                .collect()
        };
        let (a, b) = range_bearing_jacobians(&pose(&xi), &Vector2::new(l[0], l[1]));
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|c| a.column(c).iter().copied().collect())
            .chain((0..2).map(|c| b.column(c).iter().copied().collect()))
            .collect();
        check("range-bearing", &cols, &g, &x, &[1]);
    }
}

#[test]
fn prior_errors_have_identity_jacobians() {
    for &t in &headings() {
        let z = Pose2::new(1.0, 2.0, PI - 1e-4);
        let x = [1.2, 1.9, t];
        let f =
            |v: &[f64]| -> Vec<f64> { pose_prior_error(&pose(v), &z).iter().copied().collect() };
        let id: Vec<Vec<f64>> = (0..3)
            .map(|c| (0..3).map(|r| if r == c { 1.0 } else { 0.0 }).collect())
            .collect();
        check("pose prior", &id, &f, &x, &[2]);
    }
    let z = Vector2::new(1.0, -1.0);
    let f = |v: &[f64]| -> Vec<f64> {
        point_prior_error(&Vector2::new(v[0], v[1]), &z)
            .iter()
            .copied()
            .collect()
    };
    check(
        "point prior",
        &[vec![1.0, 0.0], vec![0.0, 1.0]],
        &f,
        &[0.3, 0.4],
        &[],
    );
}

#[test]
fn pose_pose_error_is_zero_at_the_true_relative_pose_across_pi() {
    let xi = Pose2::new(1.0, 2.0, PI - 0.1);
    let xj = Pose2::new(-1.0, 3.0, -PI + 0.2);
    let z = xi.between(&xj);
    assert!(pose_pose_error(&xi, &xj, &z).norm() < 1e-12);
}

/// A square loop of poses with a few landmarks, measured without noise, and an
/// initial guess perturbed by up to 0.3 m and 0.2 rad.
fn synthetic(perturb: f64) -> (PoseGraph, Vec<Pose2>) {
    let mut g = PoseGraph::new();
    let mut truth = Vec::new();
    for k in 0..16 {
        let side = k / 4;
        let s = (k % 4) as f64;
        let p = match side {
            0 => Pose2::new(s, 0.0, 0.0),
            1 => Pose2::new(4.0, s, PI / 2.0),
            2 => Pose2::new(4.0 - s, 4.0, PI),
            _ => Pose2::new(0.0, 4.0 - s, -PI / 2.0),
        };
        truth.push(p);
        let wiggle = perturb * (((k * 7) % 5) as f64 / 4.0 - 0.5);
        let start = Pose2::new(p.x + wiggle, p.y - wiggle, p.theta + 0.6 * wiggle);
        g.add_pose(k as u64, start).unwrap();
    }
    let info = Matrix3::from_diagonal(&Vector3::new(100.0, 100.0, 400.0));
    for k in 0..16 {
        let j = (k + 1) % 16;
        g.add_edge(EdgeKind::PosePose {
            from: k,
            to: j,
            measurement: truth[k].between(&truth[j]),
            information: info,
        })
        .unwrap();
    }
    let landmarks = [Vector2::new(2.0, 2.0), Vector2::new(5.0, 1.0)];
    for (n, l) in landmarks.iter().enumerate() {
        let li = g
            .add_point(100 + n as u64, l + Vector2::new(perturb, -perturb))
            .unwrap();
        for k in [0usize, 3, 6, 9, 12] {
            let local = truth[k].inverse().transform_point(l);
            let kind = if n == 0 {
                EdgeKind::PosePoint {
                    pose: k,
                    point: li,
                    measurement: local,
                    information: Matrix2::identity() * 50.0,
                }
            } else {
                EdgeKind::RangeBearing {
                    pose: k,
                    point: li,
                    range: local.norm(),
                    bearing: crate::math::atan2(local[1], local[0]),
                    information: Matrix2::new(50.0, 0.0, 0.0, 200.0),
                }
            };
            g.add_edge(kind).unwrap();
        }
    }
    g.add_edge(EdgeKind::PosePrior {
        pose: 0,
        measurement: truth[0],
        information: Matrix3::identity() * 1e6,
    })
    .unwrap();
    (g, truth)
}

#[test]
fn gauss_newton_solves_a_noise_free_graph_to_machine_precision() {
    let (g, truth) = synthetic(0.3);
    let mut opt = Optimizer::new(
        g,
        OptimizerSettings {
            solver: SolverKind::GaussNewton,
            absolute_tolerance: 0.0,
            relative_tolerance: 0.0,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(opt.cost() > 1.0, "the perturbed start costs {}", opt.cost());
    let mut steps = 0;
    while opt.cost() >= 1e-12 && steps < 6 {
        opt.step().unwrap();
        steps += 1;
    }
    assert!(
        opt.cost() < 1e-12,
        "cost {} after {steps} steps",
        opt.cost()
    );
    assert!(steps <= 6);
    for (k, t) in truth.iter().enumerate() {
        let VertexState::Pose(p) = opt.graph().vertices()[k].state else {
            panic!("not a pose")
        };
        assert!((p.x - t.x).abs() < 1e-7 && (p.y - t.y).abs() < 1e-7);
        assert!(wrap_angle(p.theta - t.theta).abs() < 1e-7);
    }
}

#[test]
fn levenberg_marquardt_never_accepts_a_cost_increase() {
    // A bad start (1.5 m, 0.9 rad) with a wrong loop closure under each kernel.
    for kernel in [
        RobustKernel::None,
        RobustKernel::Huber { delta: 1.0 },
        RobustKernel::Cauchy { c: 1.0 },
    ] {
        let (mut g, _) = synthetic(1.5);
        g.add_edge(EdgeKind::PosePose {
            from: 2,
            to: 11,
            measurement: Pose2::new(3.0, 3.0, 1.0),
            information: Matrix3::identity() * 100.0,
        })
        .unwrap();
        let mut opt = Optimizer::new(
            g,
            OptimizerSettings {
                kernel,
                ..Default::default()
            },
        )
        .unwrap();
        let mut previous = opt.cost();
        let mut rejected = 0;
        for _ in 0..60 {
            let r = opt.step().unwrap();
            assert_eq!(r.cost_before, previous);
            if r.accepted {
                assert!(r.cost < r.cost_before, "{kernel:?}: accepted {r:?}");
            } else {
                rejected += 1;
                assert_eq!(r.cost, r.cost_before);
            }
            assert_eq!(opt.cost(), r.cost);
            previous = r.cost;
            if r.converged {
                break;
            }
        }
        let _ = rejected;
    }
}

#[test]
fn first_order_method_lowers_the_cost_slower_than_gauss_newton() {
    let (g, _) = synthetic(0.3);
    let mut gd = Optimizer::new(
        g.clone(),
        OptimizerSettings {
            solver: SolverKind::GradientDescent,
            ..Default::default()
        },
    )
    .unwrap();
    let start = gd.cost();
    for _ in 0..5 {
        let r = gd.step().unwrap();
        assert!(!r.accepted || r.cost < r.cost_before);
    }
    assert!(gd.cost() < start);
    let mut gn = Optimizer::new(
        g,
        OptimizerSettings {
            solver: SolverKind::GaussNewton,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..5 {
        gn.step().unwrap();
    }
    assert!(
        gn.cost() < 1e-6 * gd.cost(),
        "gn {} gd {}",
        gn.cost(),
        gd.cost()
    );
}

#[test]
fn a_free_gauge_names_the_unanchored_component() {
    let (g, _) = synthetic(0.0);
    // Drop the prior: the graph can move rigidly.
    let mut free = g.clone();
    free.pop_edge();
    let err = Optimizer::new(free, OptimizerSettings::default()).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, OptimizeError::FreeGauge { .. }), "{err:?}");
    assert!(text.contains("18 vertices (0, 1, 2, 3, 4, …)"), "{text}");
    assert!(text.contains("no prior and no fixed vertex"), "{text}");

    // A second, disconnected pair of poses next to the anchored loop.
    let mut two = g.clone();
    let a = two.add_pose(500, Pose2::new(0.0, 0.0, 0.0)).unwrap();
    let b = two.add_pose(501, Pose2::new(1.0, 0.0, 0.0)).unwrap();
    two.add_edge(EdgeKind::PosePose {
        from: a,
        to: b,
        measurement: Pose2::new(1.0, 0.0, 0.0),
        information: Matrix3::identity(),
    })
    .unwrap();
    let err = Optimizer::new(two.clone(), OptimizerSettings::default()).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("2 disconnected parts"), "{text}");
    assert!(text.contains("2 vertices (500, 501)"), "{text}");
    // Fixing a vertex of the second part makes it solvable.
    two.set_fixed(500, true).unwrap();
    let mut opt = Optimizer::new(two, OptimizerSettings::default()).unwrap();
    opt.step().unwrap();
}

#[test]
fn an_underdetermined_vertex_is_named_at_factorization() {
    // Pose 3 is tied to the fixed pose 0 by an edge without heading information:
    // its heading is free although the gauge is fixed.
    let mut g = PoseGraph::new();
    let p = g.add_pose(0, Pose2::IDENTITY).unwrap();
    g.set_fixed(0, true).unwrap();
    let q = g.add_pose(3, Pose2::new(1.0, 0.2, 0.1)).unwrap();
    g.add_edge(EdgeKind::PosePose {
        from: p,
        to: q,
        measurement: Pose2::new(1.0, 0.0, 0.0),
        information: Matrix3::from_diagonal(&Vector3::new(10.0, 10.0, 0.0)),
    })
    .unwrap();
    let mut opt = Optimizer::new(
        g,
        OptimizerSettings {
            solver: SolverKind::GaussNewton,
            ..Default::default()
        },
    )
    .unwrap();
    let err = opt.step().unwrap_err();
    assert_eq!(
        err,
        OptimizeError::Indefinite {
            vertex: 3,
            dof: "θ"
        }
    );
    assert!(err.to_string().contains("vertex 3 (θ)"), "{err}");
}

#[test]
fn bad_edges_are_refused_with_reasons() {
    let mut g = PoseGraph::new();
    g.add_pose(1, Pose2::IDENTITY).unwrap();
    g.add_pose(2, Pose2::IDENTITY).unwrap();
    assert_eq!(
        g.add_pose(2, Pose2::IDENTITY),
        Err(GraphError::DuplicateVertex(2))
    );
    let edge = |info: Matrix3<f64>, z: Pose2| EdgeKind::PosePose {
        from: 0,
        to: 1,
        measurement: z,
        information: info,
    };
    let e = g
        .add_edge(edge(Matrix3::zeros(), Pose2::IDENTITY))
        .unwrap_err();
    assert!(e.to_string().contains("is zero"), "{e}");
    let e = g
        .add_edge(edge(
            Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, 1.0)),
            Pose2::IDENTITY,
        ))
        .unwrap_err();
    assert!(e.to_string().contains("not positive semi-definite"), "{e}");
    let e = g
        .add_edge(edge(
            Matrix3::identity(),
            Pose2 {
                x: f64::NAN,
                y: 0.0,
                theta: 0.0,
            },
        ))
        .unwrap_err();
    assert!(e.to_string().contains("not a finite number"), "{e}");
    // Denormal information (FRH.g2o) is fine.
    let mut m = Matrix3::identity();
    m[(0, 2)] = 6.95335e-310;
    m[(2, 0)] = 6.95335e-310;
    assert!(g.add_edge(edge(m, Pose2::IDENTITY)).is_ok());
}

#[test]
fn patterns_mark_fill_in_and_covariances_match_the_dense_inverse() {
    let (g, _) = synthetic(0.0);
    let mut opt = Optimizer::new(g, OptimizerSettings::default()).unwrap();
    let h = opt.information_pattern().unwrap();
    assert_eq!(h.vertex_ids.len(), 18);
    // 18 diagonal blocks + 2 x (16 loop edges + 10 landmark edges).
    assert_eq!(h.entries.len(), 18 + 2 * 26);
    let (l, nnz) = opt.factor_pattern().unwrap();
    assert!(l.entries.iter().all(|&(r, c)| r >= c));
    let fill = l.fill_in.iter().filter(|&&f| f).count();
    // A loop cannot be eliminated without fill-in.
    assert!(fill > 0);
    // The scalar factor stores at least the block pattern's lower triangle.
    assert!(nnz >= l.scalar_entries(true).len());

    // Marginal covariance of pose 5 against a dense inverse of H.
    let cov = opt.marginal_covariances(&[5, 100]).unwrap();
    let MarginalCovariance::WorldPose(world5) = cov[0] else {
        panic!("pose expected")
    };
    // H is in the poses' own frames: compare its inverse with the local
    // covariance, the world one turned back.
    let theta5 = match g_vertex_state(&opt, 5) {
        VertexState::Pose(p) => p.theta,
        VertexState::Point(_) => panic!("pose expected"),
    };
    let back = local_to_world_covariance(&world5, -theta5);
    let c5 = back;
    let MarginalCovariance::Point(_) = cov[1] else {
        panic!("point expected")
    };
    // Dense H from the same edges.
    let (g, _) = synthetic(0.0);
    let n = 16 * 3 + 2 * 2;
    let mut hd = nalgebra::DMatrix::<f64>::zeros(n, n);
    let off = |i: usize| if i < 16 { 3 * i } else { 48 + 2 * (i - 16) };
    let dim = |i: usize| if i < 16 { 3 } else { 2 };
    for e in g.edges() {
        let lin = super::solver::tests_support::linearize(&g, e);
        let (a, b) = e.vertices();
        let blocks = [(a, lin.0), (b.unwrap_or(usize::MAX), lin.1)];
        for &(va, ja) in &blocks {
            for &(vb, jb) in &blocks {
                if va == usize::MAX || vb == usize::MAX {
                    continue;
                }
                let hb = ja.transpose() * lin.2 * jb;
                for r in 0..dim(va) {
                    for c in 0..dim(vb) {
                        hd[(off(va) + r, off(vb) + c)] += hb[(r, c)];
                    }
                }
            }
        }
    }
    let inv = hd.try_inverse().unwrap();
    for r in 0..3 {
        for c in 0..3 {
            let d = inv[(15 + r, 15 + c)];
            assert!(
                (c5[(r, c)] - d).abs() < 1e-9 * (1.0 + d.abs()),
                "{r},{c}: {} vs {d}",
                c5[(r, c)]
            );
        }
    }
}

fn g_vertex_state(opt: &Optimizer, id: u64) -> VertexState {
    opt.graph().vertex(id).unwrap().state
}

/// The marginal of a pose heading 2 rad is the world-frame covariance: it
/// matches the spread of the optimized pose over many noisy re-samplings of
/// the measurements (the local-frame `H⁻¹` block, drawn as a world ellipse,
/// would be turned by the heading).
#[test]
fn pose_marginals_are_world_frame_covariances_at_a_heading_far_from_zero() {
    use crate::random::standard_normal;
    use rand::SeedableRng;
    let heading = 2.0;
    let (s, c) = crate::math::sin_cos(heading);
    // Four poses 1 m apart straight along the heading; pose 0 fixed. Odometry
    // noise sd: 0.01 m forward, 0.05 m sideways, 0.02 rad. A range-bearing-free
    // chain: the world spread of pose 3 is long across the direction of travel.
    let truth: Vec<Pose2> = (0..4)
        .map(|k| Pose2::new(1.0 + k as f64 * c, -2.0 + k as f64 * s, heading))
        .collect();
    let sd = [0.01, 0.05, 0.02];
    let info = Matrix3::from_diagonal(&Vector3::new(
        1.0 / (sd[0] * sd[0]),
        1.0 / (sd[1] * sd[1]),
        1.0 / (sd[2] * sd[2]),
    ));
    let build = |noise: &[[f64; 3]]| {
        let mut g = PoseGraph::new();
        for (k, p) in truth.iter().enumerate() {
            g.add_pose(k as u64, *p).unwrap();
        }
        g.set_fixed(0, true).unwrap();
        for k in 0..3 {
            // Straight steps: θ_ij = 0, so noise added to the measurement's
            // components has exactly the information `info` (Eq. 4.5).
            let n = noise[k];
            g.add_edge(EdgeKind::PosePose {
                from: k,
                to: k + 1,
                measurement: Pose2::new(1.0 + sd[0] * n[0], sd[1] * n[1], sd[2] * n[2]),
                information: info,
            })
            .unwrap();
        }
        g
    };
    let mut opt = Optimizer::new(build(&[[0.0; 3]; 3]), OptimizerSettings::default()).unwrap();
    let MarginalCovariance::WorldPose(marginal) = opt.marginal_covariances(&[3]).unwrap()[0] else {
        panic!("pose expected")
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
    let trials = 3000;
    let mut xs = Vec::with_capacity(trials);
    for _ in 0..trials {
        let noise: Vec<[f64; 3]> = (0..3)
            .map(|_| std::array::from_fn(|_| standard_normal(&mut rng)))
            .collect();
        let mut opt = Optimizer::new(build(&noise), OptimizerSettings::default()).unwrap();
        opt.optimize(50, |_| true).unwrap();
        let VertexState::Pose(p) = g_vertex_state(&opt, 3) else {
            panic!("pose expected")
        };
        xs.push([p.x, p.y, wrap_angle(p.theta - heading)]);
    }
    let n = trials as f64;
    let mean: [f64; 3] = std::array::from_fn(|k| xs.iter().map(|x| x[k]).sum::<f64>() / n);
    let mut sample = Matrix3::zeros();
    for x in &xs {
        let d = Vector3::new(x[0] - mean[0], x[1] - mean[1], x[2] - mean[2]);
        sample += d * d.transpose() / (n - 1.0);
    }
    // Relative standard error of a sample covariance with 3000 draws: about
    // sqrt(2/3000) = 2.6% of the scale; allow 8% of the largest entry.
    let scale = sample.abs().max();
    let diff = (marginal - sample).abs().max();
    assert!(
        diff < 0.08 * scale,
        "marginal {marginal} sample {sample} diff {diff}"
    );
    // Not a coincidence of the heading: the local-frame covariance (what the
    // solver's H⁻¹ holds) is far from the spread.
    let local = local_to_world_covariance(&marginal, -heading);
    assert!(
        (local - sample).abs().max() > 0.5 * scale,
        "local {local} sample {sample}"
    );
}

#[test]
fn a_robust_kernel_limits_the_damage_of_a_wrong_loop_closure() {
    // The noise-free loop plus one confident but wrong closure between poses 2 and 11.
    let wrong = |g: &mut PoseGraph| {
        g.add_edge(EdgeKind::PosePose {
            from: 2,
            to: 11,
            measurement: Pose2::new(1.0, -2.0, 0.5),
            information: Matrix3::from_diagonal(&Vector3::new(100.0, 100.0, 400.0)),
        })
        .unwrap();
    };
    let error_after = |kernel: RobustKernel| {
        let (mut g, truth) = synthetic(0.0);
        wrong(&mut g);
        let mut opt = Optimizer::new(
            g,
            OptimizerSettings {
                kernel,
                ..Default::default()
            },
        )
        .unwrap();
        opt.optimize(100, |_| true).unwrap();
        let sq: f64 = truth
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let p = opt.graph().vertices()[k].state.position();
                (p - t.translation()).norm_squared()
            })
            .sum();
        (sq / truth.len() as f64).sqrt()
    };
    let plain = error_after(RobustKernel::None);
    let huber = error_after(RobustKernel::Huber { delta: 1.0 });
    let cauchy = error_after(RobustKernel::Cauchy { c: 1.0 });
    println!("position RMSE: plain {plain}, huber {huber}, cauchy {cauchy}");
    assert!(
        plain > 0.1,
        "least squares is pulled off by the wrong closure: {plain}"
    );
    assert!(huber < 0.1 * plain, "huber {huber} vs plain {plain}");
    assert!(cauchy < 0.01 * plain, "cauchy {cauchy} vs plain {plain}");
}

/// Every vertex state's bits, to compare two estimates exactly.
fn state_bits(opt: &Optimizer) -> Vec<u64> {
    opt.graph()
        .vertices()
        .iter()
        .flat_map(|v| match v.state {
            VertexState::Pose(p) => vec![p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()],
            VertexState::Point(q) => vec![q[0].to_bits(), q[1].to_bits()],
        })
        .collect()
}

#[test]
fn a_checkpoint_restores_the_estimate_and_the_next_iteration_bit_for_bit() {
    for solver in [
        SolverKind::GaussNewton,
        SolverKind::LevenbergMarquardt,
        SolverKind::GradientDescent,
    ] {
        let (g, _) = synthetic(1.0);
        let mut opt = Optimizer::new(
            g,
            OptimizerSettings {
                solver,
                kernel: RobustKernel::Huber { delta: 1.0 },
                ..Default::default()
            },
        )
        .unwrap();
        opt.step().unwrap();
        opt.step().unwrap();
        let checkpoint = opt.checkpoint();
        let (bits, cost, lambda) = (state_bits(&opt), opt.cost(), opt.lambda());
        assert_eq!(checkpoint.iterations(), 2);
        let next = opt.step().unwrap();
        let after_next = state_bits(&opt);
        // An edit after the checkpoint: a wrong edge and another kernel.
        opt.add_edge(EdgeKind::PosePose {
            from: 2,
            to: 11,
            measurement: Pose2::new(3.0, 3.0, 1.0),
            information: Matrix3::identity() * 100.0,
        })
        .unwrap();
        opt.set_kernel(RobustKernel::None);
        opt.step().unwrap();
        assert_ne!(state_bits(&opt), bits);
        opt.restore_checkpoint(&checkpoint).unwrap();
        assert_eq!(opt.graph().edges().len(), 16 + 10 + 1, "{solver:?}");
        assert_eq!(state_bits(&opt), bits, "{solver:?}");
        assert_eq!(opt.cost().to_bits(), cost.to_bits(), "{solver:?}");
        assert_eq!(opt.lambda(), lambda);
        assert_eq!(opt.iterations(), 2);
        assert_eq!(opt.settings().kernel, RobustKernel::Huber { delta: 1.0 });
        // The iteration after the checkpoint is the same iteration again.
        let again = opt.step().unwrap();
        assert_eq!(again, next, "{solver:?}");
        assert_eq!(state_bits(&opt), after_next, "{solver:?}");
    }
    // A checkpoint of another graph is refused and changes nothing.
    let (g, _) = synthetic(1.0);
    let mut small = Optimizer::new(g.clone(), OptimizerSettings::default()).unwrap();
    let mut g2 = g;
    g2.add_point(200, Vector2::new(1.0, 1.0)).unwrap();
    g2.add_edge(EdgeKind::PosePoint {
        pose: 1,
        point: 18,
        measurement: Vector2::new(0.0, 1.0),
        information: Matrix2::identity(),
    })
    .unwrap();
    let other = Optimizer::new(g2, OptimizerSettings::default()).unwrap();
    let before = state_bits(&small);
    let err = small.restore_checkpoint(&other.checkpoint()).unwrap_err();
    assert!(
        matches!(err, OptimizeError::CheckpointMismatch(_)),
        "{err:?}"
    );
    assert_eq!(state_bits(&small), before);
}
