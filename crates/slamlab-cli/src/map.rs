//! `slamlab map info PATH` and `slamlab map convert IN.yaml OUT.yaml --format png|pgm`:
//! ROS map_server maps.

use crate::args;
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgMatches, Command};
use slamlab_core::grid::OccupancyGrid;
use slamlab_sim::grid::BuiltinMap;
use slamlab_sim::io::ros_map::{
    ImageFormat, export_map, load_lone_image, load_map, parse_map_yaml,
};
use std::io::Write;
use std::path::Path;

/// `--map`, for the commands that run on a grid map.
pub fn map_arg() -> Arg {
    args::flag(
        "map",
        "maze, office, or a map_server YAML (or a PGM/PNG with --resolution)",
    )
    .default_value("maze")
}

/// `--resolution`, for a map given as a lone image; `help` as the command words it.
pub fn resolution_arg(help: &'static str) -> Arg {
    args::number("resolution", help)
}

/// The `map` subcommand.
pub fn command() -> Command {
    let resolution = resolution_arg("metres per pixel, for a lone PGM/PNG image");
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
                .arg(args::choice("format", &["png", "pgm"], "image format").default_value("png"))
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

/// Reads a map: a built-in name, a YAML (its image beside it), or a lone image
/// with `resolution`. Returns the grid and its name.
pub fn read_map(spec: &str, resolution: Option<f64>) -> Result<(OccupancyGrid, String)> {
    if let Some(b) = BuiltinMap::from_name(spec) {
        return Ok((b.load()?, b.name().to_owned()));
    }
    let path = Path::new(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if ext == "pgm" || ext == "png" {
        let Some(res) = resolution else {
            bail!(
                "{spec} is an image without a YAML: give its resolution with --resolution METRES"
            );
        };
        let bytes = std::fs::read(path).with_context(|| format!("cannot read {spec}"))?;
        let grid = load_lone_image(&bytes, res).with_context(|| format!("map {spec}"))?;
        return Ok((grid, spec.to_owned()));
    }
    let text = std::fs::read_to_string(path).with_context(|| {
        format!("cannot read {spec} (a map is maze, office, a map_server YAML, or a PGM/PNG)")
    })?;
    let yaml = parse_map_yaml(&text).with_context(|| format!("map {spec}"))?;
    let image_path = path
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .join(&yaml.image);
    let bytes = std::fs::read(&image_path).with_context(|| {
        format!(
            "image '{}' named in {spec} cannot be read at {}",
            yaml.image,
            image_path.display()
        )
    })?;
    let (grid, _) = load_map(&text, &bytes).with_context(|| format!("map {spec}"))?;
    Ok((grid, spec.to_owned()))
}
