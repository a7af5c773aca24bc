//! Frame timing: how much of each frame the app itself uses, shown by View → "Frame
//! timing" and read by the browser benchmark through `slamlab_test_state()`.
//!
//! Three numbers per frame: the CPU time of the whole frame as eframe measures it
//! (the app's UI code, the simulation and tessellation, not the GPU's drawing), the
//! part of it spent stepping the simulation, and the time since the previous frame.
//! A lesson stays interactive while the CPU time stays well under the ~16 ms a 60 Hz
//! display allows.

use std::collections::VecDeque;

/// How many recent frames the statistics cover.
const WINDOW: usize = 120;

#[derive(Clone, Copy, Debug, Default)]
struct Sample {
    cpu_ms: Option<f32>,
    sim_ms: f32,
    interval_ms: f32,
    /// Whether the frame `cpu_ms` measures ran a filter update (a lesson's
    /// heavy step, such as grid FastSLAM's scan matching).
    update: bool,
}

/// The last [`WINDOW`] frames' timings.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    samples: VecDeque<Sample>,
    /// Whether the last recorded frame ran a filter update (its CPU time
    /// arrives with the next frame).
    last_update: bool,
}

/// Medians and 95th percentiles over the recent frames, milliseconds.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FrameSummary {
    /// Frames the summary covers.
    pub frames: usize,
    /// CPU time per frame (eframe's measurement; `None` where it gives none, as in tests).
    pub cpu_ms_median: Option<f32>,
    /// See `cpu_ms_median`.
    pub cpu_ms_p95: Option<f32>,
    /// Time spent stepping the simulation and the filters per frame.
    pub sim_ms_median: f32,
    /// See `sim_ms_median`.
    pub sim_ms_p95: f32,
    /// Time between frames; 1000 / this is the frame rate.
    pub interval_ms_median: f32,
    /// Frames that ran a filter update (lessons that say so; 0 elsewhere).
    pub update_frames: usize,
    /// CPU time per frame over the frames without a filter update.
    pub cpu_ms_median_outside_updates: Option<f32>,
    /// CPU time per frame over the frames with one.
    pub cpu_ms_median_update_frames: Option<f32>,
}

impl FrameStats {
    /// Records one frame. `cpu_ms` is eframe's CPU time of the previous frame.
    pub fn record(&mut self, cpu_ms: Option<f32>, sim_ms: f32, interval_ms: f32) {
        self.record_frame(cpu_ms, sim_ms, interval_ms, false);
    }

    /// Records one frame that ran a filter update (`update`) or not.
    pub fn record_frame(
        &mut self,
        cpu_ms: Option<f32>,
        sim_ms: f32,
        interval_ms: f32,
        update: bool,
    ) {
        let measured_update = std::mem::replace(&mut self.last_update, update);
        if self.samples.len() == WINDOW {
            self.samples.pop_front();
        }
        let finite = |v: f32| v.is_finite().then_some(v.max(0.0));
        self.samples.push_back(Sample {
            cpu_ms: cpu_ms.and_then(finite),
            sim_ms: finite(sim_ms).unwrap_or(0.0),
            interval_ms: finite(interval_ms).unwrap_or(0.0),
            update: measured_update,
        });
    }

    /// The summary, or `None` before the first frame.
    pub fn summary(&self) -> Option<FrameSummary> {
        if self.samples.is_empty() {
            return None;
        }
        let cpu: Vec<f32> = self.samples.iter().filter_map(|s| s.cpu_ms).collect();
        let sim: Vec<f32> = self.samples.iter().map(|s| s.sim_ms).collect();
        let interval: Vec<f32> = self.samples.iter().map(|s| s.interval_ms).collect();
        let cpu_where = |update: bool| -> Vec<f32> {
            self.samples
                .iter()
                .filter(|s| s.update == update)
                .filter_map(|s| s.cpu_ms)
                .collect()
        };
        Some(FrameSummary {
            frames: self.samples.len(),
            cpu_ms_median: quantile(cpu.clone(), 0.5),
            cpu_ms_p95: quantile(cpu, 0.95),
            sim_ms_median: quantile(sim.clone(), 0.5).unwrap_or(0.0),
            sim_ms_p95: quantile(sim, 0.95).unwrap_or(0.0),
            interval_ms_median: quantile(interval, 0.5).unwrap_or(0.0),
            update_frames: self.samples.iter().filter(|s| s.update).count(),
            cpu_ms_median_outside_updates: quantile(cpu_where(false), 0.5),
            cpu_ms_median_update_frames: quantile(cpu_where(true), 0.5),
        })
    }

    /// One line for the menu bar.
    pub fn label(&self) -> String {
        let Some(s) = self.summary() else {
            return "frame timing: no frames yet".to_owned();
        };
        let cpu = s
            .cpu_ms_median
            .map_or_else(|| "n/a".to_owned(), |v| format!("{v:.1} ms"));
        let fps = if s.interval_ms_median > 0.0 {
            format!("{:.0} fps", 1000.0 / s.interval_ms_median)
        } else {
            "- fps".to_owned()
        };
        format!(
            "frame CPU {cpu} (simulation {:.1} ms) · {fps}",
            s.sim_ms_median
        )
    }
}

/// The `q`-quantile (nearest rank) of `values`, `None` when empty.
fn quantile(mut values: Vec<f32>, q: f32) -> Option<f32> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f32::total_cmp);
    let rank = (q * values.len() as f32).ceil() as usize;
    values.get(rank.clamp(1, values.len()) - 1).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_over_the_window_with_medians_and_tails() {
        let mut stats = FrameStats::default();
        assert!(stats.summary().is_none());
        for i in 1..=200 {
            // The first 80 frames fall out of the 120-frame window.
            let ms = i as f32;
            stats.record(Some(ms), 0.5 * ms, 20.0);
        }
        let s = stats
            .summary()
            .unwrap_or_else(|| panic!("frames were recorded"));
        assert_eq!(s.frames, 120);
        // Frames 81..=200: the median (nearest rank 60) is 140, the 95th percentile 194.
        assert_eq!(s.cpu_ms_median, Some(140.0));
        assert_eq!(s.cpu_ms_p95, Some(194.0));
        assert_eq!(s.sim_ms_median, 70.0);
        assert_eq!(s.interval_ms_median, 20.0);
        assert!(stats.label().contains("50 fps"), "{}", stats.label());
    }

    #[test]
    fn update_frames_are_told_apart_by_the_frame_their_cpu_time_measures() {
        let mut stats = FrameStats::default();
        // Every fourth frame runs an update costing 40 ms; the others 5 ms.
        // eframe reports a frame's CPU time with the next frame.
        let mut previous_cpu = None;
        for i in 0..100 {
            let update = i % 4 == 0;
            stats.record_frame(previous_cpu, 1.0, 16.0, update);
            previous_cpu = Some(if update { 40.0 } else { 5.0 });
        }
        let s = stats
            .summary()
            .unwrap_or_else(|| panic!("frames were recorded"));
        assert_eq!(s.update_frames, 25);
        assert_eq!(s.cpu_ms_median_outside_updates, Some(5.0));
        assert_eq!(s.cpu_ms_median_update_frames, Some(40.0));
        assert_eq!(s.cpu_ms_median, Some(5.0));
    }

    #[test]
    fn bad_timings_are_ignored_not_propagated() {
        let mut stats = FrameStats::default();
        stats.record(None, f32::NAN, f32::INFINITY);
        stats.record(Some(f32::NAN), -1.0, 10.0);
        let s = stats
            .summary()
            .unwrap_or_else(|| panic!("frames were recorded"));
        assert_eq!(s.cpu_ms_median, None);
        assert_eq!(s.sim_ms_median, 0.0);
        assert!(s.interval_ms_median.is_finite());
        assert!(stats.label().contains("n/a"));
    }
}
