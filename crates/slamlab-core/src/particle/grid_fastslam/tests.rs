use super::*;
use crate::laser::test_room::{Segment, ray_cast, room};
use crate::random::gaussian;

const RANGE_MAX: f64 = 8.0;

fn scan_at(walls: &[Segment], pose: Pose2) -> Scan {
    ray_cast(walls, pose, 180, RANGE_MAX, None)
}

/// Two laps of an ellipse in the room (2.0 m × 1.3 m half-axes, clear of the
/// pillar and the cupboard), 0.1 m per step: the true poses, and odometry
/// that integrates the true increments with 5 % translation noise and a
/// heading error of 0.01 rad per step plus noise.
fn drive(seed: u64, steps: usize) -> (Vec<Pose2>, Vec<Pose2>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let at = |k: usize| {
        let t = k as f64 * 0.1 / 1.7;
        let (x, y) = (2.0 * math::cos(t), 1.3 * math::sin(t));
        let (dx, dy) = (-2.0 * math::sin(t), 1.3 * math::cos(t));
        Pose2::new(x, y, math::atan2(dy, dx))
    };
    let truth: Vec<Pose2> = (0..steps).map(at).collect();
    let mut odometry = vec![truth[0]];
    for k in 1..steps {
        let inc = truth[k - 1].between(&truth[k]);
        let noisy = Pose2::new(
            inc.x * (1.0 + gaussian(&mut rng, 0.05)),
            inc.y + gaussian(&mut rng, 0.005),
            inc.theta + 0.01 + gaussian(&mut rng, 0.01),
        );
        let last = odometry[k - 1];
        odometry.push(last.compose(&noisy));
    }
    (truth, odometry)
}

fn config(proposal: Proposal, particles: usize) -> GridFastSlamConfig {
    GridFastSlamConfig {
        particles,
        proposal,
        linear_update: 0.3,
        angular_update: 0.3,
        ..GridFastSlamConfig::default()
    }
}

/// Runs the filter over the drive; returns it and the RMS position error of
/// the best particle's path at its update scans.
fn run(config: GridFastSlamConfig, seed: u64, steps: usize) -> (GridFastSlam, f64) {
    let walls = room();
    let (truth, odometry) = drive(seed, steps);
    let (mut filter, notes) = GridFastSlam::new(config, InsertParams::default(), seed);
    assert!(notes.is_empty(), "{notes:?}");
    for k in 0..steps {
        filter.process(k, odometry[k], &scan_at(&walls, truth[k]));
    }
    let best = filter.best().expect("particles");
    let path = best.path.path();
    let sum: f64 = path
        .iter()
        .map(|(k, p)| (p.x - truth[*k].x).powi(2) + (p.y - truth[*k].y).powi(2))
        .sum();
    let rmse = (sum / path.len() as f64).sqrt();
    (filter, rmse)
}

#[test]
fn motion_samples_have_gmappings_spread() {
    let c = GridFastSlamConfig::default();
    let delta = Pose2::new(0.8, 0.1, 0.3);
    let std = motion_std(&c, delta);
    // srr|dx| + str|dθ| + 0.3 srr|dy|, and so on, by hand.
    assert!((std[0] - (0.1 * 0.8 + 0.1 * 0.3 + 0.03 * 0.1)).abs() < 1e-12);
    assert!((std[1] - (0.1 * 0.1 + 0.1 * 0.3 + 0.03 * 0.8)).abs() < 1e-12);
    assert!((std[2] - (0.2 * 0.3 + 0.2 * math::hypot(0.8, 0.1))).abs() < 1e-12);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let n = 20_000;
    let samples: Vec<Pose2> = (0..n)
        .map(|_| draw_from_motion(&c, Pose2::IDENTITY, delta, &mut rng))
        .collect();
    // From the identity the sample is delta plus noise, axis by axis.
    let mean = |f: &dyn Fn(&Pose2) -> f64| samples.iter().map(f).sum::<f64>() / n as f64;
    let (mx, my, mt) = (mean(&|p| p.x), mean(&|p| p.y), mean(&|p| p.theta));
    assert!((mx - 0.8).abs() < 0.003 && (my - 0.1).abs() < 0.002 && (mt - 0.3).abs() < 0.003);
    let sx = mean(&|p| (p.x - mx).powi(2)).sqrt();
    let sy = mean(&|p| (p.y - my).powi(2)).sqrt();
    let st = mean(&|p| (p.theta - mt).powi(2)).sqrt();
    for (got, want) in [(sx, std[0]), (sy, std[1]), (st, std[2])] {
        assert!((got / want - 1.0).abs() < 0.03, "std {got} against {want}");
    }
}

#[test]
fn weights_are_gmappings_smoothed_ones() {
    let walls = room();
    let scan = scan_at(&walls, Pose2::IDENTITY);
    let (mut f, _) = GridFastSlam::new(config(Proposal::Odometry, 2), InsertParams::default(), 1);
    f.initialize(0, Pose2::IDENTITY, &scan);
    f.particles[0].log_weight = 0.0;
    f.particles[1].log_weight = -6.0;
    // gain 1/(ogain M) = 1/6: weights ∝ (1, e^-1).
    let neff = f.normalize();
    let w0 = 1.0 / (1.0 + math::exp(-1.0));
    assert!((f.weights()[0] - w0).abs() < 1e-12);
    assert!((neff - 1.0 / (w0 * w0 + (1.0 - w0) * (1.0 - w0))).abs() < 1e-12);
    assert_eq!(f.best_index(), 0);
}

#[test]
fn resampled_copies_share_tiles_until_they_write_and_writing_one_cell_copies_one_tile() {
    let walls = room();
    let (mut f, _) = GridFastSlam::new(config(Proposal::Odometry, 4), InsertParams::default(), 2);
    f.initialize(0, Pose2::IDENTITY, &scan_at(&walls, Pose2::IDENTITY));
    let tiles = f.particles[0].map.tiles().count();
    assert!(tiles > 4);
    // Every particle holds the first map's tiles: the memory is one map's.
    assert_eq!(
        f.memory_bytes() - 3 * slot_bytes(&f.particles[0].map),
        f.particles[0].map.memory_bytes()
    );
    // All weight on particle 2: everyone becomes a copy of it.
    f.particles[2]
        .map
        .insert_scan(
            &Pose2::new(0.2, 0.0, 0.0),
            &scan_at(&walls, Pose2::new(0.2, 0.0, 0.0)),
            &InsertParams::default(),
        )
        .unwrap();
    f.particles[2].pose = Pose2::new(0.2, 0.0, 0.0);
    for (i, p) in f.particles.iter_mut().enumerate() {
        p.log_weight = if i == 2 { 0.0 } else { -1e4 };
    }
    f.normalize();
    let parent = f.particles[2].map.clone();
    let (resampled, survivors) = f.resample_if_needed();
    assert!(resampled);
    assert_eq!(survivors, 1);
    let parent_tiles = parent.tiles().count();
    for p in &f.particles {
        assert_eq!(p.map.shared_tiles_with(&parent), parent_tiles);
        assert_eq!(p.pose, Pose2::new(0.2, 0.0, 0.0));
        assert_eq!(p.log_weight, 0.0);
    }
    // A one-beam scan of 1 cm ends in the sensor's own cell: one cell
    // written, so one tile copied.
    let one_cell = Scan {
        angles: vec![0.0],
        ranges: vec![0.01],
        range_min: 0.0,
        range_max: RANGE_MAX,
    };
    let before = f.memory_bytes();
    let report = f.particles[1]
        .map
        .insert_scan(
            &Pose2::new(0.52, 0.52, 0.0),
            &one_cell,
            &InsertParams::default(),
        )
        .unwrap();
    assert_eq!(report.hits + report.misses, 1);
    assert_eq!(
        f.particles[1].map.shared_tiles_with(&parent),
        parent_tiles - 1
    );
    assert_eq!(f.particles[0].map.shared_tiles_with(&parent), parent_tiles);
    assert_eq!(f.memory_bytes() - before, ProbabilityGrid::TILE_BYTES);
}

fn slot_bytes(grid: &ProbabilityGrid) -> usize {
    // What `memory_bytes` counts besides the tiles: the table of slots.
    grid.memory_bytes() - grid.tiles().count() * ProbabilityGrid::TILE_BYTES
}

#[test]
fn the_fitted_proposal_matches_a_brute_force_evaluation_of_the_same_density() {
    let walls = room();
    let truth = Pose2::new(0.3, -0.4, 0.2);
    // The map from scans around the truth, the scan at the truth.
    let mut map = ProbabilityGrid::new(0.05);
    for k in 0..12 {
        let t = k as f64 / 12.0 * std::f64::consts::TAU;
        let p = Pose2::new(0.3 + 0.5 * math::cos(t), -0.4 + 0.4 * math::sin(t), t);
        map.insert_scan(&p, &scan_at(&walls, p), &InsertParams::default())
            .unwrap();
    }
    let points = LikelihoodPoints::new(&scan_at(&walls, truth));
    let c = GridFastSlamConfig::default();
    // A prior centred 3 cm and 0.01 rad off the truth.
    let prior = MotionPrior {
        mean: Pose2::new(0.33, -0.41, 0.21),
        std: [0.1, 0.1, 0.03],
    };
    let fitted = fit_proposal(&map, &points, truth, &prior, &c).expect("a Gaussian");
    assert_eq!(fitted.samples, 5 * 5 * 7);
    // Brute force: the same density on a fine grid (2.5 mm, 0.00125 rad)
    // half as wide again as the samples reach, where it has died away.
    let mut samples = Vec::new();
    let n = 24;
    for a in -n..=n {
        for b in -n..=n {
            for cx in -n..=n {
                let x = Pose2::new(
                    truth.x + cx as f64 * 0.0025,
                    truth.y + b as f64 * 0.0025,
                    truth.theta + a as f64 * 0.00125,
                );
                let (l, _) = scan_log_likelihood(&map, &points, &x, &c);
                samples.push((x, l + prior.log_density(&x)));
            }
        }
    }
    let reference = gaussian_of_weighted_poses(&samples).expect("reference");
    let dm = math::hypot(
        fitted.mean.x - reference.mean.x,
        fitted.mean.y - reference.mean.y,
    );
    assert!(dm < map.resolution(), "mean {dm} m apart");
    assert!(wrap_angle(fitted.mean.theta - reference.mean.theta).abs() < c.lasamplestep);
    // The covariance is close but not within the 10 % one might hope for:
    // standard deviations measured x +6.5 %, y +3.2 %, heading −10.2 %, the
    // whole matrix 13.9 % off in the Frobenius norm. The likelihood's peak
    // is not a Gaussian (end points snap to 5 cm cells), so its moments
    // from 175 samples depend on where the samples fall: widening the
    // heading range to 0.025 rad made the heading 19 % narrow, and a
    // 7 × 7 × 7 grid over the same box put x 19 % wide.
    for (k, axis) in ["x", "y", "heading"].into_iter().enumerate() {
        let ratio = (fitted.covariance[(k, k)] / reference.covariance[(k, k)]).sqrt();
        assert!(
            (ratio - 1.0).abs() < 0.12,
            "{axis}: standard deviation ratio {ratio:.3}"
        );
    }
    let rel = (fitted.covariance - reference.covariance).norm() / reference.covariance.norm();
    assert!(rel < 0.15, "covariance {rel:.3} off");
}

#[test]
fn a_scan_with_nothing_to_match_falls_back_to_odometry_with_finite_weights() {
    let walls = room();
    let (mut f, _) = GridFastSlam::new(config(Proposal::ScanMatch, 5), InsertParams::default(), 3);
    // A blank first scan: every beam at max range leaves the maps empty of
    // occupied cells.
    let blank = Scan {
        angles: (0..90).map(|k| k as f64 * 0.07).collect(),
        ranges: vec![RANGE_MAX; 90],
        range_min: 0.0,
        range_max: RANGE_MAX,
    };
    f.process(0, Pose2::IDENTITY, &blank).expect("first scan");
    let report = f
        .process(
            1,
            Pose2::new(0.5, 0.0, 0.0),
            &scan_at(&walls, Pose2::new(0.5, 0.0, 0.0)),
        )
        .expect("an update");
    assert_eq!(report.fallbacks, 5, "a blank map matches nothing");
    let report = f
        .process(2, Pose2::new(1.0, 0.0, 0.0), &blank)
        .expect("an update");
    assert_eq!(
        report.fallbacks, 5,
        "a scan without end points matches nothing"
    );
    assert!(f.weights().iter().all(|w| w.is_finite() && *w > 0.0));
    assert!(
        f.particles()
            .iter()
            .all(|p| p.pose.is_finite() && p.log_weight.is_finite())
    );
    assert_eq!(f.fallbacks(), 10);
    // Too little motion: no update.
    assert!(f.process(3, Pose2::new(1.05, 0.0, 0.0), &blank).is_none());
    assert!(
        f.process(4, Pose2::new(f64::NAN, 0.0, 0.0), &blank)
            .is_none()
    );
}

#[test]
fn particle_counts_out_of_range_are_clamped_with_a_message() {
    for (asked, got) in [(0, 1), (100_000, MAX_GRID_PARTICLES)] {
        let (f, notes) = GridFastSlam::new(
            GridFastSlamConfig {
                particles: asked,
                ..GridFastSlamConfig::default()
            },
            InsertParams::default(),
            1,
        );
        assert_eq!(f.config().particles, got);
        assert!(notes.iter().any(|n| n.contains("particles")), "{notes:?}");
    }
    let (f, notes) = GridFastSlam::new(
        GridFastSlamConfig {
            lsigma: f64::NAN,
            ogain: -1.0,
            resample_threshold: 2.0,
            ..GridFastSlamConfig::default()
        },
        InsertParams::default(),
        1,
    );
    assert_eq!(notes.len(), 3, "{notes:?}");
    assert_eq!(f.config().lsigma, 0.075);
    assert_eq!(f.config().ogain, 3.0);
    assert_eq!(f.config().resample_threshold, 0.5);
}

#[test]
fn the_improved_proposal_tracks_the_truth_better_than_odometry_and_runs_repeat_bit_for_bit() {
    let steps = 200;
    let (mut odo_sum, mut sm_sum) = (0.0, 0.0);
    for seed in 1..=3 {
        let (odo, odo_rmse) = run(config(Proposal::Odometry, 10), seed, steps);
        let (sm, sm_rmse) = run(config(Proposal::ScanMatch, 10), seed, steps);
        eprintln!(
            "seed {seed}: odometry proposal {odo_rmse:.3} m ({} resamplings), scan-match {sm_rmse:.3} m ({} resamplings, {} updates, {} fallbacks)",
            odo.resamplings(),
            sm.resamplings(),
            sm.updates(),
            sm.fallbacks()
        );
        odo_sum += odo_rmse;
        sm_sum += sm_rmse;
        // In this small room both track (measured: 0.04-0.10 m); the
        // difference is in the weights. The odometry proposal's samples
        // land where the scan disagrees, the weights spread, and it
        // resamples at almost every update (58-59 of 60); the improved
        // proposal's particles all sit on the likelihood's peak and it
        // almost never does (0-1).
        assert!(sm_rmse < 0.1 && odo_rmse < 0.15, "seed {seed}");
        assert!(odo.resamplings() > odo.updates() * 3 / 4, "seed {seed}");
        assert!(sm.resamplings() <= 3, "seed {seed}");
        assert_eq!(sm.fallbacks(), 0);
    }
    // The improved proposal is the closer on average (measured 0.046 m
    // against 0.078 m).
    assert!(sm_sum < odo_sum, "{sm_sum} against {odo_sum}");
    let (a, _) = run(config(Proposal::ScanMatch, 5), 9, 80);
    let (b, _) = run(config(Proposal::ScanMatch, 5), 9, 80);
    for (p, q) in a.particles().iter().zip(b.particles()) {
        assert_eq!(p.pose.x.to_bits(), q.pose.x.to_bits());
        assert_eq!(p.pose.theta.to_bits(), q.pose.theta.to_bits());
    }
}

#[test]
fn paths_form_a_tree_that_merges_after_resampling() {
    let (f, _) = run(config(Proposal::Odometry, 8), 5, 120);
    assert!(f.resamplings() > 0);
    // Every path has one node per update and starts at the first scan.
    for p in f.particles() {
        let path = p.path.path();
        assert_eq!(path.len(), f.updates());
        assert_eq!(path[0].0, 0);
    }
    // The first nodes are one allocation for all particles.
    let root = |p: &GridParticle| {
        let mut n = &p.path;
        while let Some(parent) = &n.parent {
            n = parent;
        }
        Arc::as_ptr(n)
    };
    let r0 = root(&f.particles()[0]);
    assert!(f.particles().iter().all(|p| root(p) == r0));
}
