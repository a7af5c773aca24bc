//! A ROS 2 bag through the mapping lesson: what a LaserScan and an Odometry
//! message change (float32 ranges and angles, a heading through a quaternion) is
//! all that changes in the run. (An integration test: the grid folder's own tests
//! may not use a lesson's folder.)

use slamlab_core::Pose2;
use slamlab_sim::grid::{
    BuiltinMap, LaserFile, MappingInput, SimulatedLogConfig, log_input, simulate_log,
};
use slamlab_sim::io::ros2_bag::msgs::Transform3;
use slamlab_sim::io::ros2_bag::{BagWriteOptions, TopicChoice, write_bag};
use slamlab_sim::mapping::{MappingScenario, MappingSession};
use std::sync::Arc;

#[allow(clippy::unwrap_used)] // a test helper: a failure stops the test
fn end_pose(input: MappingInput) -> Pose2 {
    let (mut session, _) = MappingSession::new(MappingScenario::default(), Arc::new(input));
    session.run_to_end();
    session.sim().current().map(|(_, _, p)| p).unwrap()
}

/// A simulated run written as a bag maps, scan to map, to the same pose to
/// the bit as the run itself with its ranges and angles rounded to float32
/// and its headings passed through a quaternion, which is all a LaserScan
/// and an Odometry message change.
#[test]
fn a_bag_feeds_the_mapping_lesson_exactly_what_its_messages_say() {
    let map = BuiltinMap::Office.load().unwrap();
    let (log, truth) = simulate_log(&map, 150, 2, &SimulatedLogConfig::default()).unwrap();
    let bag = write_bag(&log, Some(&truth), &BagWriteOptions::default()).unwrap();
    let file = LaserFile::from_bytes("run.mcap", &bag, &TopicChoice::default()).unwrap();
    assert_eq!(file.format, "ROS 2 bag, MCAP with uncompressed chunks");
    assert_eq!(file.describe(), "run.mcap (/scan, odometry /odom)");
    assert!(file.notices.is_empty(), "{:?}", file.notices);
    let topics = file.topics.clone().unwrap();
    assert_eq!(topics.scan_choices, ["/scan"]);
    assert_eq!(topics.odometry_choices, ["/odom", "tf"]);
    // The truth travels along for the metrics.
    assert_eq!(file.input.truth.as_ref().map(Vec::len), Some(150));

    let mut rounded = log.clone();
    for s in &mut rounded.scans {
        let n = s.scan.angles.len();
        let first = s.scan.angles[0] as f32;
        let step = ((s.scan.angles[n - 1] - s.scan.angles[0]) / (n - 1) as f64) as f32;
        for (k, a) in s.scan.angles.iter_mut().enumerate() {
            *a = f64::from(first) + k as f64 * f64::from(step);
        }
        for r in &mut s.scan.ranges {
            *r = f64::from(*r as f32);
        }
        s.scan.range_max = f64::from(s.scan.range_max as f32);
        s.odometry.theta = Transform3::from_pose2(s.odometry).yaw().unwrap();
    }
    let from_bag = end_pose(file.input);
    let from_log = end_pose(log_input(&rounded, "rounded"));
    assert_eq!(from_bag.x.to_bits(), from_log.x.to_bits());
    assert_eq!(from_bag.y.to_bits(), from_log.y.to_bits());
    assert_eq!(from_bag.theta.to_bits(), from_log.theta.to_bits());
    // And against the run unrounded: the float32 rounding moves the end
    // pose by less than a millimetre over 150 scans.
    let exact = end_pose(log_input(&log, "exact"));
    let d = slamlab_core::math::hypot(exact.x - from_bag.x, exact.y - from_bag.y);
    assert!(d < 1e-3, "{d}");
}
