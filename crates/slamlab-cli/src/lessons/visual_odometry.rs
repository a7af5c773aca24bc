//! `slamlab run visual-odometry`: the docking approach seen by a monocular
//! camera, two-view RANSAC chained along it, headless (thesis `000` Sec. 4.3).
//!
//! ```text
//! slamlab run visual-odometry --frames 200 --seed 1 --json
//! slamlab run visual-odometry --method eight-point --normalize off --pure-rotation on
//! ```
//!
//! The flags are the lesson's parameter table (`slamlab params --lesson
//! visual-odometry`), with the URL's names.

use crate::command::RunLesson;
use crate::flags;
use crate::output::Output;
use anyhow::Result;
use clap::{ArgMatches, Command};
use serde_json::json;
use slamlab_sim::visual_odometry::{VoScenario, run_visual_odometry};
use std::io::Write;

/// The visual-odometry lesson's run.
pub struct VisualOdometry;

impl RunLesson for VisualOdometry {
    fn command(&self) -> Command {
        // The lesson's table (the URL's names, ranges and defaults), but the
        // step the app shows in its two images.
        Command::new("visual-odometry")
            .about("Monocular visual odometry on a docking approach: RANSAC two-view steps scaled by wheel speeds, headless")
            .args(flags::table_args::<VoScenario>(|name| name != "pair"))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let scenario: VoScenario = flags::scenario_from(m, &["pair"])?;
        let settings = scenario.settings;
        let method = settings.method;
        let start = std::time::Instant::now();
        let run = run_visual_odometry(settings);
        let time_ms = start.elapsed().as_secs_f64() * 1000.0;
        crate::trajectory_out::write(
            m,
            &self.id(),
            &slamlab_sim::visual_odometry::export::trajectories(&run),
            &[],
        )?;
        let general = run.steps.iter().filter(|s| s.outcome == "general").count();
        let pure = run
            .steps
            .iter()
            .filter(|s| s.outcome == "pure-rotation")
            .count();
        let value = json!({
            "lesson": "visual-odometry",
            "settings": run.settings,
            "frames": run.settings.frames,
            "vo_steps": run.steps.len(),
            "general_steps": general,
            "pure_rotation_steps": pure,
            "failed_steps": run.steps.len() - general - pure,
            "trajectory_rmse": run.trajectory_rmse,
            "time_ms": time_ms,
        });
        if out.print_json(&value)? {
            return Ok(());
        }
        let r = run.trajectory_rmse;
        writeln!(
            out,
            "SLAM Lab visual odometry: {} frames, {} VO steps ({} general, {} pure rotation, {} failed), {} , seed {}",
            run.settings.frames,
            run.steps.len(),
            general,
            pure,
            run.steps.len() - general - pure,
            method.name(),
            run.settings.seed
        )?;
        writeln!(
            out,
            "trajectory RMSE (m): wheel odometry {:.3}, VO scaled by wheel speeds {:.3}, VO with unit steps {:.3}",
            r.wheel_odometry, r.visual_odometry, r.visual_odometry_unit_scale
        )?;
        writeln!(out, "time: {time_ms:.1} ms")?;
        Ok(())
    }
}
