//! Monte Carlo localization on a recorded robot: a simulated run written as a
//! ROS 2 bag (with its truth on `/ground_truth`) and as a CARMEN log, replayed
//! through the filters in the map it was recorded in.

use super::run::{MclRun, MclRunError, log_notes};
use super::scenario::{InitMode, LocalizationEstimator, MclScenario};
use crate::grid::scans::log_input;
use crate::grid::{BuiltinMap, LaserFile, MappingInput, SimulatedLogConfig, simulate_log};
use crate::io::laser_log::{LaserLog, TruePose, write_carmen};
use crate::io::ros2_bag::{BagWriteOptions, TopicChoice, write_bag};
use slamlab_core::Pose2;
use slamlab_core::math;

const STEPS: usize = 400;
const SEED: u64 = 3;

fn recorded_run() -> (LaserLog, Vec<TruePose>) {
    let map = BuiltinMap::Maze.load().unwrap();
    simulate_log(&map, STEPS, SEED, &SimulatedLogConfig::default()).unwrap()
}

/// The recorded run, its truth, and the lesson's input read from the run
/// written as a ROS 2 bag with its `/ground_truth`.
fn recorded_bag() -> (LaserLog, Vec<TruePose>, MappingInput) {
    let (log, truth) = recorded_run();
    let bag = write_bag(&log, Some(&truth), &BagWriteOptions::default()).unwrap();
    let file = LaserFile::from_bytes("run.mcap", &bag, &TopicChoice::default()).unwrap();
    (log, truth, file.input)
}

fn scenario(init: InitMode) -> MclScenario {
    MclScenario {
        seed: 1,
        init,
        estimators: vec![LocalizationEstimator::Mcl, LocalizationEstimator::Acmcl],
        max_particles: 2000,
        ..MclScenario::default()
    }
}

fn replay(input: MappingInput, init: InitMode) -> MclRun {
    let grid = BuiltinMap::Maze.load().unwrap();
    let mut run = MclRun::from_log(scenario(init), grid, input).unwrap();
    let before = run.tick_count();
    run.run_ticks(10_000);
    assert_eq!(run.tick_count() - before, STEPS as u64, "one tick a scan");
    assert!(run.is_finished());
    run
}

fn particles(run: &MclRun) -> Vec<(u64, u64, u64)> {
    run.filters()
        .iter()
        .flat_map(|f| f.mcl().particles().iter().map(|p| p.pose))
        .map(|p| (p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()))
        .collect()
}

/// Distance of each filter's final estimate from `truth`, metres.
fn final_errors(run: &MclRun, truth: Pose2) -> Vec<f64> {
    (0..run.filters().len())
        .map(|k| {
            let e = run.filters()[k].current_estimate(&run.odometry()).unwrap();
            math::hypot(e.x - truth.x, e.y - truth.y)
        })
        .collect()
}

/// Global localization from the bag: MCL and ACMCL find the recorded robot in
/// the maze and stay on it; the errors are measured against the bag's
/// `/ground_truth`.
#[test]
fn a_bag_replayed_in_its_map_localizes_against_its_own_truth() {
    let (_, truth, input) = recorded_bag();
    let run = replay(input.clone(), InitMode::Global);
    assert!(run.has_truth());
    assert!(run.notes().is_empty(), "{:?}", run.notes());
    assert_eq!(run.truth_ticks().len(), STEPS);
    assert_eq!(run.truth_ticks()[STEPS - 1], truth[STEPS - 1].pose);
    for f in run.filters() {
        let s = f.summary();
        let converged = s
            .converged_tick
            .unwrap_or_else(|| panic!("{} never converged", f.name));
        let rmse = s.position_rmse_converged.unwrap();
        println!(
            "{}: converged at tick {converged}, RMSE after {rmse:.3} m, final {:.3} m, {} updates",
            f.name,
            s.position_error_final.unwrap(),
            f.updates.len()
        );
        assert!(converged < 200, "{}: tick {converged}", f.name);
        assert!(rmse < 0.12, "{}: {rmse}", f.name);
        assert!(s.position_error_final.unwrap() < 0.12);
    }
    // A replay that reads the laser mirrored (an upside-down mounting missed,
    // or a clockwise scanner's angles taken the wrong way round) does not
    // localize: the bounds above are ones a broken replay fails.
    let mut mirrored = input;
    for s in &mut mirrored.scans {
        for a in &mut s.scan.angles {
            *a = -*a;
        }
    }
    let broken = replay(mirrored, InitMode::Global);
    let worst = broken
        .filters()
        .iter()
        .map(|f| f.summary().position_rmse_converged.unwrap_or(f64::INFINITY))
        .fold(0.0, f64::max);
    println!("mirrored laser: worst RMSE after convergence {worst:.3} m");
    assert!(worst >= 0.12, "{worst}");
}

/// The CARMEN copy of the run has no truth: the errors are NaN, the summary
/// leaves them out, the status says why; the filters still find the robot
/// (checked here against the truth file beside the log). Its replay is bit for
/// bit the replay of the run rounded as CARMEN writes it.
#[test]
fn a_carmen_log_replays_without_truth_and_reads_what_its_text_says() {
    let (log, truth) = recorded_run();
    let text = write_carmen(&log).unwrap();
    let file = LaserFile::from_bytes("run.clf", text.as_bytes(), &TopicChoice::default()).unwrap();
    assert!(file.input.truth.is_none());
    let run = replay(file.input.clone(), InitMode::Global);
    assert!(!run.has_truth());
    assert!(run.truth_ticks().is_empty() && run.path().is_empty());
    assert!(
        run.status_of(0)
            .starts_with("no truth in this log: estimate ("),
        "{}",
        run.status_of(0)
    );
    for f in run.filters() {
        let s = f.summary();
        assert_eq!(
            (
                s.converged_tick,
                s.position_error_final,
                s.position_rmse_converged
            ),
            (None, None, None)
        );
        assert!(f.updates.iter().all(|u| u.position_error.is_nan()));
        assert!(f.updates.last().unwrap().position_2sigma < 0.5);
    }
    let errors = final_errors(&run, truth[STEPS - 1].pose);
    println!("CARMEN copy, final errors against the truth file: {errors:?}");
    assert!(errors.iter().all(|&e| e < 0.15), "{errors:?}");

    // The same log rounded in memory as the CARMEN text holds it (ranges to the
    // millimetre, poses and times to 1e-6) replays to the same particles.
    let mut rounded = log.clone();
    let round = |v: f64, digits: i32| format!("{v:.*}", digits as usize).parse::<f64>().unwrap();
    for s in &mut rounded.scans {
        for r in &mut s.scan.ranges {
            *r = round(*r, 3);
        }
        s.odometry = Pose2::new(
            round(s.odometry.x, 6),
            round(s.odometry.y, 6),
            round(s.odometry.theta, 6),
        );
        s.timestamp = round(s.timestamp, 6);
    }
    let from_memory = replay(log_input(&rounded, "rounded"), InitMode::Global);
    assert_eq!(particles(&run), particles(&from_memory));
}

/// Tracking from the bag's first true pose, and from the CARMEN copy's first
/// odometry pose (a simulated robot's odometry starts where it stands): the
/// same place, so both track.
#[test]
fn tracking_starts_at_the_truth_or_at_the_first_odometry() {
    let (log, truth, input) = recorded_bag();
    let run = replay(input, InitMode::Tracking);
    for f in run.filters() {
        assert_eq!(f.summary().converged_tick, Some(0), "{}", f.name);
    }
    let input = log_input(&log, "run.clf");
    let grid = BuiltinMap::Maze.load().unwrap();
    let run = MclRun::from_log(scenario(InitMode::Tracking), grid, input.clone()).unwrap();
    assert!(
        run.notes()
            .iter()
            .any(|n| n.contains("tracking starts around its first odometry pose"))
    );
    let run = replay(input, InitMode::Tracking);
    let errors = final_errors(&run, truth[STEPS - 1].pose);
    assert!(errors.iter().all(|&e| e < 0.15), "{errors:?}");
}

#[test]
fn a_log_that_does_not_fit_the_map_says_so() {
    let (log, truth) = recorded_run();
    let office = BuiltinMap::Office.load().unwrap();
    // With truth: the maze's poses are not the office's free space.
    let mut input = log_input(&log, "run");
    input.truth = Some(truth.iter().map(|t| t.pose).collect());
    let notes = log_notes(&office, &input);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(
        notes[0]
            .ends_with("true poses are outside the map's free space: was it recorded in this map?"),
        "{}",
        notes[0]
    );
    assert!(log_notes(&BuiltinMap::Maze.load().unwrap(), &input).is_empty());
    // Without truth: an odometry path twenty times the maze's size.
    let mut input = log_input(&log, "run");
    assert!(log_notes(&BuiltinMap::Maze.load().unwrap(), &input).is_empty());
    for s in &mut input.scans {
        s.odometry.x *= 20.0;
        s.odometry.y *= 20.0;
    }
    let notes = log_notes(&BuiltinMap::Maze.load().unwrap(), &input);
    assert!(
        notes[0].contains("its scans fall outside this map"),
        "{notes:?}"
    );
    // A truth of the wrong length is left out, with a note.
    let mut input = log_input(&log, "run");
    input.truth = Some(vec![Pose2::default(); 3]);
    let run = MclRun::from_log(
        scenario(InitMode::Global),
        BuiltinMap::Maze.load().unwrap(),
        input,
    )
    .unwrap();
    assert!(!run.has_truth());
    assert!(run.notes()[0].starts_with("the log's truth has 3 poses for 400 scans"));
    // Scans whose odometry is not a number are left out, with a note.
    let mut input = log_input(&log, "run");
    input.scans[7].odometry.x = f64::NAN;
    input.scans[9].odometry.theta = f64::INFINITY;
    let run = MclRun::from_log(
        scenario(InitMode::Global),
        BuiltinMap::Maze.load().unwrap(),
        input,
    )
    .unwrap();
    assert_eq!(run.log_progress(), Some((0, 398)));
    assert!(
        run.notes()
            .contains(&"2 scans whose odometry pose is not a number were left out".to_owned()),
        "{:?}",
        run.notes()
    );
    // An empty log is refused; a kidnap of a recorded robot too.
    let e =
        MclRun::from_log(scenario(InitMode::Global), office, MappingInput::default()).unwrap_err();
    assert_eq!(e, MclRunError::EmptyLog);
}

#[test]
fn a_recorded_robot_is_not_kidnapped() {
    let (log, _) = recorded_run();
    let grid = BuiltinMap::Maze.load().unwrap();
    let mut run =
        MclRun::from_log(scenario(InitMode::Global), grid, log_input(&log, "run")).unwrap();
    run.run_ticks(5);
    let odom = run.odometry();
    assert!(run.kidnap_to(Pose2::new(1.0, 1.0, 0.0)).is_err());
    run.kidnap_random();
    assert_eq!(run.kidnap_tick(), None);
    assert_eq!(run.odometry(), odom);
    assert_eq!(run.log_progress(), Some((5, STEPS)));
    assert!(
        (run.tick_time(4) - 0.4).abs() < 1e-9,
        "{}",
        run.tick_time(4)
    );
}
