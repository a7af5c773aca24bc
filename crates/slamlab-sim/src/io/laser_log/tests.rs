use super::*;
use std::f64::consts::{FRAC_PI_2, PI};
use std::io::Write as _;

/// Every record type the reader knows, and some it skips.
const EVERY_RECORD: &str = "\
# message_name [message contents] ipc_timestamp ipc_hostname logger_timestamp
# a comment

PARAM robot_frontlaser_offset 0.0 nohost 0
PARAM robot_comment two words 1.5 nohost 0.1
ODOM 0.000000 0.000000 -0.002458 0.000000 0.000000 0.000000 100.000000 nohost 0.000000
FLASER 4 1.07 2.5 81.83 0.50 0.1 0.2 0.3 0.1 0.2 0.3 100.100000 nohost 0.1
RLASER 2 3.0 4.0 1.0 2.0 3.1 0.0 0.0 3.0 100.150000 nohost 0.15
SYNC tag 100.2 nohost 0.2
TRUEPOS 1 2 3 1 2 3 100.3 nohost 0.3
ODOM 1.000000 2.000000 0.500000 0.300000 0.100000 0.000000 100.400000 nohost 0.4
ROBOTLASER1 0 -1.5 3.0 0.5 30.0 0.01 0 7 1 2 3 4 5 6 7 2 0.9 0.8 5.1 5.2 0.1 5.0 5.0 0.1 0.2 0.3 0.4 0.5 0 100.500000 nohost 0.5
TRUEPOS 1 2 3 1 2 3 100.6 nohost 0.6
NMEA-GGA 1 2 3 100.7 nohost 0.7
";

pub(crate) fn read(text: &str) -> Result<LaserLog, LogError> {
    LaserLog::from_bytes(text.as_bytes())
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn bzip2(bytes: &[u8]) -> Vec<u8> {
    let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

#[test]
fn every_record_type_is_read_counted_or_skipped() {
    let log = read(EVERY_RECORD).unwrap();
    assert_eq!(log.comments, 2);
    assert_eq!(log.scans.len(), 3);
    assert_eq!(log.odometry.len(), 2);
    assert_eq!(log.params.len(), 2);
    assert_eq!(log.params["robot_frontlaser_offset"], "0.0");
    assert_eq!(log.params["robot_comment"], "two words");
    let skipped: Vec<(&str, usize)> = log.skipped.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    assert_eq!(skipped, [("NMEA-GGA", 1), ("SYNC", 1), ("TRUEPOS", 2)]);
    assert_eq!(log.compression, Some(Compression::Plain));

    // ODOM.
    let o = log.odometry[1];
    assert_eq!((o.pose.x, o.pose.y, o.pose.theta), (1.0, 2.0, 0.5));
    assert_eq!((o.tv, o.rv, o.timestamp), (0.3, 0.1, 100.4));

    // FLASER: 4 beams over 180°, 45° apart from -90°; 50 m default max range,
    // so 81.83 is "nothing within range".
    let f = &log.scans[0];
    assert_eq!(f.kind, LaserKind::Front);
    assert_eq!(f.line, 7);
    assert_eq!(f.timestamp, 100.1);
    assert_eq!(f.scan.ranges, [1.07, 2.5, 81.83, 0.5]);
    let expected = [-FRAC_PI_2, -PI / 4.0, 0.0, PI / 4.0];
    for (a, e) in f.scan.angles.iter().zip(expected) {
        assert!((a - e).abs() < 1e-15, "{a} vs {e}");
    }
    assert_eq!(f.scan.range_max, 50.0);
    assert!(f.scan.is_max_range(2) && f.scan.is_end_point(1));
    assert_eq!(f.odometry, Pose2::new(0.1, 0.2, 0.3));
    assert_eq!(f.laser_pose, None);

    // RLASER: same layout; its laser pose differs from the odometry.
    let r = &log.scans[1];
    assert_eq!(r.kind, LaserKind::Rear);
    assert_eq!(r.scan.angles, [-FRAC_PI_2, 0.0]);
    assert_eq!(r.laser_pose, Some(Pose2::new(1.0, 2.0, 3.1)));
    assert_eq!(r.odometry, Pose2::new(0.0, 0.0, 3.0));

    // ROBOTLASER1: its own angles (start -1.5, 0.5 apart) and max range; the
    // two remissions are skipped.
    let b = &log.scans[2];
    assert_eq!(b.kind, LaserKind::Robot);
    assert_eq!(b.scan.ranges, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    assert_eq!(b.scan.angles, [-1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5]);
    assert_eq!(b.scan.range_max, 30.0);
    assert_eq!(b.laser_pose, Some(Pose2::new(5.1, 5.2, 0.1)));
    assert_eq!(b.odometry, Pose2::new(5.0, 5.0, 0.1));
    assert_eq!(b.timestamp, 100.5);

    assert_eq!(log.beams(), Some(4));
    assert_eq!(log.time_span(), Some((100.1, 100.5)));
    let counts: Vec<_> = log.scan_counts().into_iter().collect();
    assert_eq!(counts, [("FLASER", 1), ("RLASER", 1), ("ROBOTLASER1", 1)]);
}

#[test]
fn params_set_the_flaser_layout() {
    let text = "\
PARAM laser_front_laser_fov 100 nohost 0
PARAM laser_front_laser_resolution 0.5 nohost 0
PARAM robot_front_laser_max 8.0 nohost 0
PARAM robot_rear_laser_fov 90 nohost 0
FLASER 3 1 2 3 0 0 0 0 0 0 1.0 nohost 0
RLASER 3 1 2 3 0 0 0 0 0 0 1.0 nohost 0
";
    let log = read(text).unwrap();
    let f = &log.scans[0].scan;
    let d = 1f64.to_radians();
    for (a, e) in f.angles.iter().zip([-50.0 * d, -49.5 * d, -49.0 * d]) {
        assert!((a - e).abs() < 1e-15);
    }
    assert_eq!(f.range_max, 8.0);
    // The rear laser: fov 90° over 3 beams (30° apart), default max range.
    let r = &log.scans[1].scan;
    for (a, e) in r.angles.iter().zip([-45.0 * d, -15.0 * d, 15.0 * d]) {
        assert!((a - e).abs() < 1e-15);
    }
    assert_eq!(r.range_max, DEFAULT_FLASER_MAX_RANGE);
    // A layout parameter that is not a positive number names its line.
    let bad = "PARAM laser_front_laser_fov -3 nohost 0\nFLASER 1 1 0 0 0 0 0 0 1 h 0\n";
    assert_eq!(
        read(bad),
        Err(LogError::BadParam {
            line: 1,
            name: "laser_front_laser_fov".into(),
            value: "-3".into()
        })
    );
}

#[test]
fn gzip_and_bzip2_are_detected_from_the_bytes_and_read_the_same() {
    let plain = read(EVERY_RECORD).unwrap();
    for (packed, kind) in [
        (gzip(EVERY_RECORD.as_bytes()), Compression::Gzip),
        (bzip2(EVERY_RECORD.as_bytes()), Compression::Bzip2),
    ] {
        let log = LaserLog::from_bytes(&packed).unwrap();
        assert_eq!(log.compression, Some(kind));
        assert_eq!(
            LaserLog {
                compression: Some(Compression::Plain),
                ..log
            },
            plain
        );
    }
    // Two gzip members (as `cat a.gz b.gz` makes) read as one text.
    let (a, b) = EVERY_RECORD.split_at(EVERY_RECORD.find("SYNC").unwrap());
    let mut two = gzip(a.as_bytes());
    two.extend(gzip(b.as_bytes()));
    let log = LaserLog::from_bytes(&two).unwrap();
    assert_eq!(log.scans.len(), 3);
    let mut two = bzip2(a.as_bytes());
    two.extend(bzip2(b.as_bytes()));
    assert_eq!(LaserLog::from_bytes(&two).unwrap().scans.len(), 3);
}

#[test]
fn truncated_or_corrupt_compressed_data_is_an_error() {
    for packed in [
        gzip(EVERY_RECORD.as_bytes()),
        bzip2(EVERY_RECORD.as_bytes()),
    ] {
        for cut in [packed.len() - 1, packed.len() / 2, 12] {
            let err = LaserLog::from_bytes(&packed[..cut]).unwrap_err();
            assert!(matches!(err, LogError::Corrupt { .. }), "cut {cut}: {err}");
        }
        let mut flipped = packed.clone();
        for b in &mut flipped[20..30] {
            *b ^= 0x5a;
        }
        let err = LaserLog::from_bytes(&flipped).unwrap_err();
        assert!(matches!(err, LogError::Corrupt { .. }), "{err}");
    }
    let xz = [0xfd, b'7', b'z', b'X', b'Z', 0, 1, 2];
    assert_eq!(
        LaserLog::from_bytes(&xz),
        Err(LogError::UnsupportedCompression("xz"))
    );
}

#[test]
fn size_caps_refuse_big_files_and_stop_a_zip_bomb() {
    let limits = LogLimits {
        max_input_bytes: 100,
        max_unpacked_bytes: 1 << 20,
    };
    let err = LaserLog::from_bytes_with_limits(EVERY_RECORD.as_bytes(), limits).unwrap_err();
    assert!(
        matches!(
            err,
            LogError::TooLarge {
                what: "the file",
                cap: 100,
                ..
            }
        ),
        "{err}"
    );
    // 8 MiB of zeros packs to a few kB; unpacking stops one byte past 1 MiB.
    let zeros = vec![b'0'; 8 << 20];
    let limits = LogLimits {
        max_input_bytes: MAX_INPUT_BYTES,
        max_unpacked_bytes: 1 << 20,
    };
    for packed in [gzip(&zeros), bzip2(&zeros)] {
        assert!(packed.len() < 64 << 10, "{}", packed.len());
        let err = LaserLog::from_bytes_with_limits(&packed, limits).unwrap_err();
        assert_eq!(
            err,
            LogError::TooLarge {
                what: "the unpacked log",
                bytes: (1 << 20) + 1,
                cap: 1 << 20
            }
        );
    }
    // Plain text over the unpacked cap.
    let limits = LogLimits {
        max_input_bytes: MAX_INPUT_BYTES,
        max_unpacked_bytes: 100,
    };
    let err = LaserLog::from_bytes_with_limits(EVERY_RECORD.as_bytes(), limits).unwrap_err();
    assert!(
        matches!(
            err,
            LogError::TooLarge {
                what: "the log",
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(
        check_input_size(MAX_INPUT_BYTES + 1, LogLimits::default()),
        Err(LogError::TooLarge {
            what: "the file",
            bytes: MAX_INPUT_BYTES + 1,
            cap: MAX_INPUT_BYTES
        })
    );
}

/// The line number and a fragment of the message of each malformed line.
#[test]
fn malformed_lines_are_named_by_line_number() {
    let good = "FLASER 2 1 2 0 0 0 0 0 0 5.0 h 0\n";
    let cases: [(&str, &str); 11] = [
        (
            "FLASER 3 1 2 0 0 0 0 0 0",
            "3 readings announced, so at least 10 fields must follow the count, but only 8 do",
        ),
        (
            "FLASER 3 1 2 0 0 0 0 0 0 5.0 h 0",
            "ipc_timestamp \"h\" is not a finite",
        ),
        ("FLASER two 1 2", "\"two\" is not a count"),
        (
            "FLASER 2 1 x 0 0 0 0 0 0 5.0 h 0",
            "reading \"x\" is not a number",
        ),
        (
            "FLASER 2 1 2 0 0 0 0 0",
            "at least 9 fields must follow the count, but only 7 do",
        ),
        ("ODOM 1 2 3 0 0", "missing accel (field 7)"),
        (
            "FLASER 2 1 2 0 0 0 0 0 0 NaN h 0",
            "ipc_timestamp \"NaN\" is not a finite number",
        ),
        ("FLASER 999999999 1", "over the limit"),
        (
            "ODOM 1 2 inf 0 0 0 5 h 0",
            "pose theta \"inf\" is not a finite number",
        ),
        (
            "ROBOTLASER1 0 -1 2 1 30 0.01 0 2 1 2 20 1 2 3 4 5 6 7 8 9 10 11 12 13",
            "20 remissions announced, so at least 32 fields must follow their count, but only 13 do",
        ),
        ("PARAM lonely", "expected PARAM name value"),
    ];
    for (bad, fragment) in cases {
        let text = format!("{good}# comment\n{bad}\n{good}");
        let err = read(&text).unwrap_err();
        assert!(
            matches!(err, LogError::Malformed { line: 3, .. }),
            "{bad}: {err}"
        );
        let message = err.to_string();
        assert!(message.starts_with("line 3: malformed "), "{message}");
        assert!(message.contains(fragment), "{bad}: {message}");
    }
    let not_text = [good.as_bytes(), b"FLASER 1 \xff\xfe\n"].concat();
    assert_eq!(
        LaserLog::from_bytes(&not_text),
        Err(LogError::NotText { line: 2 })
    );
}

#[test]
fn nan_and_negative_ranges_are_kept_as_unusable_beams_and_counted() {
    let text = "FLASER 4 1.5 nan -0.2 81.83 0 0 0 0 0 0 5.0 h 0\nFLASER 4 NaN 1 1 inf 0 0 0 0 0 0 5.1 h 0\n";
    let log = read(text).unwrap();
    assert_eq!(log.unusable_readings, 3);
    let s = &log.scans[0].scan;
    assert_eq!(s.ranges[0], 1.5);
    assert!(s.ranges[1].is_nan() && s.ranges[2].is_nan());
    assert_eq!(s.points().len(), 1);
    assert!(!s.is_end_point(2) && !s.is_max_range(2) && s.is_max_range(3));
    assert!(log.scans[1].scan.is_max_range(3));
}

#[test]
fn a_log_without_laser_records_or_with_changing_beam_counts_is_refused() {
    let text = "# header\nODOM 0 0 0 0 0 0 1 h 0\nPARAM a b 0 h 0\n";
    assert_eq!(read(text), Err(LogError::NoLaserRecord { lines: 4 }));
    assert_eq!(read(""), Err(LogError::NoLaserRecord { lines: 1 }));
    let text = "\
FLASER 2 1 2 0 0 0 0 0 0 5.0 h 0
RLASER 3 1 2 3 0 0 0 0 0 0 5.0 h 0
FLASER 2 1 2 0 0 0 0 0 0 5.1 h 0
ODOM 0 0 0 0 0 0 1 h 0
FLASER 3 1 2 3 0 0 0 0 0 0 5.2 h 0
";
    let err = read(text).unwrap_err();
    assert_eq!(
        err,
        LogError::BeamCountChanged {
            line: 5,
            record: "FLASER".into(),
            expected: 2,
            first_line: 1,
            found: 3
        }
    );
    assert!(
        err.to_string().starts_with("line 5: FLASER has 3 beams"),
        "{err}"
    );
}

#[test]
fn no_input_makes_the_reader_panic() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let base = [
        EVERY_RECORD.as_bytes().to_vec(),
        gzip(EVERY_RECORD.as_bytes()),
        bzip2(EVERY_RECORD.as_bytes()),
    ];
    let mut outcomes = [0usize; 2];
    for k in 0..600 {
        let mut bytes = base[k % 3].clone();
        for _ in 0..rng.random_range(1..6) {
            let i = rng.random_range(0..bytes.len());
            bytes[i] = rng.random();
        }
        if k % 7 == 0 {
            bytes.truncate(rng.random_range(0..bytes.len()));
        }
        outcomes[usize::from(LaserLog::from_bytes(&bytes).is_ok())] += 1;
    }
    // Both outcomes occur: the mutations reach the parser, not only the magic.
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
}

fn sample_log() -> LaserLog {
    let angles: Vec<f64> = (0..8).map(|k| -PI + k as f64 * PI / 4.0).collect();
    let mut log = LaserLog::default();
    log.params
        .insert("robot_frontlaser_offset".into(), "0.0".into());
    for k in 0..5 {
        let t = 1000.0 + k as f64 * 0.123_456_7;
        let odometry = Pose2::new(
            0.1 * k as f64,
            -0.033_333_3 * k as f64,
            0.4 * k as f64 - 1.0,
        );
        log.odometry.push(LogOdometry {
            timestamp: t - 0.01,
            pose: odometry,
            tv: 0.25,
            rv: -0.1,
        });
        log.scans.push(LogScan {
            timestamp: t,
            kind: LaserKind::Front,
            scan: Scan {
                angles: angles.clone(),
                ranges: (0..8).map(|b| 0.5 + 1.234_567 * (b + k) as f64).collect(),
                range_min: 0.0,
                range_max: 12.0,
            },
            odometry,
            laser_pose: (k == 2).then(|| Pose2::new(1.0, 2.0, 0.5)),
            line: 0,
        });
    }
    log.scans[3].scan.ranges[1] = 12.0;
    log.scans[4].scan.ranges[2] = f64::NAN;
    log
}

/// `a` equals `b` to the precision [`write_carmen`] prints.
pub(crate) fn assert_same_to_printed_precision(a: &LaserLog, b: &LaserLog) {
    assert_eq!(a.scans.len(), b.scans.len());
    assert_eq!(a.odometry.len(), b.odometry.len());
    let pose_close = |p: &Pose2, q: &Pose2| {
        (p.x - q.x).abs() <= 5e-7 && (p.y - q.y).abs() <= 5e-7 && (p.theta - q.theta).abs() <= 5e-7
    };
    for (s, r) in a.scans.iter().zip(&b.scans) {
        assert!((s.timestamp - r.timestamp).abs() <= 5e-7);
        assert!(pose_close(&s.odometry, &r.odometry));
        assert!(pose_close(&s.laser_pose(), &r.laser_pose()));
        assert_eq!(s.laser_pose.is_some(), r.laser_pose.is_some());
        assert_eq!(s.scan.range_max, r.scan.range_max);
        assert_eq!(s.scan.ranges.len(), r.scan.ranges.len());
        for (x, y) in s.scan.ranges.iter().zip(&r.scan.ranges) {
            assert!(
                x.is_nan() && y.is_nan() || (x - y).abs() <= 5e-4 + 1e-12,
                "{x} {y}"
            );
        }
        for (x, y) in s.scan.angles.iter().zip(&r.scan.angles) {
            assert!((x - y).abs() < 1e-10, "{x} {y}");
        }
    }
    for (o, p) in a.odometry.iter().zip(&b.odometry) {
        assert!((o.timestamp - p.timestamp).abs() <= 5e-7);
        assert!(pose_close(&o.pose, &p.pose));
        assert!((o.tv - p.tv).abs() <= 5e-7 && (o.rv - p.rv).abs() <= 5e-7);
    }
}

#[test]
fn written_logs_read_back_to_the_printed_precision() {
    let log = sample_log();
    let text = write_carmen(&log).unwrap();
    let back = read(&text).unwrap();
    assert_same_to_printed_precision(&log, &back);
    assert_eq!(back.unusable_readings, 1);
    assert_eq!(back.params["robot_frontlaser_offset"], "0.0");
    assert_eq!(back.params["robot_front_laser_max"], "12");
    assert!(back.scans[3].scan.is_max_range(1));
    // What was read is written again to the same text, and a third pass reads
    // the same numbers bit for bit.
    let again = write_carmen(&back).unwrap();
    assert_eq!(again, text);
    // (Debug text: NaN readings compare unequal as numbers.)
    assert_eq!(format!("{:?}", read(&again).unwrap()), format!("{back:?}"));
    // A hand-checked line.
    let line = text.lines().find(|l| l.starts_with("FLASER")).unwrap();
    assert_eq!(
        line,
        "FLASER 8 0.500 1.735 2.969 4.204 5.438 6.673 7.907 9.142 \
         0.000000 0.000000 -1.000000 0.000000 0.000000 -1.000000 1000.000000 slamlab 1000.000000"
    );
    // Scans that FLASER cannot describe are refused, not written wrong.
    let mut uneven = sample_log();
    uneven.scans[1].scan.angles[3] += 0.01;
    assert!(matches!(
        write_carmen(&uneven),
        Err(WriteError::UnevenLayout { index: 1, .. })
    ));
    assert_eq!(write_carmen(&LaserLog::default()), Err(WriteError::NoScans));
}

#[test]
fn truth_files_round_trip_and_name_bad_lines() {
    let poses = vec![
        TruePose {
            timestamp: 0.1,
            pose: Pose2::new(1.25, -3.5, 0.75),
        },
        TruePose {
            timestamp: 0.2,
            pose: Pose2::new(1.3, -3.45, -3.1),
        },
    ];
    let text = write_truth(&poses);
    assert_eq!(
        text.lines().nth(1),
        Some("0.100000 1.250000 -3.500000 0.750000")
    );
    assert_eq!(read_truth(&text).unwrap(), poses);
    assert_eq!(write_truth(&read_truth(&text).unwrap()), text);
    let bad = format!("{text}0.3 1 2\n");
    let err = read_truth(&bad).unwrap_err();
    assert!(
        matches!(err, TruthError::Malformed { line: 4, .. }),
        "{err}"
    );
    assert!(read_truth("0.1 1 2 nan\n").is_err());
    assert!(read_truth("0.1 1 2 3 4\n").is_err());
}

/// The Intel Research Lab log from `shared/data/laser` (beside the
/// repository, or in `$SLAMLAB_SHARED`), when present.
#[test]
fn the_intel_log_reads_as_published() {
    let shared = std::env::var_os("SLAMLAB_SHARED").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
        std::path::PathBuf::from,
    );
    let path = shared.join("data/laser/intel.clf.bz2");
    if !path.exists() {
        eprintln!(
            "skipped: the Intel log is not at {} (the shared data sits beside the repository)",
            path.display()
        );
        return;
    }
    let log = LaserLog::read_file(&path).unwrap();
    assert_eq!(log.compression, Some(Compression::Bzip2));
    assert_eq!(log.scans.len(), 13_631);
    assert_eq!(log.odometry.len(), 26_915);
    assert_eq!(log.comments, 9);
    assert_eq!(log.params.len(), 2);
    assert!(log.skipped.is_empty(), "{:?}", log.skipped);
    assert_eq!(log.unusable_readings, 0);
    assert!(
        log.scans
            .iter()
            .all(|s| s.scan.ranges.len() == 180 && s.kind == LaserKind::Front)
    );
    // First and last FLASER ipc_timestamps, read off the file with bzcat.
    assert_eq!(
        log.time_span(),
        Some((976_052_857.337_53, 976_055_548.624_744))
    );
    let s = &log.scans[0].scan;
    assert_eq!(s.ranges[0], 1.07);
    assert_eq!(s.angles[0], -FRAC_PI_2);
    assert!((s.angles[179] - 89f64.to_radians()).abs() < 1e-15);
    assert_eq!(s.range_max, 50.0);
    // The 81.83 m no-return code reads as "nothing within range".
    let no_return: usize = log
        .scans
        .iter()
        .map(|s| (0..180).filter(|&k| s.scan.is_max_range(k)).count())
        .sum();
    assert_eq!(no_return, 68_313);
    assert!(log.scans.iter().all(|s| s.laser_pose.is_none()));
}
