//! The readers on the real data sets (row counts, first and last times, the
//! barcode table) and on hand-made files with every quirk that
//! `../shared/data/landmarks/README.md` lists, and every refusal named by file
//! and line.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // a failing test stops

use super::mrclam::Subject;
use super::*;
use std::io::Write;

/// `../shared/data/landmarks/<path>`, or `None` with a message when absent.
fn shared(path: &str) -> Option<std::path::PathBuf> {
    let Some(data) = slamlab_fuzz::shared_data() else {
        println!("skipped: ../shared/data is absent (or set SLAMLAB_SHARED_DATA)");
        return None;
    };
    let full = data.join("landmarks").join(path);
    if full.exists() {
        Some(full)
    } else {
        println!("skipped: ../shared/data/landmarks/{path} is absent");
        None
    }
}

/// A file in MRCLAM's layout: four `#` lines, tab-separated fields padded with
/// spaces, a trailing space.
fn mrclam_file(name: &str, header: &str, rows: &[&str]) -> DataFile {
    let mut text = format!(
        "# UTIAS Multi-Robot Cooperative Localization and Mapping Dataset\n\
         # produced by Keith Leung (keith.leung@robotics.utias.utoronto.ca) 2009\n\
         # {name} Data Fomat:\n# {header} \n"
    );
    for row in rows {
        let fields: Vec<String> = row.split_whitespace().map(|f| format!(" {f} ")).collect();
        text.push_str(&fields.join("\t"));
        text.push('\n');
    }
    DataFile::new(format!("MRCLAM_Dataset9/{name}"), text.into_bytes())
}

/// A small MRCLAM data set whose barcode table differs from Dataset 6's: robots 1
/// and 2, landmarks 6, 7 and 8.
fn small_mrclam() -> Vec<DataFile> {
    vec![
        mrclam_file(
            "Barcodes.dat",
            "Subject #    Barcode #",
            &["1 72", "2 5", "6 14", "7 90", "8 41"],
        ),
        mrclam_file(
            "Landmark_Groundtruth.dat",
            "Subject #    x [m]    y [m]    x std-dev [m]    y std-dev [m]",
            &[
                "6 1.0 2.0 0.0001 0.0002",
                "7 -1.5 0.5 0.0001 0.0001",
                "8 3.0 -2.0 0.00005 0.0003",
            ],
        ),
        mrclam_file(
            "Robot1_Odometry.dat",
            "Time [s]    forward velocity [m/s]    angular velocity[rad/s]",
            &[
                "1248444187.156 0.086 -0.398",
                "1248444187.166 0.086 -0.398",
                "1248444187.166 0.1 0.0",
                "1248444188.171 0.0 0.0",
            ],
        ),
        mrclam_file(
            "Robot1_Measurement.dat",
            "Time [s]    Subject #    range [m]    bearing [rad]",
            &[
                "1248444187.2 14 3.787 -0.257",
                "1248444187.2 5 2.5 0.1",
                "1248444187.2 43 1.0 0.0",
                "1248444187.9 90 6.758 -0.005",
            ],
        ),
        mrclam_file(
            "Robot1_Groundtruth.dat",
            "Time [s]    x [m]    y [m]    orientation [rad]",
            &[
                "1248444187.100 1.4 -3.8 2.2696",
                "1248444187.116 1.41 -3.81 2.2697",
                "1248444189.116 1.5 -3.9 2.3",
            ],
        ),
    ]
}

fn error_of(result: Result<LandmarkData, DataError>) -> DataError {
    match result {
        Ok(data) => panic!("accepted: {:?}", data.kind()),
        Err(e) => e,
    }
}

fn zip(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut writer = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in entries {
        writer.start_file(*name, options).unwrap();
        writer.write_all(bytes).unwrap();
    }
    writer.finish().unwrap().into_inner()
}

#[test]
fn mrclam_dataset6_reads_with_its_counts_times_and_barcodes() {
    let Some(path) = shared("mrclam/MRCLAM_Dataset6.zip") else {
        return;
    };
    let LandmarkData::Mrclam(data) = read_path(&path).unwrap() else {
        panic!("not MRCLAM");
    };
    assert_eq!(data.name, "MRCLAM_Dataset6");
    // Dataset 6's barcode table (subjects 1-5 robots, 6-20 landmarks).
    let table: Vec<(u32, u32)> = data.barcodes.iter().map(|(&b, &s)| (s, b)).collect();
    let mut by_subject = table.clone();
    by_subject.sort_unstable();
    assert_eq!(
        by_subject,
        [
            (1, 5),
            (2, 14),
            (3, 41),
            (4, 32),
            (5, 23),
            (6, 63),
            (7, 81),
            (8, 7),
            (9, 70),
            (10, 45),
            (11, 27),
            (12, 18),
            (13, 54),
            (14, 61),
            (15, 90),
            (16, 36),
            (17, 16),
            (18, 9),
            (19, 72),
            (20, 25)
        ]
    );
    assert_eq!(data.landmarks.len(), 15);
    assert_eq!(data.landmarks[0].subject, 6);
    assert_eq!(
        (data.landmarks[0].x, data.landmarks[0].y),
        (0.58831396, -4.28264845)
    );
    assert_eq!(data.subject(63), Subject::Landmark(6));
    assert_eq!(data.subject(41), Subject::Robot(3));
    assert_eq!(data.subject(43), Subject::Unknown);
    // (robot, odometry rows, first and last time, measurement rows, Vicon rows, Vicon's last time)
    let expected = [
        (
            1,
            61785,
            1248444187.156,
            1248445075.103,
            1942,
            49241,
            1248444946.976,
        ),
        (
            2,
            65005,
            1248444188.949,
            1248445075.102,
            4031,
            59705,
            1248445075.103,
        ),
        (
            3,
            61158,
            1248444187.886,
            1248445075.099,
            5627,
            56977,
            1248445075.103,
        ),
        (
            4,
            52916,
            1248444191.043,
            1248445075.086,
            2399,
            61714,
            1248445075.103,
        ),
        (
            5,
            60567,
            1248444189.327,
            1248445075.095,
            5378,
            57467,
            1248445075.103,
        ),
    ];
    assert_eq!(data.robots.len(), 5);
    for (robot, (n, odometry, first, last, measurements, vicon, vicon_last)) in
        data.robots.iter().zip(expected)
    {
        assert_eq!(robot.number, n);
        assert_eq!(robot.odometry.len(), odometry, "robot {n}");
        assert_eq!(robot.odometry[0].time, first, "robot {n}");
        assert_eq!(robot.odometry[odometry - 1].time, last, "robot {n}");
        assert_eq!(robot.measurements.len(), measurements, "robot {n}");
        assert_eq!(robot.groundtruth.len(), vicon, "robot {n}");
        assert_eq!(robot.groundtruth[vicon - 1].time, vicon_last, "robot {n}");
    }
    // Robot 1: its first measurement, and the unknown barcodes the README mentions.
    let r1 = &data.robots[0];
    assert_eq!(
        (r1.measurements[0].time, r1.measurements[0].barcode),
        (1248444189.599, 14)
    );
    let unknown: Vec<usize> = data
        .robots
        .iter()
        .map(|r| {
            r.measurements
                .iter()
                .filter(|m| data.subject(m.barcode) == Subject::Unknown)
                .count()
        })
        .collect();
    assert_eq!(unknown, [1, 0, 2, 3, 0]);
    // Robot 1's Vicon stops 128 s before its odometry does.
    let gap = r1.odometry.last().unwrap().time - r1.groundtruth.last().unwrap().time;
    assert!((gap - 128.127).abs() < 1e-3, "{gap}");
}

#[test]
fn freiburg_files_read_with_331_steps_and_1212_sensor_lines() {
    let Some(path) = shared("freiburg/sensor_data.dat") else {
        return;
    };
    let LandmarkData::Freiburg(data) = read_path(&path).unwrap() else {
        panic!("not Freiburg");
    };
    assert_eq!(data.steps.len(), 331);
    assert_eq!(data.sensor_count(), 1212);
    assert_eq!(data.world.len(), 9);
    assert_eq!(
        (data.world[0].id, data.world[0].x, data.world[0].y),
        (1, 2.0, 1.0)
    );
    let first = &data.steps[0];
    assert_eq!(first.odometry.rot1, 0.100692392654);
    assert_eq!(first.sensors.len(), 2);
    assert_eq!(first.sensors[0].id, 1);
    // The quirks the course's code accepts: one negative range, bearings beyond ±π.
    assert_eq!(data.negative_ranges, 1);
    assert!(data.bearings_beyond_pi > 0);
    let negative: Vec<f64> = data
        .steps
        .iter()
        .flat_map(|s| &s.sensors)
        .filter(|s| s.range < 0.0)
        .map(|s| s.range)
        .collect();
    assert_eq!(negative.len(), 1);
    assert!((negative[0] + 0.035).abs() < 5e-4, "{negative:?}");
}

#[test]
fn victoria_park_reads_its_inputs_scans_and_gps() {
    let Some(path) = shared("victoria_park") else {
        return;
    };
    let LandmarkData::VictoriaPark(data) = read_path(&path).unwrap() else {
        panic!("not Victoria Park");
    };
    assert_eq!(data.inputs.len(), 61945);
    assert_eq!(data.detection_count(), 52974);
    assert_eq!(data.scans.len(), 7230);
    assert_eq!(data.gps.len(), 4466);
    assert_eq!(data.inputs[0].time, 0.973);
    assert_eq!(data.scans[0].time, 0.852);
    assert_eq!(data.gps[0].time, 0.0);
    assert_eq!(data.scans[0].trees[0].range, 20.46202);
    assert!(
        data.scans
            .iter()
            .flat_map(|s| &s.trees)
            .all(|t| (0.0..=std::f64::consts::PI).contains(&t.bearing))
    );
}

#[test]
fn a_hand_made_mrclam_set_reads_through_its_own_barcode_table() {
    let LandmarkData::Mrclam(data) = read_landmark_data(small_mrclam()).unwrap() else {
        panic!("not MRCLAM");
    };
    assert_eq!(data.name, "MRCLAM_Dataset9");
    // This table is not Dataset 6's: barcode 14 is landmark 6 here, robot 2 there.
    assert_eq!(data.subject(14), Subject::Landmark(6));
    assert_eq!(data.subject(5), Subject::Robot(2));
    assert_eq!(data.subject(43), Subject::Unknown);
    let robot = data.robot(1).unwrap();
    assert!(data.robot(2).is_none(), "robot 2's files were not given");
    assert_eq!(robot.odometry.len(), 4);
    // Equal times are kept (one camera image; odometry rows that share a time).
    assert_eq!(robot.measurements.len(), 4);
    assert_eq!(robot.measurements[1].time, robot.measurements[0].time);
    assert_eq!(robot.groundtruth.len(), 3);
    assert_eq!(robot.groundtruth[0].pose.theta, 2.2696);
    assert_eq!(data.landmarks[2].y_std, 0.0003);
}

#[test]
fn an_mrclam_zip_with_a_folder_inside_reads_like_its_files() {
    let files = small_mrclam();
    let entries: Vec<(&str, &[u8])> = files
        .iter()
        .map(|f| (f.name.as_str(), f.bytes.as_slice()))
        .collect();
    let zipped = DataFile::new("MRCLAM_Dataset9.zip", zip(&entries));
    let from_zip = read_landmark_data(vec![zipped]).unwrap();
    let from_files = read_landmark_data(files).unwrap();
    assert_eq!(from_zip, from_files);
    // Without the folder, the zip's name names the set.
    let flat = zip(&[
        ("Barcodes.dat", &small_mrclam()[0].bytes),
        ("Landmark_Groundtruth.dat", &small_mrclam()[1].bytes),
        ("Robot1_Odometry.dat", &small_mrclam()[2].bytes),
        ("Robot1_Measurement.dat", &small_mrclam()[3].bytes),
    ]);
    let LandmarkData::Mrclam(data) =
        read_landmark_data(vec![DataFile::new("lab.zip", flat)]).unwrap()
    else {
        panic!("not MRCLAM");
    };
    assert_eq!(data.name, "lab");
    assert!(data.robots[0].groundtruth.is_empty(), "no Vicon file given");
}

#[test]
fn a_zip_without_the_expected_files_is_refused_by_name() {
    let other = zip(&[("notes/readme.txt", b"hello")]);
    let e = error_of(read_landmark_data(vec![DataFile::new("lab.zip", other)]));
    assert!(e.message.contains("no file of a landmark data set"), "{e}");
    assert!(e.to_string().contains("lab.zip/notes/readme.txt"), "{e}");
    // An MRCLAM zip missing a required file names it.
    let files = small_mrclam();
    let partial = zip(&[
        ("D/Barcodes.dat", &files[0].bytes),
        ("D/Robot1_Odometry.dat", &files[2].bytes),
        ("D/Robot1_Measurement.dat", &files[3].bytes),
    ]);
    let e = error_of(read_landmark_data(vec![DataFile::new("D.zip", partial)]));
    assert!(
        e.message.starts_with("Landmark_Groundtruth.dat is missing"),
        "{e}"
    );
    let no_measurements = zip(&[
        ("D/Barcodes.dat", &files[0].bytes),
        ("D/Landmark_Groundtruth.dat", &files[1].bytes),
        ("D/Robot1_Odometry.dat", &files[2].bytes),
    ]);
    let e = error_of(read_landmark_data(vec![DataFile::new(
        "D.zip",
        no_measurements,
    )]));
    assert!(
        e.message.starts_with("Robot1_Measurement.dat is missing"),
        "{e}"
    );
    // Not a zip at all, though it starts like one.
    let e = error_of(read_landmark_data(vec![DataFile::new(
        "broken.zip",
        b"PK\x03\x04 and then nothing".to_vec(),
    )]));
    assert_eq!(e.file, "broken.zip");
    assert!(e.message.contains("not a zip archive"), "{e}");
}

/// Replaces row `row` (0-based, after the four comment lines) of file `index` of
/// the small set.
fn with_row(index: usize, row: usize, text: &str) -> Vec<DataFile> {
    let mut files = small_mrclam();
    let content = String::from_utf8(files[index].bytes.clone()).unwrap();
    let mut lines: Vec<String> = content.lines().map(str::to_owned).collect();
    lines[4 + row] = text.to_owned();
    files[index].bytes = (lines.join("\n") + "\n").into_bytes();
    files
}

#[test]
fn bad_mrclam_files_are_refused_naming_the_file_and_the_line() {
    // A missing column.
    let e = error_of(read_landmark_data(with_row(3, 1, "1248444187.2\t5\t2.5")));
    assert_eq!(e.file, "MRCLAM_Dataset9/Robot1_Measurement.dat");
    assert_eq!(e.line, Some(6));
    assert!(e.message.contains("3 fields, expected 4"), "{e}");
    // Times that go back.
    let e = error_of(read_landmark_data(with_row(2, 2, "1248444187.100 0.1 0.0")));
    assert_eq!(e.file, "MRCLAM_Dataset9/Robot1_Odometry.dat");
    assert_eq!(e.line, Some(7));
    assert!(e.message.contains("goes back"), "{e}");
    let e = error_of(read_landmark_data(with_row(
        4,
        2,
        "1248444187.0 1.5 -3.9 2.3",
    )));
    assert_eq!(
        (e.file.as_str(), e.line),
        ("MRCLAM_Dataset9/Robot1_Groundtruth.dat", Some(7))
    );
    // Two subjects on one barcode, and one subject with two barcodes.
    let e = error_of(read_landmark_data(with_row(0, 4, "8 14")));
    assert_eq!(
        (e.file.as_str(), e.line),
        ("MRCLAM_Dataset9/Barcodes.dat", Some(9))
    );
    assert!(
        e.message
            .contains("barcode 14 is given to subject 8 and to subject 6 (line 7)"),
        "{e}"
    );
    let e = error_of(read_landmark_data(with_row(0, 4, "6 99")));
    assert!(
        e.message
            .contains("subject 6 has barcode 99 and barcode 14"),
        "{e}"
    );
    // A negative range.
    let e = error_of(read_landmark_data(with_row(
        3,
        3,
        "1248444187.9 90 -6.758 -0.005",
    )));
    assert_eq!(
        (e.file.as_str(), e.line),
        ("MRCLAM_Dataset9/Robot1_Measurement.dat", Some(8))
    );
    assert!(e.message.contains("negative"), "{e}");
    // Not a number, not finite, not a whole barcode, not text.
    let e = error_of(read_landmark_data(with_row(
        2,
        0,
        "1248444187.156 fast -0.398",
    )));
    assert!(
        e.to_string().ends_with("line 5: v 'fast' is not a number"),
        "{e}"
    );
    let e = error_of(read_landmark_data(with_row(
        2,
        0,
        "1248444187.156 NaN -0.398",
    )));
    assert!(e.message.contains("not a finite number"), "{e}");
    let e = error_of(read_landmark_data(with_row(
        3,
        0,
        "1248444187.2 14.5 3.787 -0.257",
    )));
    assert!(e.message.contains("not a whole number"), "{e}");
    let mut files = small_mrclam();
    files[2].bytes.extend_from_slice(b"1248444189.0 \xff 0.0\n");
    let e = error_of(read_landmark_data(files));
    assert_eq!(e.line, Some(9));
    assert!(e.message.contains("UTF-8"), "{e}");
    // A landmark without a barcode.
    let e = error_of(read_landmark_data(with_row(
        1,
        0,
        "21 1.0 2.0 0.0001 0.0002",
    )));
    assert!(e.message.contains("landmark 21 has no barcode"), "{e}");
}

#[test]
fn the_freiburg_quirks_are_accepted_and_its_errors_named() {
    let world = DataFile::new("world.dat", b"1 2 1\n2 0 4\n".to_vec());
    let sensors = DataFile::new(
        "sensor_data.dat",
        b"ODOMETRY 0.1 0.1 0.0\nSENSOR 1 1.9 0.37\nSENSOR 2 -0.035 3.1500\n\
          ODOMETRY 0.1 0.1 -0.0002\nODOMETRY 0 0 0\nSENSOR 2 3.9 -3.1420\n"
            .to_vec(),
    );
    let LandmarkData::Freiburg(data) =
        read_landmark_data(vec![world.clone(), sensors.clone()]).unwrap()
    else {
        panic!("not Freiburg");
    };
    assert_eq!(data.steps.len(), 3);
    assert_eq!(data.sensor_count(), 3);
    assert_eq!(data.steps[1].sensors.len(), 0, "a step without sightings");
    assert_eq!((data.negative_ranges, data.bearings_beyond_pi), (1, 2));
    assert_eq!(data.steps[2].line, 5);
    // Without world.dat: no true landmarks.
    let LandmarkData::Freiburg(alone) = read_landmark_data(vec![sensors]).unwrap() else {
        panic!("not Freiburg");
    };
    assert!(alone.world.is_empty());

    let bad = |text: &[u8]| {
        error_of(read_landmark_data(vec![
            world.clone(),
            DataFile::new("sensor_data.dat", text.to_vec()),
        ]))
    };
    let e = bad(b"SENSOR 1 1.9 0.37\n");
    assert_eq!(e.line, Some(1));
    assert!(e.message.contains("before the first ODOMETRY"), "{e}");
    let e = bad(b"ODOMETRY 0.1 0.1 0.0\nSENSOR 1 1.9\n");
    assert_eq!(
        e.to_string(),
        "sensor_data.dat, line 2: SENSOR has 2 numbers, expected 3: id, range, bearing"
    );
    let e = bad(b"ODOMETRY 0.1 0.1 0.0\nLASER 1 1.9 0.3\n");
    assert!(e.message.contains("'LASER' is not a record"), "{e}");
    let e = error_of(read_landmark_data(vec![
        DataFile::new("world.dat", b"1 2 1\n1 0 4\n".to_vec()),
        DataFile::new("sensor_data.dat", b"ODOMETRY 0 0 0\n".to_vec()),
    ]));
    assert_eq!((e.file.as_str(), e.line), ("world.dat", Some(2)));
    let e = error_of(read_landmark_data(vec![world]));
    assert!(e.message.starts_with("sensor_data.dat is missing"), "{e}");
}

#[test]
fn victoria_park_scans_group_by_time_and_bad_rows_are_named() {
    let inputs = DataFile::new(
        "inputs.dat",
        b"     0.973      0.000    -0.0035\n     0.998      1.500    -0.0042\n".to_vec(),
    );
    let measurements = DataFile::new(
        "measurements.dat",
        b"     0.852   20.46202    0.88575    0.35404\n     0.852   29.59859    1.02102    0.25717\n\
              1.052    9.5         3.1    0.2\n"
            .to_vec(),
    );
    let gps = DataFile::new("gps.dat", b"     0.000     -2.023     -1.923\n".to_vec());
    let LandmarkData::VictoriaPark(data) =
        read_landmark_data(vec![inputs.clone(), measurements.clone(), gps.clone()]).unwrap()
    else {
        panic!("not Victoria Park");
    };
    assert_eq!(data.scans.len(), 2);
    assert_eq!(data.scans[0].trees.len(), 2);
    assert_eq!(data.scans[1].trees[0].bearing, 3.1);
    assert_eq!(data.gps.len(), 1);
    let e = error_of(read_landmark_data(vec![
        inputs.clone(),
        DataFile::new("measurements.dat", b"0.852 -1.0 0.5 0.3\n".to_vec()),
    ]));
    assert_eq!(
        e.to_string(),
        "measurements.dat, line 1: range -1 m is negative"
    );
    let e = error_of(read_landmark_data(vec![
        DataFile::new("inputs.dat", b"1.0 0 0\n0.5 0 0\n".to_vec()),
        measurements.clone(),
    ]));
    assert_eq!((e.file.as_str(), e.line), ("inputs.dat", Some(2)));
    let e = error_of(read_landmark_data(vec![inputs.clone(), gps.clone()]));
    assert!(e.message.starts_with("measurements.dat is missing"), "{e}");
    // Files of two data sets at once.
    let e = error_of(read_landmark_data(vec![
        inputs,
        measurements,
        DataFile::new("world.dat", b"1 2 1\n".to_vec()),
    ]));
    assert!(e.message.contains("give one data set at a time"), "{e}");
}

#[test]
fn files_over_the_cap_are_refused_before_they_are_parsed() {
    // A 1 GiB file on disk (sparse: it takes no space) is refused by its size.
    let dir = std::env::temp_dir().join(format!("slamlab-landmark-data-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let big = dir.join("Robot1_Odometry.dat");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(1 << 30)
        .unwrap();
    let e = error_of(read_path(&big));
    assert!(e.file.ends_with("Robot1_Odometry.dat"), "{e}");
    assert!(e.message.contains("1073741824 bytes, over the cap"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
    // In memory (a dropped file): refused before it is decoded.
    let mut files = small_mrclam();
    files[2].bytes = vec![b' '; MAX_FILE_BYTES + 1];
    let e = error_of(read_landmark_data(files));
    assert_eq!(e.file, "MRCLAM_Dataset9/Robot1_Odometry.dat");
    assert!(e.message.contains("over the cap"), "{e}");
}
