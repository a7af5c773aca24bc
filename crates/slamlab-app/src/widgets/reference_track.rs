//! A laser log's reference trajectory (a corrected log, Kümmerle et al. 2009) in
//! a lidar lesson: the run's trajectory error against it as the run goes, and the
//! reference path drawn on the map.
//!
//! Each time the run passes a reference scan, the trajectory so far (one pose
//! per scan, as the lesson's estimator has it now: loop closures move the past)
//! is aligned to the reference scans passed by the SE(2) transform that fits
//! best, and its ATE (RMS position error after the alignment) is recorded
//! against the scan. The reference is in a frame of its own; it is drawn moved
//! by the inverse of that alignment, onto the estimate.

use crate::widgets::map_canvas::MapTransform;
use egui::{Color32, Stroke};
use slamlab_core::{Pose2, math};
use slamlab_sim::grid::reference::{LogReference, alignment};

/// The error against the reference as the run went, and the aligned path.
#[derive(Clone, Debug, Default)]
pub struct ReferenceTrack {
    /// `[scan, ATE (m)]`, one per reference scan passed (from the second
    /// on): the ATE of the trajectory up to that scan.
    pub ate: Vec<[f64; 2]>,
    /// The reference scans passed, moved onto the estimate by the latest
    /// alignment (world metres).
    pub path: Vec<[f64; 2]>,
    /// Scans the run had processed at the last update.
    done: usize,
}

impl ReferenceTrack {
    /// Forgets the run (a new run starts).
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// The latest ATE and the scan it was measured at.
    pub fn latest(&self) -> Option<[f64; 2]> {
        self.ate.last().copied()
    }

    /// Brings the track up to a run that has processed `done` scans:
    /// `poses()` gives one pose per input scan as the run has them now (asked
    /// only when a reference scan was passed since the last update, or the
    /// run went back). Each reference scan passed gets the ATE of the poses
    /// up to it, as the run has them at this update (a frame that runs many
    /// scans scores each of their reference scans with that frame's poses). A
    /// run that went back (step back, a replay) drops what lies past it.
    pub fn update(
        &mut self,
        reference: Option<&LogReference>,
        done: usize,
        poses: impl FnOnce() -> Vec<Option<Pose2>>,
    ) {
        let Some(reference) = reference else {
            if self.done > 0 || !self.ate.is_empty() {
                self.clear();
            }
            return;
        };
        if done == self.done {
            return;
        }
        let went_back = done < self.done;
        let mut new: Vec<usize> = reference
            .points
            .iter()
            .map(|p| p.scan)
            .filter(|&s| s < done && s >= self.done)
            .collect();
        self.done = done;
        if went_back {
            self.ate.retain(|p| (p[0] as usize) < done);
        } else if new.is_empty() {
            return;
        }
        let poses = poses();
        let upto = |scan: usize| &poses[..scan.min(poses.len())];
        new.sort_unstable();
        for scan in new {
            if let Some((_, ate, _)) = alignment(reference, upto(scan + 1)) {
                self.ate.push([scan as f64, ate]);
            }
        }
        let Some((similarity, _, _)) = alignment(reference, upto(done)) else {
            self.path.clear();
            return;
        };
        // The inverse of `p ↦ R p + t`: `q ↦ Rᵀ (q − t)`.
        let (s, c) = math::sin_cos(similarity.rotation);
        let [tx, ty] = similarity.translation;
        self.path = reference
            .points
            .iter()
            .filter(|p| p.scan < done)
            .map(|p| {
                let (x, y) = (p.pose.x - tx, p.pose.y - ty);
                [c * x + s * y, -s * x + c * y]
            })
            .collect();
    }

    /// Draws the aligned reference path: a line through the reference scans
    /// passed and a ring at each, in `color` over a `halo` (the canvas
    /// background) so that it reads over free and occupied cells alike.
    pub fn draw_path(
        &self,
        painter: &egui::Painter,
        t: &MapTransform,
        color: Color32,
        halo: Color32,
    ) {
        let points: Vec<egui::Pos2> = self.path.iter().map(|p| t.xy(p[0], p[1])).collect();
        painter.add(egui::Shape::line(points.clone(), Stroke::new(3.0, halo)));
        for &p in &points {
            painter.circle_stroke(p, 2.4, Stroke::new(2.8, halo));
        }
        painter.add(egui::Shape::line(points.clone(), Stroke::new(1.2, color)));
        for &p in &points {
            painter.circle_stroke(p, 2.4, Stroke::new(1.0, color));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_sim::grid::reference::ReferencePoint;

    #[test]
    fn the_track_follows_the_run_and_drops_what_a_step_back_undoes() {
        // A reference at scans 0, 2, 4, ... of a straight drive, in a frame
        // turned by 90° and moved; the estimate is the drive itself.
        let moved = Pose2::new(5.0, -3.0, std::f64::consts::FRAC_PI_2);
        let truth: Vec<Pose2> = (0..20)
            .map(|k| Pose2::new(0.5 * k as f64, 0.0, 0.0))
            .collect();
        let reference = LogReference {
            name: "test".to_owned(),
            points: (0..20)
                .step_by(2)
                .map(|k| ReferencePoint {
                    scan: k,
                    pose: moved.compose(&truth[k]),
                })
                .collect(),
            reference_scans: 10,
            description: String::new(),
        };
        let poses = || truth.iter().copied().map(Some).collect::<Vec<_>>();
        let mut track = ReferenceTrack::default();
        track.update(Some(&reference), 1, poses);
        assert!(
            track.ate.is_empty(),
            "one reference scan fixes no alignment"
        );
        track.update(Some(&reference), 11, poses);
        // One entry per reference scan passed from the second on: 2, 4, ..., 10.
        let scans: Vec<f64> = track.ate.iter().map(|p| p[0]).collect();
        assert_eq!(scans, [2.0, 4.0, 6.0, 8.0, 10.0]);
        assert!(track.ate.iter().all(|p| p[1] < 1e-9), "{:?}", track.ate);
        // The path lies on the estimate.
        assert_eq!(track.path.len(), 6);
        for (p, k) in track.path.iter().zip((0..20).step_by(2)) {
            assert!(
                (p[0] - truth[k].x).abs() < 1e-9 && p[1].abs() < 1e-9,
                "{p:?}"
            );
        }
        // Nothing new passed: nothing asked.
        track.update(Some(&reference), 11, || panic!("no new scan"));
        track.update(Some(&reference), 12, || panic!("no new reference scan"));
        track.update(Some(&reference), 20, poses);
        assert_eq!(track.latest().map(|p| p[0]), Some(18.0));
        assert_eq!(track.ate.len(), 9);
        // Back to scan 11: the entries past it go, the path is redrawn.
        track.update(Some(&reference), 11, poses);
        assert_eq!(track.ate.len(), 5);
        assert_eq!(track.path.len(), 6);
        // A drifting estimate: the error grows with the scans passed.
        let drift = || {
            truth
                .iter()
                .enumerate()
                .map(|(k, p)| Some(Pose2::new(p.x, 0.01 * (k * k) as f64, 0.0)))
                .collect::<Vec<_>>()
        };
        let mut drifting = ReferenceTrack::default();
        drifting.update(Some(&reference), 20, drift);
        assert!(
            drifting.ate.windows(2).all(|w| w[1][1] > w[0][1]),
            "{:?}",
            drifting.ate
        );
        track.update(None, 11, poses);
        assert!(track.ate.is_empty() && track.path.is_empty());
    }
}
