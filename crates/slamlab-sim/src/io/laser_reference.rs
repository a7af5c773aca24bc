//! Reference trajectories of laser logs: the "corrected" CARMEN logs of
//! Kümmerle et al. 2009 ("On measuring the accuracy of SLAM algorithms",
//! Autonomous Robots 27(4)), and which scans of a raw log they belong to.
//!
//! A corrected log (`intel-corrected.log.gz`) is a CARMEN log like the raw one
//! ([`LaserLog`] reads it), holding a subset of the raw log's `FLASER` scans
//! whose `x y theta` are poses corrected by a high-quality SLAM run, in a frame
//! of their own. Each reference scan has the same ranges as one raw scan, and
//! its time is that scan's time minus the raw log's first `FLASER` time (to
//! within 5 ms on the Intel log). [`associate`] finds each reference scan's raw
//! scan **by time, confirmed by identical ranges**: the raw scans within
//! [`TIME_TOLERANCE`] of the reference time (shifted by the raw log's first
//! time; the raw times are not in order, so every scan in the interval is
//! looked at), of those the ones whose ranges are the same numbers, of those
//! the nearest in time. If no reference scan matches with the first-time
//! shift, the shift 0 is tried (a reference written with the raw log's own
//! clock).
//!
//! What goes wrong is said in words, with the line: a reference that cannot
//! be read ([`LogError`], with its line), one with no scan, a log or a
//! reference whose scans all have one time (nothing to match by), and a
//! reference none of whose scans matches.

use super::laser_log::{LaserKind, LaserLog, LogError};
use slamlab_core::Pose2;

/// A reference scan matches a raw scan whose time (shifted) is within this
/// many seconds, seconds. The Intel log's references are within 5.3 ms of
/// their raw scans, whose times are 0.09 s apart at the median (and out of
/// order in 631 places, by up to 0.9 s).
pub const TIME_TOLERANCE: f64 = 0.05;

/// One scan of a corrected log.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceScan {
    /// The 1-based line it was read from.
    pub line: usize,
    /// Its time (`ipc_timestamp`), seconds.
    pub time: f64,
    /// The corrected pose (`x y theta` of the `FLASER` record).
    pub pose: Pose2,
    /// Its ranges, metres.
    pub ranges: Vec<f64>,
}

/// A corrected log: the reference poses of some of a raw log's scans.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReferenceLog {
    /// The reference scans in file order.
    pub scans: Vec<ReferenceScan>,
}

/// Why a reference cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ReferenceError {
    /// The file is not a readable CARMEN log (the line is in the message).
    #[error("the reference is not a readable CARMEN log: {0}")]
    Log(#[from] LogError),
    /// It has no `FLASER` scan (`RLASER` and `ROBOTLASER1` references are not read).
    #[error("the reference has no FLASER scan (corrected logs hold their poses in FLASER records)")]
    NoScans,
    /// Every scan of the log (or the reference) has the same time.
    #[error(
        "the {which}'s {count} scans all have the time {time} s: scans are matched to the reference by time, so a log without timestamps cannot be scored"
    )]
    NoTimestamps {
        /// `log` or `reference`.
        which: &'static str,
        /// Its laser scans.
        count: usize,
        /// Their one time.
        time: f64,
    },
    /// No reference scan has a raw scan at its time with the same ranges.
    #[error(
        "none of the reference's {reference} scans matches a scan of the log ({log} scans) by time (within {tolerance} s, times shifted by the log's first scan time or not) and identical ranges: it is the reference of another log"
    )]
    NoMatch {
        /// Reference scans.
        reference: usize,
        /// Raw scans of the log.
        log: usize,
        /// The time tolerance, seconds.
        tolerance: f64,
    },
}

impl ReferenceLog {
    /// Reads a corrected log (plain, gzip or bzip2): its `FLASER` scans, each
    /// with the corrected pose and its ranges.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, ReferenceError> {
        Self::from_log(&LaserLog::from_bytes(bytes)?)
    }

    /// The reference scans of a corrected log already read.
    pub fn from_log(log: &LaserLog) -> Result<Self, ReferenceError> {
        let scans: Vec<ReferenceScan> = log
            .scans
            .iter()
            .filter(|s| s.kind == LaserKind::Front)
            .map(|s| ReferenceScan {
                line: s.line,
                time: s.timestamp,
                pose: s.laser_pose(),
                ranges: s.scan.ranges.clone(),
            })
            .collect();
        if scans.is_empty() {
            return Err(ReferenceError::NoScans);
        }
        check_times("reference", scans.iter().map(|s| s.time))?;
        Ok(Self { scans })
    }
}

/// Refuses a set of scans whose times are all the same (two or more scans).
fn check_times(
    which: &'static str,
    times: impl Iterator<Item = f64> + Clone,
) -> Result<(), ReferenceError> {
    let count = times.clone().count();
    let mut it = times;
    let Some(first) = it.next() else {
        return Ok(());
    };
    if count >= 2 && it.all(|t| t == first) {
        return Err(ReferenceError::NoTimestamps {
            which,
            count,
            time: first,
        });
    }
    Ok(())
}

/// A reference scan and the raw scan it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferencePair {
    /// Index into [`ReferenceLog::scans`].
    pub reference: usize,
    /// Index into the raw log's scans ([`LaserLog::scans`], the same index
    /// as the lessons' input scans).
    pub scan: usize,
    /// The raw scan's time minus the reference's (shifted), seconds.
    pub time_error: f64,
}

/// Why one reference scan was not matched.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unmatched {
    /// No raw scan within the time tolerance.
    NoScanAtTime,
    /// Raw scans at its time, none with its ranges.
    RangesDiffer,
}

/// Which raw scan each reference scan is.
#[derive(Clone, Debug, PartialEq)]
pub struct Association {
    /// The matched reference scans, in reference order.
    pub pairs: Vec<ReferencePair>,
    /// The reference scans not matched (index, why).
    pub unmatched: Vec<(usize, Unmatched)>,
    /// The shift added to a reference time to get a raw time, seconds (the
    /// raw log's first `FLASER` time, or 0).
    pub time_shift: f64,
    /// The largest `|time_error|` of a match, seconds.
    pub max_time_error: f64,
}

impl Association {
    /// A sentence on how many matched.
    pub fn describe(&self) -> String {
        let total = self.pairs.len() + self.unmatched.len();
        let mut s = format!(
            "{} of {total} reference scans matched to scans of the log by time and identical ranges (largest time difference {:.1} ms)",
            self.pairs.len(),
            self.max_time_error * 1e3
        );
        let no_time = self
            .unmatched
            .iter()
            .filter(|(_, u)| *u == Unmatched::NoScanAtTime)
            .count();
        let differ = self.unmatched.len() - no_time;
        if no_time > 0 {
            s.push_str(&format!("; {no_time} with no scan at their time"));
        }
        if differ > 0 {
            s.push_str(&format!(
                "; {differ} whose ranges differ from every scan at their time"
            ));
        }
        s
    }
}

/// Matches each reference scan to the raw `FLASER` scan of `log` at its time
/// with the same ranges (module docs). Indices are into `log.scans`.
pub fn associate(reference: &ReferenceLog, log: &LaserLog) -> Result<Association, ReferenceError> {
    let front: Vec<(usize, f64, &[f64])> = log
        .scans
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kind == LaserKind::Front)
        .map(|(i, s)| (i, s.timestamp, s.scan.ranges.as_slice()))
        .collect();
    associate_scans(reference, &front)
}

/// [`associate`] against any scans: `(index, time, ranges)` each, the time in
/// the raw log's clock (UNIX seconds for a CARMEN log).
pub fn associate_scans(
    reference: &ReferenceLog,
    scans: &[(usize, f64, &[f64])],
) -> Result<Association, ReferenceError> {
    check_times("log", scans.iter().map(|s| s.1))?;
    let first = scans.first().map_or(0.0, |s| s.1);
    // Raw scans sorted by time (the raw times are not in file order).
    let mut by_time: Vec<(f64, usize)> = (0..scans.len())
        .map(|k| (scans[k].1, k))
        .filter(|(t, _)| t.is_finite())
        .collect();
    by_time.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut best: Option<Association> = None;
    for shift in [first, 0.0] {
        let a = associate_with_shift(reference, scans, &by_time, shift);
        let better = best.as_ref().is_none_or(|b| a.pairs.len() > b.pairs.len());
        if better {
            best = Some(a);
        }
        if best.as_ref().is_some_and(|b| !b.pairs.is_empty()) {
            break;
        }
    }
    match best {
        Some(a) if !a.pairs.is_empty() => Ok(a),
        _ => Err(ReferenceError::NoMatch {
            reference: reference.scans.len(),
            log: scans.len(),
            tolerance: TIME_TOLERANCE,
        }),
    }
}

fn associate_with_shift(
    reference: &ReferenceLog,
    scans: &[(usize, f64, &[f64])],
    by_time: &[(f64, usize)],
    shift: f64,
) -> Association {
    let mut out = Association {
        pairs: Vec::new(),
        unmatched: Vec::new(),
        time_shift: shift,
        max_time_error: 0.0,
    };
    for (k, r) in reference.scans.iter().enumerate() {
        let t = r.time + shift;
        let lo = by_time.partition_point(|(rt, _)| *rt < t - TIME_TOLERANCE);
        let hi = by_time.partition_point(|(rt, _)| *rt <= t + TIME_TOLERANCE);
        let near = &by_time[lo..hi.max(lo)];
        if near.is_empty() {
            out.unmatched.push((k, Unmatched::NoScanAtTime));
            continue;
        }
        let found = near
            .iter()
            .filter(|(_, j)| same_ranges(scans[*j].2, &r.ranges))
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()));
        match found {
            Some(&(rt, j)) => {
                let i = scans[j].0;
                let time_error = rt - t;
                out.max_time_error = out.max_time_error.max(time_error.abs());
                out.pairs.push(ReferencePair {
                    reference: k,
                    scan: i,
                    time_error,
                });
            }
            None => out.unmatched.push((k, Unmatched::RangesDiffer)),
        }
    }
    out
}

/// The same readings: equal counts and every range the same number (both
/// NaN counts as the same: a reading neither log could use).
fn same_ranges(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn line(ranges: &[f64], pose: (f64, f64, f64), time: f64) -> String {
        let r: Vec<String> = ranges.iter().map(|v| v.to_string()).collect();
        format!(
            "FLASER {} {} {} {} {} {} {} {} {time} host {time}\n",
            ranges.len(),
            r.join(" "),
            pose.0,
            pose.1,
            pose.2,
            pose.0,
            pose.1,
            pose.2
        )
    }

    /// A raw log of `n` scans 0.2 s apart from `t0`, scan k's ranges
    /// `[k, k + 1, k + 2]` (k = 2 and 3 share theirs: the robot stood still).
    fn raw(n: usize, t0: f64) -> LaserLog {
        let mut text = String::new();
        for k in 0..n {
            let base = if k == 3 { 2.0 } else { k as f64 };
            text += &line(
                &[base, base + 1.0, base + 2.0],
                (0.0, 0.0, 0.0),
                t0 + 0.2 * k as f64,
            );
        }
        LaserLog::from_bytes(text.as_bytes()).unwrap()
    }

    #[test]
    fn reference_scans_match_by_time_and_ranges() {
        let log = raw(10, 1000.0);
        // Scans 1, 3 and 7 as references, times relative to the first scan
        // with a few ms of jitter, poses in their own frame.
        let mut text = String::from("# corrected\nODOM 0 0 0 0 0 0 0.0 pippo 0.0\n");
        text += &line(&[1.0, 2.0, 3.0], (5.0, 1.0, 0.1), 0.203);
        text += &line(&[2.0, 3.0, 4.0], (5.5, 1.0, 0.1), 0.598);
        text += &line(&[7.0, 8.0, 9.0], (6.0, 1.2, 0.2), 1.404);
        let reference = ReferenceLog::from_bytes(text.as_bytes()).unwrap();
        assert_eq!(reference.scans.len(), 3);
        assert_eq!(reference.scans[1].pose, Pose2::new(5.5, 1.0, 0.1));
        assert_eq!(reference.scans[0].line, 3);
        let a = associate(&reference, &log).unwrap();
        let scans: Vec<(usize, usize)> = a.pairs.iter().map(|p| (p.reference, p.scan)).collect();
        // Scan 3 has scan 2's ranges; time picks 3.
        assert_eq!(scans, vec![(0, 1), (1, 3), (2, 7)]);
        assert_eq!(a.time_shift, 1000.0);
        assert!(
            (a.max_time_error - 0.004).abs() < 1e-9,
            "{}",
            a.max_time_error
        );
        assert!(a.unmatched.is_empty());
        assert!(a.describe().starts_with("3 of 3 reference scans matched"));
    }

    #[test]
    fn a_reference_in_the_logs_own_clock_matches_with_no_shift() {
        let log = raw(5, 1000.0);
        let text = line(&[4.0, 5.0, 6.0], (0.0, 0.0, 0.0), 1000.8);
        let a = associate(&ReferenceLog::from_bytes(text.as_bytes()).unwrap(), &log).unwrap();
        assert_eq!(a.time_shift, 0.0);
        assert_eq!(a.pairs[0].scan, 4);
    }

    #[test]
    fn unmatched_scans_are_counted_and_a_foreign_reference_is_refused() {
        let log = raw(5, 1000.0);
        let mut text = line(&[1.0, 2.0, 3.0], (0.0, 0.0, 0.0), 0.2);
        // The right time, other ranges; then a time past the log.
        text += &line(&[1.5, 2.0, 3.0], (0.0, 0.0, 0.0), 0.4);
        text += &line(&[4.0, 5.0, 6.0], (0.0, 0.0, 0.0), 9.0);
        let a = associate(&ReferenceLog::from_bytes(text.as_bytes()).unwrap(), &log).unwrap();
        assert_eq!(a.pairs.len(), 1);
        assert_eq!(
            a.unmatched,
            vec![(1, Unmatched::RangesDiffer), (2, Unmatched::NoScanAtTime)]
        );
        let d = a.describe();
        assert!(
            d.contains("1 of 3") && d.contains("1 with no scan") && d.contains("1 whose ranges"),
            "{d}"
        );
        // None matches: refused with a sentence.
        let foreign = line(&[9.0, 9.0, 9.0], (0.0, 0.0, 0.0), 0.2);
        let e =
            associate(&ReferenceLog::from_bytes(foreign.as_bytes()).unwrap(), &log).unwrap_err();
        assert!(
            matches!(
                e,
                ReferenceError::NoMatch {
                    reference: 1,
                    log: 5,
                    ..
                }
            ),
            "{e}"
        );
        assert!(
            e.to_string().contains("none of the reference's 1 scans"),
            "{e}"
        );
    }

    #[test]
    fn bad_references_and_logs_say_why() {
        // A scan line cut short: fewer readings than it states.
        let cut = "FLASER 180 1.0 2.0 3.0 0 0 0 0 0 0 5.0 host 5.0\n";
        let e = ReferenceLog::from_bytes(cut.as_bytes()).unwrap_err();
        assert!(e.to_string().contains("line 1"), "{e}");
        assert!(e.to_string().contains("180 readings announced"), "{e}");
        // No FLASER.
        let odom = "ODOM 0 0 0 0 0 0 1.0 host 1.0\nRLASER 1 1.0 0 0 0 0 0 0 1.0 host 1.0\n";
        assert_eq!(
            ReferenceLog::from_bytes(odom.as_bytes()).unwrap_err(),
            ReferenceError::NoScans
        );
        // A log whose scans carry no time (all 0).
        let reference =
            ReferenceLog::from_bytes(line(&[1.0], (0.0, 0.0, 0.0), 0.2).as_bytes()).unwrap();
        let mut text = String::new();
        for k in 0..4 {
            text += &line(&[k as f64], (0.0, 0.0, 0.0), 0.0);
        }
        let log = LaserLog::from_bytes(text.as_bytes()).unwrap();
        let e = associate(&reference, &log).unwrap_err();
        assert!(
            matches!(
                e,
                ReferenceError::NoTimestamps {
                    which: "log",
                    count: 4,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("cannot be scored"), "{e}");
    }

    /// `shared/data/laser` beside the repository (or in `$SLAMLAB_SHARED`),
    /// when the Intel files are there; None with a message otherwise.
    pub(crate) fn shared_laser_dir() -> Option<std::path::PathBuf> {
        let dir = std::env::var_os("SLAMLAB_SHARED")
            .map_or_else(
                || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
                std::path::PathBuf::from,
            )
            .join("data/laser");
        if dir.join("intel.clf.bz2").exists() && dir.join("intel-corrected.log.gz").exists() {
            Some(dir)
        } else {
            eprintln!(
                "skipped: the Intel log and its corrected version are not in {} (the shared data sits beside the repository, or set SLAMLAB_SHARED)",
                dir.display()
            );
            None
        }
    }

    /// The Intel files (in `../shared/data/laser`): 910 of 910 reference
    /// scans matched, each within 5.3 ms of its raw scan.
    #[test]
    fn every_intel_reference_scan_matches_a_raw_scan() {
        let Some(dir) = shared_laser_dir() else {
            return;
        };
        let log = LaserLog::read_file(&dir.join("intel.clf.bz2")).unwrap();
        let bytes = std::fs::read(dir.join("intel-corrected.log.gz")).unwrap();
        let reference = ReferenceLog::from_bytes(&bytes).unwrap();
        assert_eq!(reference.scans.len(), 910);
        let a = associate(&reference, &log).unwrap();
        assert_eq!(a.pairs.len(), 910, "{}", a.describe());
        assert!(a.unmatched.is_empty());
        assert!(a.max_time_error < 0.0055, "{}", a.max_time_error);
        // In order, and each a different raw scan.
        assert!(a.pairs.windows(2).all(|w| w[0].scan < w[1].scan));
        assert!(a.pairs.iter().enumerate().all(|(k, p)| p.reference == k));
        assert_eq!(a.time_shift, log.scans[0].timestamp);
    }
}
