//! One branch-and-bound search (thesis `000` Algorithm 12) of a 360-beam scan
//! in a 7 m x 7 m x 30° window (Cartographer's constraint window) on a 5 cm
//! submap of a 16 m x 12 m room with boxes, 150 points, heights 0..=6:
//! `cargo bench -p slamlab-core --bench branch_and_bound`.
//!
//! Target (issue 23): 10 ms natively. Results with date and machine are in
//! `docs/cartographer.md`.

use slamlab_core::Pose2;
use slamlab_core::grid::{InsertParams, ProbabilityGrid, UpdateRule};
use slamlab_core::laser::test_room::{Segment, ray_cast, rectangle};
use slamlab_core::math;
use slamlab_core::scan::branch_and_bound::{
    BranchAndBoundParams, PrecomputedGrids, SearchWindow, branch_and_bound, exhaustive_search,
};
use slamlab_core::scan::scan_to_map::spread_points;
use slamlab_core::scan::{Point2, Scan};
use std::f64::consts::PI;

fn main() {
    let (grid, points) = setup();
    let Some(grids) = PrecomputedGrids::new(&grid, 6) else {
        println!("the submap has no cells");
        return;
    };
    let (m, record) = branch_and_bound(&grids, &points, &window(), &params());
    println!(
        "{} points, {} headings; found {:?}; {} candidates scored ({:?} per height), exhaustive {} ({:.0}x)",
        points.len(),
        record.angles,
        m.map(|m| (m.pose, m.score)),
        record.evaluated(),
        record.evaluated_per_height,
        record.exhaustive_candidates,
        record.exhaustive_candidates as f64 / record.evaluated().max(1) as f64
    );
    divan::main();
}

/// A 16 m × 12 m room with five boxes.
fn walls() -> Vec<Segment> {
    let mut w = rectangle(-8.0, -6.0, 8.0, 6.0);
    for (x, y, s) in [
        (-5.0, -3.0, 1.0),
        (2.0, 2.5, 0.8),
        (4.5, -2.0, 1.2),
        (-3.0, 3.0, 0.6),
        (0.5, -4.0, 0.7),
    ] {
        w.extend(rectangle(x, y, x + s, y + s));
    }
    w
}

/// 360 beams over 360°, exact ranges up to 12 m.
fn scan_at(walls: &[Segment], pose: &Pose2) -> Scan {
    ray_cast(walls, *pose, 360, 12.0, None)
}

fn setup() -> (ProbabilityGrid, Vec<Point2>) {
    let walls = walls();
    let mut grid = ProbabilityGrid::new(0.05);
    let params = InsertParams {
        rule: UpdateRule::CARTOGRAPHER,
        max_range_free: 0.0,
    };
    for k in 0..60 {
        let t = k as f64 / 60.0 * 2.0 * PI;
        let pose = Pose2::new(-1.0 + 4.0 * math::cos(t), 1.0 * math::sin(t), t);
        // The rule is valid and the poses finite: insertion cannot fail.
        let _ = grid.insert_scan(&pose, &scan_at(&walls, &pose), &params);
    }
    let truth = Pose2::new(1.3, -0.6, 0.4);
    let points = spread_points(&scan_at(&walls, &truth).points(), 150);
    (grid, points)
}

fn window() -> SearchWindow {
    // The estimate 1.5 m and 10° off the truth.
    SearchWindow::Around {
        initial: Pose2::new(2.3, 0.5, 0.4 + 10f64.to_radians()),
        linear: 7.0,
        angular: 30f64.to_radians(),
    }
}

fn params() -> BranchAndBoundParams {
    BranchAndBoundParams {
        min_score: 0.55,
        recorded_nodes: 0,
    }
}

#[divan::bench(sample_count = 20)]
fn bbs_7m_30deg_5cm(bencher: divan::Bencher) {
    let (grid, points) = setup();
    let Some(grids) = PrecomputedGrids::new(&grid, 6) else {
        return;
    };
    bencher.bench(|| branch_and_bound(&grids, &points, &window(), &params()));
}

#[divan::bench(sample_count = 10)]
fn precompute_heights_0_to_6(bencher: divan::Bencher) {
    let (grid, _) = setup();
    bencher.bench(|| PrecomputedGrids::new(&grid, 6));
}

#[divan::bench(sample_count = 3)]
fn exhaustive_7m_30deg_5cm(bencher: divan::Bencher) {
    let (grid, points) = setup();
    let Some(grids) = PrecomputedGrids::new(&grid, 6) else {
        return;
    };
    bencher.bench(|| exhaustive_search(&grids, &points, &window(), 0.55));
}
