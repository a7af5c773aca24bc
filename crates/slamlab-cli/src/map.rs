//! `slamlab map info PATH` and `slamlab map convert IN.yaml OUT.yaml --format png|pgm`:
//! ROS map_server maps.

use crate::kidnap::read_map;
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::grid::map_io::{ImageFormat, export_map};
use std::io::Write;
use std::path::Path;

/// The `map` subcommand.
pub fn command() -> Command {
    let resolution = Arg::new("resolution")
        .long("resolution")
        .value_parser(clap::value_parser!(f64))
        .help("metres per pixel, for a lone PGM/PNG image");
    Command::new("map")
        .about("ROS map_server maps: print their size and cell counts, or convert them")
        .subcommand_required(true)
        .subcommand(
            Command::new("info")
                .about("Print size, resolution, origin and free/occupied/unknown cell counts")
                .arg(
                    Arg::new("path")
                        .required(true)
                        .help("a map YAML, a PGM/PNG with --resolution, maze or office"),
                )
                .arg(resolution.clone()),
        )
        .subcommand(
            Command::new("convert")
                .about("Write a map as a YAML and a PNG or PGM image beside it")
                .arg(
                    Arg::new("input")
                        .required(true)
                        .help("a map YAML (or maze, office, an image with --resolution)"),
                )
                .arg(
                    Arg::new("output")
                        .required(true)
                        .help("the YAML to write; the image gets the same name"),
                )
                .arg(
                    Arg::new("format")
                        .long("format")
                        .value_parser(["png", "pgm"])
                        .default_value("png")
                        .help("image format"),
                )
                .arg(resolution),
        )
}

/// Runs `slamlab map ...`.
pub fn run(m: &ArgMatches) -> Result<()> {
    let out = std::io::stdout();
    let mut out = out.lock();
    match m.subcommand() {
        Some(("info", m)) => {
            let path = m.get_one::<String>("path").map_or("", String::as_str);
            let (g, name) = read_map(path, m.get_one::<f64>("resolution").copied())?;
            let (free, occ, unknown) = g.counts();
            let o = g.origin();
            let (wm, hm) = g.size_m();
            writeln!(out, "map:        {name}")?;
            writeln!(
                out,
                "size:       {} x {} cells ({wm:.2} x {hm:.2} m)",
                g.width(),
                g.height()
            )?;
            writeln!(out, "resolution: {} m per cell", g.resolution())?;
            writeln!(out, "origin:     [{}, {}, {}]", o.x, o.y, o.theta)?;
            writeln!(out, "free:       {free}")?;
            writeln!(out, "occupied:   {occ}")?;
            writeln!(out, "unknown:    {unknown}")?;
        }
        Some(("convert", m)) => {
            let input = m.get_one::<String>("input").map_or("", String::as_str);
            let output = Path::new(m.get_one::<String>("output").map_or("", String::as_str));
            let format = match m.get_one::<String>("format").map(String::as_str) {
                Some("pgm") => ImageFormat::Pgm,
                _ => ImageFormat::Png,
            };
            let (g, _) = read_map(input, m.get_one::<f64>("resolution").copied())?;
            let Some(stem) = output.file_stem().and_then(|s| s.to_str()) else {
                bail!("{} is not a file name", output.display());
            };
            let image_name = format!("{stem}.{}", format.extension());
            let image_path = output.with_file_name(&image_name);
            let (yaml, bytes) = export_map(&g, &image_name, format)?;
            std::fs::write(&image_path, bytes)
                .with_context(|| format!("cannot write {}", image_path.display()))?;
            std::fs::write(output, yaml)
                .with_context(|| format!("cannot write {}", output.display()))?;
            writeln!(
                out,
                "wrote {} and {}",
                output.display(),
                image_path.display()
            )?;
        }
        _ => {}
    }
    Ok(())
}
