//! `slamlab run visual-odometry`: the docking approach seen by a monocular
//! camera, two-view RANSAC chained along it, headless (thesis `000` Sec. 4.3).
//!
//! ```text
//! slamlab run visual-odometry --frames 200 --seed 1 --json
//! ```

use crate::command::RunLesson;
use crate::output::Output;
use anyhow::{Result, bail};
use clap::{Arg, ArgAction, ArgMatches, Command};
use serde_json::json;
use slamlab_core::vision::Method;
use slamlab_sim::vision::{VoSettings, run_visual_odometry};
use std::io::Write;

/// The visual-odometry lesson's run.
pub struct VisualOdometry;

impl RunLesson for VisualOdometry {
    fn id(&self) -> &'static str {
        "visual-odometry"
    }

    fn about(&self) -> &'static str {
        "Monocular visual odometry on a docking approach: RANSAC two-view steps scaled by wheel speeds, headless"
    }

    fn command(&self) -> Command {
        Command::new(self.id())
            .arg(
                Arg::new("frames")
                    .long("frames")
                    .value_parser(clap::value_parser!(u64).range(2..=100_000))
                    .default_value("200")
                    .help("frames of 0.1 s"),
            )
            .arg(
                Arg::new("seed")
                    .long("seed")
                    .value_parser(clap::value_parser!(u64))
                    .default_value("1")
                    .help("seed of the world, the noise and RANSAC"),
            )
            .arg(
                Arg::new("method")
                    .long("method")
                    .default_value("five-point")
                    .help("eight-point or five-point"),
            )
            .arg(
                Arg::new("noise-px")
                    .long("noise-px")
                    .value_parser(clap::value_parser!(f64))
                    .default_value("1")
                    .help("pixel noise standard deviation, pixels (0 .. 20)"),
            )
            .arg(
                Arg::new("outliers")
                    .long("outliers")
                    .value_parser(clap::value_parser!(f64))
                    .default_value("0.3")
                    .help("share of wrong matches (0 .. 1)"),
            )
            .arg(
                Arg::new("stride")
                    .long("stride")
                    .value_parser(clap::value_parser!(u64).range(1..=1000))
                    .default_value("5")
                    .help("frames between the two images of a VO step"),
            )
            .arg(
                Arg::new("no-normalize")
                    .long("no-normalize")
                    .action(ArgAction::SetTrue)
                    .help("eight-point without Hartley normalization"),
            )
            .arg(
                Arg::new("pure-rotation")
                    .long("pure-rotation")
                    .action(ArgAction::SetTrue)
                    .help("a 20-frame turn on the spot a third of the way"),
            )
            .arg(
                Arg::new("planar")
                    .long("planar")
                    .action(ArgAction::SetTrue)
                    .help("the middle third sees only the facade (a planar scene)"),
            )
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let method_name = m
            .get_one::<String>("method")
            .map_or("five-point", String::as_str);
        let Some(method) = Method::from_name(method_name) else {
            bail!("--method: '{method_name}' is not a method (eight-point, five-point)");
        };
        let noise_px = m.get_one::<f64>("noise-px").copied().unwrap_or(1.0);
        if !(noise_px.is_finite() && (0.0..=20.0).contains(&noise_px)) {
            bail!("--noise-px: {noise_px} is outside 0 .. 20");
        }
        let outliers = m.get_one::<f64>("outliers").copied().unwrap_or(0.3);
        if !(outliers.is_finite() && (0.0..=1.0).contains(&outliers)) {
            bail!("--outliers: {outliers} is outside 0 .. 1");
        }
        let settings = VoSettings {
            frames: m.get_one::<u64>("frames").copied().unwrap_or(200) as usize,
            seed: m.get_one::<u64>("seed").copied().unwrap_or(1),
            method,
            normalize: !m.get_flag("no-normalize"),
            noise_px,
            outliers,
            stride: m.get_one::<u64>("stride").copied().unwrap_or(5) as usize,
            pure_rotation_segment: m.get_flag("pure-rotation"),
            planar_segment: m.get_flag("planar"),
        };
        let start = std::time::Instant::now();
        let run = run_visual_odometry(settings);
        let time_ms = start.elapsed().as_secs_f64() * 1000.0;
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
