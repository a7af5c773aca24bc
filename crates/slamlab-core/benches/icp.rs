//! ICP of two 360-beam scans of a simulated room taken 0.1 m and 3° apart:
//! `cargo bench -p slamlab-core --bench icp`.
//!
//! Target: point-to-line ≤ 0.3 ms natively. Results with date and machine are
//! in `docs/icp.md`.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::laser::test_room::{self, Segment, rectangle};
use slamlab_core::scan::icp::{IcpConfig, IcpState, IcpVariant, align};
use slamlab_core::scan::{Point2, Scan};

fn main() {
    // Print what is being timed once, so the numbers can be read with it.
    let (reference, scan) = room_scans();
    for variant in [IcpVariant::PointToLine, IcpVariant::PointToPoint] {
        let run = IcpState::new(&reference, &scan, Pose2::IDENTITY, config(variant))
            .and_then(|mut icp| Ok((icp.run()?.0, icp.query_counts())));
        match run {
            Ok((m, (certified, asked))) => println!(
                "{variant:?}: {} + {} points, {} iterations, converged {}, pose ({:.4} m, {:.4} m, {:.3}°), truth (0.1 m, 0 m, 3°); nearest neighbours: {certified} certified, {asked} asked of the tree",
                reference.len(),
                scan.len(),
                m.iterations,
                m.converged,
                m.pose.x,
                m.pose.y,
                m.pose.theta.to_degrees()
            ),
            Err(e) => println!("{variant:?}: {e}"),
        }
    }
    cpu_times(&reference, &scan);
    divan::main();
}

/// The thread's CPU time per registration (median of 15 batches of 200), which
/// other work on the machine does not inflate as it does the wall-clock times
/// divan reports below.
fn cpu_times(reference: &[Point2], scan: &[Point2]) {
    for variant in [IcpVariant::PointToLine, IcpVariant::PointToPoint] {
        let config = config(variant);
        let mut batches: Vec<f64> = (0..15)
            .map(|_| {
                let started = cpu_time::ThreadTime::now();
                for _ in 0..200 {
                    std::hint::black_box(
                        align(reference, scan, Pose2::IDENTITY, &config).map(|r| r.0),
                    )
                    .ok();
                }
                started.elapsed().as_secs_f64() * 1e3 / 200.0
            })
            .collect();
        batches.sort_by(f64::total_cmp);
        println!(
            "{variant:?}: whole registration {:.3} ms of thread CPU time (median of 15 batches; fastest {:.3} ms)",
            batches[7], batches[0]
        );
    }
}

/// An 8 m × 6 m room with a table, a cupboard and a pillar.
fn room() -> Vec<Segment> {
    let mut walls = Vec::new();
    walls.extend(rectangle(-4.0, -3.0, 4.0, 3.0));
    walls.extend(rectangle(1.0, -0.5, 2.2, 0.3));
    walls.extend(rectangle(-3.8, 1.8, -2.0, 3.0));
    walls.extend(rectangle(-1.5, -2.0, -1.2, -1.7));
    walls
}

/// 360 beams over 360°, 10 m range, 1 cm Gaussian range noise.
fn ray_cast(walls: &[Segment], pose: Pose2, rng: &mut ChaCha8Rng) -> Scan {
    test_room::ray_cast(walls, pose, 360, 10.0, Some((0.01, rng)))
}

fn room_scans() -> (Vec<Point2>, Vec<Point2>) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let walls = room();
    let reference = ray_cast(&walls, Pose2::new(0.0, 0.5, 0.0), &mut rng).points();
    let scan = ray_cast(&walls, Pose2::new(0.1, 0.5, 3f64.to_radians()), &mut rng).points();
    (reference, scan)
}

fn config(variant: IcpVariant) -> IcpConfig {
    IcpConfig {
        variant,
        ..IcpConfig::default()
    }
}

/// The whole registration: k-d tree, normals, iterations, final cost.
#[divan::bench(args = [IcpVariant::PointToLine, IcpVariant::PointToPoint])]
fn align_360_beams(bencher: divan::Bencher, variant: IcpVariant) {
    let (reference, scan) = room_scans();
    let config = config(variant);
    bencher.bench_local(|| align(&reference, &scan, Pose2::IDENTITY, &config).map(|r| r.0));
}

/// Only the set-up: the k-d tree over the reference and, for point-to-line,
/// its normals.
#[divan::bench(args = [IcpVariant::PointToLine, IcpVariant::PointToPoint])]
fn setup_360_beams(bencher: divan::Bencher, variant: IcpVariant) {
    let (reference, scan) = room_scans();
    let config = config(variant);
    bencher.bench_local(|| IcpState::new(&reference, &scan, Pose2::IDENTITY, config).is_ok());
}
