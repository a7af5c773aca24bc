//! Assignments end to end: the built-in ones read, each student's variant, the
//! inputs handed out read back to the very numbers the reference estimators got,
//! and the grades (dead reckoning and raw odometry fail, the reference filters'
//! exported trajectories pass), with the refusals an instructor or a student meets.
#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use slamlab_core::belief::PoseBelief;
use slamlab_core::kalman::{EkfSlam, LandmarkSlam};
use slamlab_core::range_bearing::RangeBearing;
use slamlab_core::{Control, Pose2};
use slamlab_sim::assignments::{self, builtin, prepare};
use slamlab_sim::coursework::landmarks::LandmarkRun;
use slamlab_sim::coursework::{CourseworkError, Grade, Prepared, Variant, apply_params};
use slamlab_sim::io::laser_log::LaserLog;
use slamlab_sim::io::ros_map::load_map;
use slamlab_sim::io::trajectory::{read_trajectory, write_tum};
use slamlab_sim::kidnap::MclScenario;
use slamlab_sim::kidnap::assignment::reference_mcl;
use slamlab_sim::world::landmark_scenario::LandmarkScenario;

/// The students every grading test runs: their variants are 1,000 to 1,200
/// steps long, each with its own noise.
const STUDENTS: [&str; 6] = [
    "ada@uni.edu",
    "alan@uni.edu",
    "grace@uni.edu",
    "edsger@uni.edu",
    "barbara@uni.edu",
    "s0123456",
];

fn text(p: &Prepared, path: &str) -> String {
    String::from_utf8(p.input_files(false).get(path).unwrap().to_vec()).unwrap()
}

/// The reference named `name`, written as a TUM file.
fn reference_tum(p: &Prepared, name: &str) -> Vec<u8> {
    let (_, t) = p
        .references()
        .unwrap()
        .iter()
        .find(|(n, _)| n == name)
        .unwrap();
    write_tum(t).into_bytes()
}

#[test]
fn the_built_in_assignments_read_and_name_their_lessons() {
    assert_eq!(
        assignments::builtin_names(),
        [
            "ekf-slam",
            "mcl",
            "pose-graph",
            "grid-mapping",
            "icp",
            "two-view",
            "fusion"
        ]
    );
    let ekf = builtin("ekf-slam").unwrap();
    assert_eq!(
        (ekf.lesson.as_str(), ekf.max_score(), ekf.pass_score()),
        ("landmark-slam", 100.0, 70.0)
    );
    let mcl = builtin("mcl").unwrap();
    assert_eq!(
        (mcl.lesson.as_str(), mcl.max_score(), mcl.pass_score()),
        ("kidnap", 100.0, 70.0)
    );
    let err = builtin("ekf_slam").unwrap_err().to_string();
    assert!(
        err.contains("ekf_slam") && err.contains("ekf-slam, mcl"),
        "{err}"
    );
}

#[test]
fn dead_reckoning_fails_ekf_slam_and_the_reference_ekf_passes() {
    let a = builtin("ekf-slam").unwrap();
    for student in STUDENTS {
        let p = prepare(&a, student).unwrap();
        let ekf = p.grade("ekf.tum", &reference_tum(&p, "ekf")).unwrap();
        let dr = p
            .grade("dr.tum", &reference_tum(&p, "dead-reckoning"))
            .unwrap();
        assert!(ekf.pass && ekf.criteria[0].pass, "{student}: {ekf:#?}");
        assert!(!dr.pass && !dr.criteria[0].pass, "{student}: {dr:#?}");
        // The reference values beside the student's are the same numbers.
        let ate = ekf.criteria[0].value.unwrap();
        assert_eq!(ekf.criteria[0].references[0].value, Some(ate));
        assert_eq!(ekf.criteria[0].references[0].name, "ekf");
        assert_eq!(dr.criteria[0].references[1].value, dr.criteria[0].value);
        assert!(ate < 0.5 && dr.criteria[0].value.unwrap() > 0.5);
    }
}

#[test]
fn raw_odometry_fails_mcl_and_the_reference_mcl_passes() {
    let a = builtin("mcl").unwrap();
    for student in STUDENTS {
        let p = prepare(&a, student).unwrap();
        let mcl = p.grade("mcl.tum", &reference_tum(&p, "mcl")).unwrap();
        let odom = p.grade("odom.tum", &reference_tum(&p, "odometry")).unwrap();
        assert!(mcl.pass && mcl.criteria[0].pass, "{student}: {mcl:#?}");
        assert!(!odom.pass && !odom.criteria[0].pass, "{student}: {odom:#?}");
        assert_eq!(mcl.score, 100.0, "{student}");
    }
}

#[test]
fn a_student_always_gets_the_same_bytes_and_two_students_different_ones() {
    for name in assignments::builtin_names() {
        let a = builtin(name).unwrap();
        let ada = prepare(&a, "ada@uni.edu").unwrap();
        let again = prepare(&a, " ADA@uni.edu").unwrap();
        let alan = prepare(&a, "alan@uni.edu").unwrap();
        assert_eq!(ada.variant.seed, again.variant.seed);
        assert_ne!(ada.variant.seed, alan.variant.seed);
        // The README names the student as given; every data file is identical.
        let data = |p: &Prepared| {
            p.input_files(true)
                .files
                .into_iter()
                .filter(|(path, _)| path != "README.txt")
                .collect::<Vec<_>>()
        };
        assert_eq!(data(&ada), data(&again), "{name}");
        assert_eq!(
            ada.zip(false).unwrap(),
            prepare(&a, "ada@uni.edu").unwrap().zip(false).unwrap()
        );
        let (fa, fb) = (ada.input_files(false), alan.input_files(false));
        let differing = fa
            .files
            .iter()
            .filter(|(path, bytes)| fb.get(path) != Some(bytes.as_slice()))
            .count();
        // The README and every data file (a pose graph has one: problem.g2o;
        // two views one: matches.csv, the camera is every student's).
        let data_files = if ["pose-graph", "two-view"].contains(&name) {
            2
        } else {
            3
        };
        assert!(
            differing >= data_files,
            "{name}: only {differing} files differ"
        );
        assert!(!fa.paths().iter().any(|p| p.starts_with("answers/")));
        let answers = ada.input_files(true);
        assert!(
            answers.get("answers/truth.tum").is_some()
                || answers.get("answers/relative_pose.txt").is_some(),
            "{name}"
        );
    }
}

#[test]
fn another_students_estimate_is_refused_and_says_so() {
    let a = builtin("ekf-slam").unwrap();
    let ada = prepare(&a, "ada@uni.edu").unwrap();
    let alan = prepare(&a, "alan@uni.edu").unwrap();
    assert_ne!(ada.steps, alan.steps);
    let err = ada
        .grade("alans.tum", &reference_tum(&alan, "ekf"))
        .unwrap_err();
    assert!(matches!(err, CourseworkError::OtherVariant(_)), "{err:?}");
    let message = err.to_string();
    assert!(
        message.starts_with("alans.tum: ") && message.contains("variant"),
        "{message}"
    );
    // Nonsense and an empty file are refused with the file's name.
    for bytes in [&b"hello world\n"[..], b""] {
        let err = ada.grade("bad.tum", bytes).unwrap_err().to_string();
        assert!(err.starts_with("bad.tum"), "{err}");
    }
}

#[test]
fn the_answers_hold_the_truth() {
    let a = builtin("mcl").unwrap();
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let files = p.input_files(true);
    let truth = read_trajectory("truth.tum", files.get("answers/truth.tum").unwrap()).unwrap();
    let graded = p
        .grade("truth.tum", files.get("answers/truth.tum").unwrap())
        .unwrap();
    assert_eq!(truth.trajectory.len(), p.truth().len());
    assert!(graded.criteria[0].value.unwrap() < 1e-6, "{graded:#?}");
}

fn numbers(line: &str, sep: char) -> Vec<f64> {
    line.split(sep)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect()
}

/// The velocity-model files read back give the reference EKF's run bit for bit,
/// and the Freiburg files the same odometry and measurements.
#[test]
fn the_landmark_files_read_back_to_the_same_run() {
    let a = builtin("ekf-slam").unwrap();
    let p = prepare(&a, "grace@uni.edu").unwrap();
    // The same run, made here, hands out the same bytes as the prepared one.
    let (mut scenario, refused) = apply_params::<LandmarkScenario>(&a);
    assert!(refused.is_empty(), "{refused:?}");
    scenario.seed = Variant::new("ekf-slam", "grace@uni.edu").seed;
    let run = LandmarkRun::simulate(&scenario, p.steps);
    assert_eq!(
        run.files(true, true, "", false).files[1..],
        p.input_files(false).files[1..]
    );

    let start = numbers(text(&p, "start_pose.txt").trim(), ' ');
    let start = Pose2::new(start[0], start[1], start[2]);
    let controls: Vec<Vec<f64>> = text(&p, "controls.csv")
        .lines()
        .skip(1)
        .map(|l| numbers(l, ','))
        .collect();
    let measurements: Vec<Vec<f64>> = text(&p, "measurements.csv")
        .lines()
        .skip(1)
        .map(|l| numbers(l, ','))
        .collect();
    assert_eq!(controls.len() as u64, p.steps);
    let mut ekf = EkfSlam::new(scenario.filter_config(), start).unwrap();
    let mut path = vec![ekf.robot_pose()];
    let dt = scenario.dt;
    let mut next = 0;
    for c in &controls {
        let _ = ekf.predict(&Control { v: c[1], w: c[2] }, dt);
        while next < measurements.len() && measurements[next][0] == c[0] {
            let m = &measurements[next];
            let _ = ekf.update(
                m[1] as usize - 1,
                &RangeBearing {
                    range: m[2],
                    bearing: m[3],
                },
            );
            next += 1;
        }
        path.push(ekf.robot_pose());
    }
    assert_eq!(next, measurements.len());
    let (_, reference) = &p.references().unwrap()[0];
    assert_eq!(path.len(), reference.len());
    for (mine, theirs) in path.iter().zip(reference.poses()) {
        assert_eq!(
            [mine.x.to_bits(), mine.y.to_bits(), mine.theta.to_bits()],
            [
                theirs.x.to_bits(),
                theirs.y.to_bits(),
                theirs.theta.to_bits()
            ]
        );
    }

    // sensor_data.dat: the same readings as the run's, to the bit, block by block.
    let readings = run.odometry_readings();
    let mut k = 0;
    let mut sensor = 0;
    for line in text(&p, "sensor_data.dat").lines() {
        let fields: Vec<&str> = line.split(' ').collect();
        let values = numbers(&fields[1..].join(" "), ' ');
        match fields[0] {
            "ODOMETRY" => {
                assert_eq!(values.as_slice(), readings[k].as_slice());
                k += 1;
            }
            "SENSOR" => {
                let m = &measurements[sensor];
                assert_eq!(values.as_slice(), &m[1..]);
                sensor += 1;
            }
            other => panic!("line {other}"),
        }
    }
    assert_eq!((k, sensor), (readings.len(), measurements.len()));
    // world.dat: the true landmarks, ids from 1.
    let world: Vec<Vec<f64>> = text(&p, "world.dat")
        .lines()
        .map(|l| numbers(l, ' '))
        .collect();
    assert_eq!(world.len(), run.landmarks.len());
    for (row, (id, position)) in world.iter().zip(&run.landmarks) {
        assert_eq!(
            row.as_slice(),
            &[(*id + 1) as f64, position[0], position[1]]
        );
    }
}

/// The ROS map and the CARMEN log handed out give the reference MCL's run bit
/// for bit.
#[test]
fn the_map_and_log_read_back_to_the_same_mcl_run() {
    let a = builtin("mcl").unwrap();
    let p = prepare(&a, "alan@uni.edu").unwrap();
    let files = p.input_files(false);
    let log = LaserLog::from_bytes(files.get("robot.log").unwrap()).unwrap();
    let yaml = std::str::from_utf8(files.get("map.yaml").unwrap()).unwrap();
    let (grid, _) = load_map(yaml, files.get("map.pgm").unwrap()).unwrap();
    let start = numbers(text(&p, "start_pose.txt").trim(), ' ');
    let (mut scenario, _) = apply_params::<MclScenario>(&a);
    scenario.seed = p.variant.seed;
    let mine = reference_mcl(
        &scenario,
        grid,
        &log,
        Pose2::new(start[0], start[1], start[2]),
    )
    .unwrap();
    let (_, theirs) = &p.references().unwrap()[0];
    assert_eq!(mine.stamps(), theirs.stamps());
    assert_eq!(mine.poses(), theirs.poses());
    assert_eq!(log.scans.len() as u64, p.steps);
}

#[test]
fn assignment_files_are_refused_with_what_to_fix() {
    let good = coursework_json("ekf-slam");
    assert!(assignments::read("hw.json", good.as_bytes()).is_ok());
    let cases = [
        (
            r#""threshold": 0.5"#,
            r#""threshold": -0.5"#,
            "threshold -0.5",
        ),
        (r#""max_score": 100"#, r#""max_score": 90"#, "add up to 100"),
        (
            r#""metric": "ate_rmse""#,
            r#""metric": "cost_ratio""#,
            "no such metric",
        ),
        (
            r#""metric": "ate_rmse""#,
            r#""metric": "ate""#,
            "unknown variant",
        ),
        (r#""range-std": 0.2"#, r#""seed": 4"#, "seed"),
        (r#""range-std": 0.2"#, r#""range-std": -1"#, "range-std"),
        (
            r#""lesson": "landmark-slam""#,
            r#""lesson": "kidnap""#,
            "input format",
        ),
        (
            r#""lesson": "landmark-slam""#,
            r#""lesson": "pose-graph""#,
            "input format",
        ),
        (
            r#""lesson": "landmark-slam""#,
            r#""lesson": "cartographer""#,
            "has no assignments",
        ),
        (r#""id": "ekf-slam""#, r#""id": "hw 3""#, "id"),
        (r#""pass_score": 70"#, r#""pass_score": 170"#, "pass_score"),
        (r#""steps": 1000"#, r#""steps": 0"#, "steps"),
        (
            r#""alignment": "none""#,
            r#""alignment": "se3""#,
            "alignment",
        ),
        (r#""title""#, r#""titel""#, "unknown field"),
    ];
    for (from, to, says) in cases {
        let bad = good.replacen(from, to, 1);
        assert_ne!(bad, good, "{from} is not in the built-in file");
        let err = assignments::read("hw.json", bad.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("hw.json: ") && err.contains(says),
            "{to}: {err}"
        );
    }
    let huge = vec![b' '; 300 * 1024];
    let err = assignments::read("big.json", &huge)
        .unwrap_err()
        .to_string();
    assert!(err.contains("big.json") && err.contains("bytes"), "{err}");
    // A pose-graph task of the instructor's reads; one with more poses than
    // the lesson's graph may have is refused.
    let graph = good
        .replacen(
            r#""lesson": "landmark-slam""#,
            r#""lesson": "pose-graph""#,
            1,
        )
        .replacen(
            r#""freiburg",
    "velocity-csv""#,
            r#""g2o""#,
            1,
        )
        .replacen(r#""format": "trajectory""#, r#""format": "g2o""#, 1)
        .replacen("final_position_error", "ate_max", 1)
        .replacen(
            r#""range-std": 0.2,
      "bearing-std-deg": 5"#,
            "",
            1,
        );
    assert!(assignments::read("graph.json", graph.as_bytes()).is_ok());
    let err = assignments::read(
        "graph.json",
        graph
            .replacen(r#""steps": 1000"#, r#""steps": 6000"#, 1)
            .as_bytes(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("a pose-graph assignment has 10 to 5000 poses"),
        "{err}"
    );
}

fn coursework_json(name: &str) -> String {
    slamlab_sim::coursework::BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap()
        .1
        .to_owned()
}

/// The numbers docs/assignments.md gives: the reference filters' and the naive
/// estimates' ATE RMSE over 60 students. `cargo test -p slamlab-sim --release
/// --test assignments -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement for the docs (60 students per assignment)"]
fn measure_the_references_over_sixty_students() {
    for (name, good, naive) in [
        ("ekf-slam", "ekf", "dead-reckoning"),
        ("mcl", "mcl", "odometry"),
    ] {
        let rows = over_sixty_students(name, |p| {
            (
                p.grade("ref.tum", &reference_tum(p, good)).unwrap(),
                p.grade("naive.tum", &reference_tum(p, naive)).unwrap(),
            )
        });
        eprintln!(
            "{name}: {good} ATE RMSE min/median/max {:.3?}, passes {}/60; {naive} {:.3?}, passes {}/60",
            spread(rows.iter().map(|(g, _)| value(g, 0))),
            rows.iter().filter(|(g, _)| g.pass).count(),
            spread(rows.iter().map(|(_, n)| value(n, 0))),
            rows.iter().filter(|(_, n)| n.pass).count(),
        );
    }
}

/// Sixty students' variants of the built-in assignment `name`, each with what
/// `measure` makes of it: the measurements docs/assignments.md gives.
fn over_sixty_students<T>(name: &str, measure: impl Fn(&Prepared) -> T) -> Vec<T> {
    let a = builtin(name).unwrap();
    (0..60)
        .map(|k| measure(&prepare(&a, &format!("student{k}@uni.edu")).unwrap()))
        .collect()
}

/// The student's value of a grade's criterion `k`.
fn value(grade: &Grade, k: usize) -> f64 {
    grade.criteria[k].value.unwrap()
}

/// The smallest, the median and the largest of `values`.
fn spread(values: impl IntoIterator<Item = f64>) -> (f64, f64, f64) {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2], v[v.len() - 1])
}

/// A pose-graph variant's file by its path in the download.
fn file(p: &Prepared, path: &str) -> Vec<u8> {
    p.input_files(true).get(path).unwrap().to_vec()
}

#[test]
fn the_initial_guess_fails_pose_graph_and_the_reference_solver_passes() {
    let a = builtin("pose-graph").unwrap();
    for student in &STUDENTS[..4] {
        let p = prepare(&a, student).unwrap();
        assert!((300..=400).contains(&p.steps), "{student}: {}", p.steps);
        let reference = p
            .grade("reference.g2o", &file(&p, "answers/reference.g2o"))
            .unwrap();
        let naive = p.grade("estimate.g2o", &file(&p, "problem.g2o")).unwrap();
        assert!(
            reference.pass && reference.score == 100.0,
            "{student}: {reference:#?}"
        );
        // The reference's cost is its own: the ratio is 1 to the last bits.
        let ratio = reference.criteria[0].value.unwrap();
        assert!((ratio - 1.0).abs() < 1e-12, "{student}: {ratio}");
        assert!(
            !naive.pass && !naive.criteria[0].pass,
            "{student}: {naive:#?}"
        );
        // The references beside the student's values are the same numbers.
        let naive_ratio = naive.criteria[0].value.unwrap();
        assert_eq!(naive.criteria[0].references[1].value, Some(naive_ratio));
        assert_eq!(
            naive.criteria[1].references[1].value,
            naive.criteria[1].value
        );
        assert_eq!(
            reference.criteria[1].references[0].value,
            reference.criteria[1].value
        );
    }
}

#[test]
fn another_students_graph_is_refused_and_a_broken_one_named() {
    let a = builtin("pose-graph").unwrap();
    let ada = prepare(&a, "ada@uni.edu").unwrap();
    let alan = prepare(&a, "alan@uni.edu").unwrap();
    let err = ada
        .grade("alans.g2o", &file(&alan, "answers/reference.g2o"))
        .unwrap_err();
    assert!(matches!(err, CourseworkError::OtherVariant(_)), "{err:?}");
    assert!(err.to_string().contains("alans.g2o"), "{err}");
    // A vertex left out: named.
    let text = String::from_utf8(file(&ada, "answers/reference.g2o")).unwrap();
    let without: String = text
        .lines()
        .filter(|l| !l.starts_with("VERTEX_SE2 7 "))
        .map(|l| format!("{l}\n"))
        .collect();
    let err = ada
        .grade("mine.g2o", without.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(err.contains("mine.g2o"), "{err}");
    for bytes in [&b"hello world\n"[..], b"", b"PK\x03\x04zip"] {
        let err = ada.grade("bad.g2o", bytes).unwrap_err().to_string();
        assert!(err.starts_with("bad.g2o"), "{err}");
    }
}

#[test]
#[ignore = "a measurement for the docs (60 students)"]
fn measure_the_pose_graph_references_over_sixty_students() {
    let rows = over_sixty_students("pose-graph", |p| {
        (
            p.grade("ref.g2o", &file(p, "answers/reference.g2o"))
                .unwrap(),
            p.grade("naive.g2o", &file(p, "problem.g2o")).unwrap(),
        )
    });
    eprintln!(
        "pose-graph: reference ATE RMSE min/median/max {:.3?}, passes {}/60; initial guess cost ratio {:.3?}, ATE {:.3?}, passes {}/60",
        spread(rows.iter().map(|(g, _)| value(g, 1))),
        rows.iter().filter(|(g, _)| g.pass).count(),
        spread(rows.iter().map(|(_, n)| value(n, 0))),
        spread(rows.iter().map(|(_, n)| value(n, 1))),
        rows.iter().filter(|(_, n)| n.pass).count(),
    );
}

/// A map handed in: `answers/<stem>.yaml` and its `.pgm`, zipped as a
/// student's `map.yaml` and `map.pgm`.
fn map_zip(p: &Prepared, stem: &str) -> Vec<u8> {
    let yaml = String::from_utf8(file(p, &format!("answers/{stem}.yaml")))
        .unwrap()
        .replace(&format!("{stem}.pgm"), "map.pgm");
    slamlab_sim::io::archive::write_zip(
        "hand-in",
        &[
            ("map.yaml".to_owned(), yaml.into_bytes()),
            (
                "map.pgm".to_owned(),
                file(p, &format!("answers/{stem}.pgm")),
            ),
        ],
    )
    .unwrap()
}

#[test]
fn an_all_free_map_fails_grid_mapping_and_the_known_poses_map_passes() {
    use slamlab_sim::io::map_archive::read_map_zip;
    let a = builtin("grid-mapping").unwrap();
    for student in &STUDENTS[..3] {
        let p = prepare(&a, student).unwrap();
        let reference = p.grade("reference.zip", &map_zip(&p, "reference")).unwrap();
        assert!(
            reference.pass && reference.score == 100.0,
            "{student}: {reference:#?}"
        );
        // Its values are the references' beside it.
        assert_eq!(
            reference.criteria[0].references[0].value,
            reference.criteria[0].value
        );
        // The true map agrees with itself everywhere and covers everything.
        let truth = p.grade("true.zip", &map_zip(&p, "true_map")).unwrap();
        assert_eq!(truth.criteria[0].value, Some(1.0));
        assert_eq!(truth.criteria[1].value, Some(1.0));
        // Every cell free: full coverage, the walls wrong.
        let (map, _) = read_map_zip("true.zip", &map_zip(&p, "true_map")).unwrap();
        let cells = vec![slamlab_core::grid::Cell::Free; map.width() * map.height()];
        let free = slamlab_core::grid::OccupancyGrid::new(
            map.width(),
            map.height(),
            map.resolution(),
            map.origin(),
            cells,
        )
        .unwrap();
        let zip = slamlab_sim::io::map_archive::write_map_zip(
            &free,
            "map",
            slamlab_sim::io::ros_map::ImageFormat::Pgm,
        )
        .unwrap();
        let naive = p.grade("free.zip", &zip).unwrap();
        assert!(
            !naive.pass && !naive.criteria[0].pass,
            "{student}: {naive:#?}"
        );
        assert_eq!(naive.criteria[1].value, Some(1.0));
        assert_eq!(
            naive.criteria[0].references[1].value,
            naive.criteria[0].value
        );
    }
    // A YAML alone, or text, is refused with the file's name.
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let err = p
        .grade("map.yaml", &file(&p, "answers/reference.yaml"))
        .unwrap_err();
    assert!(err.to_string().contains("map.yaml"), "{err}");
}

#[test]
#[ignore = "a measurement for the docs (60 students)"]
fn measure_the_grid_mapping_references_over_sixty_students() {
    let rows = over_sixty_students("grid-mapping", |p| {
        p.grade("ref.zip", &map_zip(p, "reference")).unwrap()
    });
    eprintln!(
        "grid-mapping: reference agreement min/median/max {:.4?}, coverage {:.4?}, passes {}/60; all free agreement {:.4?}",
        spread(rows.iter().map(|g| value(g, 0))),
        spread(rows.iter().map(|g| value(g, 1))),
        rows.iter().filter(|g| g.pass).count(),
        spread(
            rows.iter()
                .map(|g| g.criteria[0].references[1].value.unwrap())
        ),
    );
}

/// The relative pose of a reference (`icp`, `identity`) as a file.
fn relative_pose_file(p: &Prepared, name: &str) -> Vec<u8> {
    use slamlab_sim::mapping::icp_assignment::relative_pose_of;
    let (_, t) = p
        .references()
        .unwrap()
        .iter()
        .find(|(n, _)| n == name)
        .unwrap();
    slamlab_sim::io::relative_pose::write_relative_pose(&relative_pose_of(&t.poses()[1]))
        .into_bytes()
}

/// The true relative pose, handed back as answers/ gives it, passes both
/// relative-pose tasks with all but no error (criterion 1: ICP's translation
/// error, two views' translation direction).
#[test]
fn the_true_relative_pose_passes_icp_and_two_view() {
    let two_view_students = ["ada@uni.edu", "alan@uni.edu", "grace@uni.edu", "s0123456"];
    for (name, students, second_error) in [
        ("icp", &STUDENTS[..4], 1e-9),
        ("two-view", &two_view_students[..], 1e-5),
    ] {
        let a = builtin(name).unwrap();
        for student in students {
            let p = prepare(&a, student).unwrap();
            let truth = p
                .grade("truth.txt", &file(&p, "answers/relative_pose.txt"))
                .unwrap();
            assert!(truth.pass, "{name} {student}: {truth:#?}");
            assert!(truth.criteria[0].value.unwrap() < 1e-5, "{name}");
            assert!(truth.criteria[1].value.unwrap() < second_error, "{name}");
        }
    }
}

#[test]
fn the_odometry_fails_icp_and_the_reference_icp_passes() {
    let a = builtin("icp").unwrap();
    for student in &STUDENTS[..4] {
        let p = prepare(&a, student).unwrap();
        let icp = p.grade("icp.txt", &relative_pose_file(&p, "icp")).unwrap();
        assert!(icp.pass, "{student}: {icp:#?}");
        // The reference's value beside the student's: the same pose, written
        // and read back (17 digits).
        let (mine, reference) = (
            icp.criteria[1].value.unwrap(),
            icp.criteria[1].references[0].value.unwrap(),
        );
        assert!((mine - reference).abs() < 1e-9, "{mine} {reference}");
        let none = p
            .grade("none.txt", &relative_pose_file(&p, "odometry"))
            .unwrap();
        assert!(!none.pass, "{student}: {none:#?}");
    }
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let err = p.grade("bad.txt", b"1 2 3\n").unwrap_err().to_string();
    assert!(err.starts_with("bad.txt"), "{err}");
}

#[test]
#[ignore = "a measurement for the docs (60 students)"]
fn measure_the_icp_references_over_sixty_students() {
    let rows = over_sixty_students("icp", |p| {
        (
            p.grade("icp.txt", &relative_pose_file(p, "icp")).unwrap(),
            p.grade("none.txt", &relative_pose_file(p, "odometry"))
                .unwrap(),
        )
    });
    eprintln!(
        "icp: reference rotation error min/median/max {:.4?} deg, translation {:.4?} m, passes {}/60; odometry: rotation {:.3?} deg, translation {:.3?} m, passes {}/60",
        spread(rows.iter().map(|(g, _)| value(g, 0))),
        spread(rows.iter().map(|(g, _)| value(g, 1))),
        rows.iter().filter(|(g, _)| g.pass).count(),
        spread(rows.iter().map(|(_, n)| value(n, 0))),
        spread(rows.iter().map(|(_, n)| value(n, 1))),
        rows.iter().filter(|(_, n)| n.pass).count(),
    );
}

/// A fusion variant's reference `name`, written as a TUM file.
fn fusion_reference(p: &Prepared, name: &str) -> Vec<u8> {
    reference_tum(p, name)
}

/// The numbers docs/assignments.md gives for `fusion`: the reference EKF's and
/// dead reckoning's ATE RMSE and largest error over 60 students, and every
/// fusion mode's (the reference's mode is the assignment's first, absolute).
/// `cargo test -p slamlab-sim --release --test assignments -- --ignored
/// --nocapture measure_the_fusion`.
#[test]
#[ignore = "a measurement for the docs (60 students)"]
fn measure_the_fusion_references_over_sixty_students() {
    use slamlab_sim::fusion::assignment::FusionRun;
    use slamlab_sim::fusion::{FusionMode, ModeRun};
    use slamlab_sim::metrics::evaluate;
    let a = builtin("fusion").unwrap();
    let settings = slamlab_sim::coursework::grade::trajectory_settings(&a);
    let rows = over_sixty_students("fusion", |p| {
        let g = p
            .grade("ref.tum", &fusion_reference(p, "ekf-absolute"))
            .unwrap();
        let n = p
            .grade("naive.tum", &fusion_reference(p, "dead-reckoning"))
            .unwrap();
        // Every mode's ATE RMSE on the same drive.
        let (lesson, _) = apply_params::<slamlab_sim::fusion::params::FusionLessonScenario>(&a);
        let mut lesson = lesson;
        lesson.scenario.seed = p.variant.seed;
        let run = FusionRun::simulate(&lesson, p.steps).unwrap();
        let mut modes = [0.0; 4];
        for (i, mode) in FusionMode::ALL.into_iter().enumerate() {
            let mut scenario = run.lesson.scenario.clone();
            scenario.output_rate = 10.0;
            let mut r = ModeRun::new(&scenario, mode).unwrap();
            r.run_to_end(&run.log);
            let mut t = slamlab_sim::metrics::Trajectory::default();
            for s in r.samples() {
                t.push(s.t, s.estimate, None);
            }
            modes[i] = evaluate(&run.truth, &t, &settings)
                .unwrap()
                .ape
                .translation
                .rmse;
        }
        // The SLAM poses alone, each held until the next.
        let slam = run.slam_rows();
        let mut held = slamlab_sim::metrics::Trajectory::default();
        for &t in run.truth.stamps() {
            let k = slam.partition_point(|(s, _)| *s <= t + 1e-9).max(1) - 1;
            let v = &slam[k].1;
            held.push(t, Pose2::new(v[0], v[1], v[2]), None);
        }
        let e = evaluate(&run.truth, &held, &settings).unwrap();
        (g, n, modes, [e.ape.translation.rmse, e.ape.translation.max])
    });
    eprintln!(
        "fusion: ekf-absolute ATE RMSE {:.4?} m, max {:.4?} m, passes {}/60; dead reckoning ATE RMSE {:.3?} m, max {:.3?} m, passes {}/60",
        spread(rows.iter().map(|(g, ..)| value(g, 0))),
        spread(rows.iter().map(|(g, ..)| value(g, 1))),
        rows.iter().filter(|(g, ..)| g.pass).count(),
        spread(rows.iter().map(|(_, n, ..)| value(n, 0))),
        spread(rows.iter().map(|(_, n, ..)| value(n, 1))),
        rows.iter().filter(|(_, n, ..)| n.pass).count(),
    );
    eprintln!(
        "  the SLAM poses held: ATE RMSE {:.4?} m, max {:.4?} m",
        spread(rows.iter().map(|r| r.3[0])),
        spread(rows.iter().map(|r| r.3[1]))
    );
    for (i, mode) in FusionMode::ALL.into_iter().enumerate() {
        eprintln!(
            "  mode {}: ATE RMSE {:.4?} m",
            mode.name(),
            spread(rows.iter().map(|r| r.2[i]))
        );
    }
}

/// Every fusion student's drive, graded: the reference EKF (the lesson's,
/// `_differential`) passes with every point, dead reckoning (what the starter
/// writes) fails, and the references' values are the numbers beside the grade.
#[test]
fn dead_reckoning_fails_fusion_and_the_reference_ekf_passes() {
    let a = builtin("fusion").unwrap();
    assert_eq!((a.lesson.as_str(), a.pass_score()), ("fusion", 70.0));
    for student in STUDENTS {
        let p = prepare(&a, student).unwrap();
        let ekf = p
            .grade("ekf.tum", &reference_tum(&p, "ekf-absolute"))
            .unwrap();
        let dr = p
            .grade("dr.tum", &reference_tum(&p, "dead-reckoning"))
            .unwrap();
        assert!(ekf.pass && ekf.score == 100.0, "{student}: {ekf:#?}");
        assert!(!dr.pass && !dr.criteria[0].pass, "{student}: {dr:#?}");
        assert_eq!(
            ekf.criteria[0].references[0].value, ekf.criteria[0].value,
            "{student}"
        );
        assert_eq!(ekf.criteria[0].references[0].name, "ekf-absolute");
        assert_eq!(dr.criteria[0].references[1].value, dr.criteria[0].value);
        // One pose every 0.1 s from 0 to the end of the drive.
        let truth = p.truth();
        assert_eq!(truth.len() as u64, p.steps + 1, "{student}");
        assert_eq!(truth.span(), Some((0.0, p.steps as f64 / 10.0)));
        // The answers' truth scores zero.
        let files = p.input_files(true);
        let graded = p
            .grade("truth.tum", files.get("answers/truth.tum").unwrap())
            .unwrap();
        assert!(graded.criteria[0].value.unwrap() < 1e-6, "{graded:#?}");
    }
}

/// The fusion CSVs read back to the very readings the reference filter fused,
/// bit for bit, with the header naming the time first and every unit.
#[test]
fn the_fusion_files_read_back_to_the_drives_readings() {
    use slamlab_core::kalman::fusion::Reading;
    use slamlab_sim::fusion::{IMU, ODOMETRY, SLAM};
    let a = builtin("fusion").unwrap();
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let (lesson, _) = apply_params::<slamlab_sim::fusion::params::FusionLessonScenario>(&a);
    let mut lesson = lesson;
    lesson.scenario.seed = p.variant.seed;
    let run = slamlab_sim::fusion::assignment::FusionRun::simulate(&lesson, p.steps).unwrap();
    assert_eq!(run.truth.poses(), p.truth().poses());
    for (file, header, sensor) in [
        ("odometry.csv", "t_s,v_m_per_s,w_rad_per_s", ODOMETRY),
        (
            "imu.csv",
            "t_s,gyro_z_rad_per_s,accel_x_m_per_s2,accel_y_m_per_s2",
            IMU,
        ),
        ("slam_pose.csv", "t_s,x_m,y_m,theta_rad", SLAM),
    ] {
        let text = text(&p, file);
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(header), "{file}");
        let rows: Vec<Vec<f64>> = lines.map(|l| numbers(l, ',')).collect();
        let readings: Vec<Vec<f64>> = run
            .log
            .measurements
            .iter()
            .filter(|m| m.measurement.sensor == sensor)
            .map(|m| {
                let mut row = vec![m.measurement.stamp];
                match m.measurement.reading {
                    Reading::Twist { twist, .. } => row.extend([twist[0], twist[2]]),
                    Reading::Imu { values, .. } => row.extend(values.iter()),
                    Reading::Pose { pose, .. } => row.extend([pose.x, pose.y, pose.theta]),
                }
                row
            })
            .collect();
        assert_eq!(rows.len(), readings.len(), "{file}");
        let bits = |r: &[Vec<f64>]| -> Vec<Vec<u64>> {
            r.iter()
                .map(|v| v.iter().map(|x| x.to_bits()).collect())
                .collect()
        };
        assert_eq!(bits(&rows), bits(&readings), "{file}");
    }
    // 50 Hz odometry, 100 Hz IMU, 1 Hz SLAM over the drive.
    let seconds = p.steps as f64 / 10.0;
    for (file, rate) in [
        ("odometry.csv", 50.0),
        ("imu.csv", 100.0),
        ("slam_pose.csv", 1.0),
    ] {
        let rows = text(&p, file).lines().count() - 1;
        let expected = (seconds * rate + 1e-6).floor() + 1.0;
        assert!(
            (rows as f64 - expected).abs() <= 1.0,
            "{file}: {rows} rows, {expected} expected"
        );
    }
    let readme = text(&p, "README.txt");
    for needle in [
        "odometry.csv",
        "imu.csv",
        "slam_pose.csv",
        "world frame",
        "rad/s",
    ] {
        assert!(readme.contains(needle), "{needle}: {readme}");
    }
    // The dead reckoning the grade shows is the odometry integrated from the file.
    let odo: Vec<(f64, Vec<f64>)> = text(&p, "odometry.csv")
        .lines()
        .skip(1)
        .map(|l| {
            let v = numbers(l, ',');
            (v[0], v[1..].to_vec())
        })
        .collect();
    let dr = slamlab_sim::fusion::assignment::dead_reckoning(&odo, p.truth().stamps());
    assert_eq!(
        write_tum(&dr).into_bytes(),
        reference_tum(&p, "dead-reckoning")
    );
}

/// A fusion assignment's parameters the drive cannot honour are refused with
/// the reason.
#[test]
fn fusion_assignment_files_are_refused_with_what_to_fix() {
    let base = coursework_json("fusion");
    for (params, steps, needle) in [
        (r#"{"duration": 100}"#, 2400, "duration"),
        (r#"{"odom": 0}"#, 2400, "odom"),
        (r#"{"slam-latency": 0.5}"#, 2400, "slam-latency"),
        (r#"{"slam-source": "landmark-ekf"}"#, 2400, "slam-source"),
        (r#"{"imu-rate": "fast"}"#, 2400, "imu-rate"),
        ("{}", 50, "scenario.steps"),
    ] {
        let text = base
            .replace(
                r#""params": {
      "modes": "absolute,differential"
    }"#,
                &format!(r#""params": {params}"#),
            )
            .replace(r#""steps": 2400"#, &format!(r#""steps": {steps}"#));
        let err = assignments::read("hw.json", text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(needle) && err.contains("hw.json"),
            "{params}: {err}"
        );
    }
    // The lesson's own parameters are taken: a faster, noisier drive.
    let text = base.replace(
        r#""modes": "absolute,differential""#,
        r#""max-speed": 0.2, "slam-position-noise": 0.1, "imu": 0"#,
    );
    let a = assignments::read("hw.json", text.as_bytes()).unwrap();
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let files = p.input_files(false);
    assert!(files.get("imu.csv").is_none() && files.get("slam_pose.csv").is_some());
}
