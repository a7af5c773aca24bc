//! `slamlab export-inputs` and `slamlab grade`: an assignment's inputs for one
//! student, written as the page's *Download inputs* zip holds them, and the
//! grade of a handed-in estimate (one student, or a class from a roster), as
//! the page computes it and as Gradescope's autograder reads it.

use crate::args;
use anyhow::{Context, Result, anyhow, bail};
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::assignments;
use slamlab_sim::coursework::assignment::MAX_ASSIGNMENT_BYTES;
use slamlab_sim::coursework::{Assignment, Grade, Prepared};
use slamlab_sim::io::trajectory::MAX_TRAJECTORY_BYTES;
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

fn assignment_arg() -> Arg {
    Arg::new("assignment")
        .required(true)
        .value_name("ASSIGNMENT")
        .help("a built-in assignment (ekf-slam, mcl, pose-graph, grid-mapping, icp, two-view, fusion) or an assignment JSON file")
}

/// The `export-inputs` subcommand.
pub fn export_command() -> Command {
    Command::new("export-inputs")
        .about("Write one student's inputs of an assignment (the page's Download inputs)")
        .long_about(
            "Write one student's inputs of an assignment into a folder: the data files in the \
             formats courses use (Freiburg world.dat and sensor_data.dat, controls and measurements \
             CSV, a ROS map and a CARMEN log), README.txt with each file's format, units and frames, \
             and starter.py (Python 3 with numpy) that writes a naive estimate. The student's id \
             (any text, e.g. an e-mail address) seeds the run: the same id gives the same bytes here \
             and in the page. --answers adds answers/ (the true trajectory in TUM format and the true \
             landmarks) for the instructor. See docs/assignments.md.",
        )
        .arg(assignment_arg())
        .arg(
            args::named("student", "ID", "the student's id, e.g. an e-mail address").required(true),
        )
        .arg(
            args::path("out", "DIR", "the folder to write (made if missing)").required(true),
        )
        .arg(
            args::switch("answers", "add answers/: the true trajectory and map (for the instructor)"),
        )
        .arg(
            args::switch("force", "overwrite files of the same names already in the folder"),
        )
}

/// The `grade` subcommand.
pub fn grade_command() -> Command {
    Command::new("grade")
        .about("Grade a student's estimate (or a class's) as the assignment's page does")
        .long_about(
            "Grade a handed-in estimate against the student's variant: each criterion of the \
             assignment (metric, value, threshold, points, pass), beside the reference \
             estimators' values on the same variant, the score and whether it passes. --json \
             prints the grade as JSON; --gradescope FILE writes Gradescope's results.json (score, \
             max_score, one test per criterion), so the same check runs as a Gradescope \
             autograder. --students roster.csv --estimates DIR grades a class into one CSV: the \
             roster's 'student' column (or its first) names each student, whose estimate is \
             DIR/<student>.tum, .csv, .txt, .g2o or .zip, or DIR/<student>/<the assignment's output file>.",
        )
        .arg(assignment_arg())
        .arg(
            args::named("student", "ID", "the student's id, as they gave it for their inputs").conflicts_with("students").requires("estimate"),
        )
        .arg(
            args::path("estimate", "FILE", "the student's estimate: a TUM or CSV trajectory, or the assignment's output (an optimized g2o graph; a ROS map as a zip, or its YAML with the image beside it; a relative pose)").requires("student"),
        )
        .arg(
            args::switch("json", "print the grade as JSON"),
        )
        .arg(
            args::path("gradescope", "FILE", "also write Gradescope's results.json to FILE").conflicts_with("students"),
        )
        .arg(
            args::path("students", "ROSTER", "a roster CSV: grade every student in it").requires("estimates"),
        )
        .arg(
            args::path("estimates", "DIR", "the folder of the class's estimates").requires("students"),
        )
        .arg(
            args::path("out", "FILE", "write the class's CSV to FILE (default: standard output)").requires("students"),
        )
        .group(
            clap::ArgGroup::new("who")
                .args(["student", "students"])
                .required(true),
        )
}

/// A built-in assignment by name, or an assignment JSON file by path.
fn load_assignment(m: &ArgMatches) -> Result<Assignment> {
    let name = m
        .get_one::<String>("assignment")
        .ok_or_else(|| anyhow!("name an assignment"))?;
    let path = Path::new(name);
    let is_file = name.ends_with(".json") || path.is_file();
    if !is_file {
        return assignments::builtin(name).map_err(|e| anyhow!("{e}"));
    }
    let bytes = read_capped(path, MAX_ASSIGNMENT_BYTES)?;
    assignments::read(&path.display().to_string(), &bytes).map_err(|e| anyhow!("{e}"))
}

/// A file's bytes, refused over `cap` before it is read.
fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>> {
    let size = std::fs::metadata(path)
        .with_context(|| format!("cannot read {}", path.display()))?
        .len();
    if size > cap {
        bail!(
            "{}: {size} bytes, more than the {cap} this file may have",
            path.display()
        );
    }
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

fn prepare(assignment: &Assignment, student: &str) -> Result<Prepared> {
    if student.trim().is_empty() {
        bail!("--student is empty: give the student's id, e.g. their e-mail address");
    }
    assignments::prepare(assignment, student).map_err(|e| anyhow!("{e}"))
}

/// The variant of `--student`.
fn prepare_student(m: &ArgMatches, assignment: &Assignment) -> Result<Prepared> {
    let student = m
        .get_one::<String>("student")
        .ok_or_else(|| anyhow!("--student is required"))?;
    prepare(assignment, student)
}

/// Runs `slamlab export-inputs`.
pub fn run_export(m: &ArgMatches, out: &mut dyn Write) -> Result<()> {
    let assignment = load_assignment(m)?;
    let prepared = prepare_student(m, &assignment)?;
    let dir = m
        .get_one::<PathBuf>("out")
        .ok_or_else(|| anyhow!("--out is required"))?;
    let files = prepared.input_files(m.get_flag("answers"));
    if !m.get_flag("force") {
        let existing: Vec<&str> = files
            .paths()
            .into_iter()
            .filter(|p| dir.join(p).exists())
            .collect();
        if !existing.is_empty() {
            bail!(
                "{} already holds {}: give another folder, or --force to overwrite them",
                dir.display(),
                existing.join(", ")
            );
        }
    }
    for (path, bytes) in &files.files {
        let target = dir.join(path);
        if let Some(parent) = target.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("cannot make {}", parent.display()))?;
        }
        std::fs::write(&target, bytes)
            .with_context(|| format!("cannot write {}", target.display()))?;
    }
    writeln!(
        out,
        "{}: variant {} of {:?} ({} steps) in {}:",
        assignment.id,
        prepared.variant.code,
        prepared.variant.student,
        prepared.steps,
        dir.display()
    )?;
    write!(out, "{}", files.listing())?;
    Ok(())
}

fn grade_file(prepared: &Prepared, path: &Path) -> Result<Grade> {
    let name = path.display().to_string();
    let bytes = match yaml_and_image(path)? {
        Some(zip) => zip,
        None => read_capped(path, MAX_TRAJECTORY_BYTES)?,
    };
    prepared.grade(&name, &bytes).map_err(|e| anyhow!("{e}"))
}

/// A ROS map given by its YAML: the YAML and the image it names (beside it),
/// zipped as a map is handed in. `None` for any other file.
fn yaml_and_image(path: &Path) -> Result<Option<Vec<u8>>> {
    use slamlab_sim::io::ros_map::{MAX_YAML_BYTES, parse_map_yaml};
    let is_yaml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"));
    if !is_yaml {
        return Ok(None);
    }
    let yaml = read_capped(path, MAX_YAML_BYTES as u64)?;
    let text = String::from_utf8(yaml.clone())
        .map_err(|_| anyhow!("{}: not UTF-8 text", path.display()))?;
    let parsed = parse_map_yaml(&text).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let image = path
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .join(&parsed.image);
    let image_bytes = read_capped(&image, slamlab_sim::io::map_archive::MAX_IMAGE_BYTES as u64)
        .with_context(|| format!("{} names the image {:?}", path.display(), parsed.image))?;
    let file_name = |p: &Path| {
        p.file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    };
    let zip = slamlab_sim::io::archive::write_zip(
        "map",
        &[(file_name(path), yaml), (file_name(&image), image_bytes)],
    )
    .map_err(|e| anyhow!("{e}"))?;
    Ok(Some(zip))
}

/// Runs `slamlab grade`.
pub fn run_grade(m: &ArgMatches, out: &mut dyn Write) -> Result<()> {
    let assignment = load_assignment(m)?;
    if let Some(roster) = m.get_one::<PathBuf>("students") {
        let dir = m
            .get_one::<PathBuf>("estimates")
            .ok_or_else(|| anyhow!("--estimates DIR is required with --students"))?;
        let csv = grade_class(&assignment, roster, dir)?;
        return match m.get_one::<PathBuf>("out") {
            Some(path) => std::fs::write(path, csv)
                .with_context(|| format!("cannot write {}", path.display())),
            None => Ok(write!(out, "{csv}")?),
        };
    }
    let prepared = prepare_student(m, &assignment)?;
    let estimate = m
        .get_one::<PathBuf>("estimate")
        .ok_or_else(|| anyhow!("--estimate is required"))?;
    let grade = grade_file(&prepared, estimate)?;
    if let Some(path) = m.get_one::<PathBuf>("gradescope") {
        let text = serde_json::to_string_pretty(&grade.gradescope())?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if m.get_flag("json") {
        writeln!(out, "{}", serde_json::to_string_pretty(&grade)?)?;
    } else {
        write!(out, "{}", grade_text(&grade))?;
    }
    Ok(())
}

/// The grade as a student reads it.
pub fn grade_text(g: &Grade) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} ({}), variant {} of {:?}",
        g.title, g.assignment, g.variant, g.student
    );
    let _ = writeln!(
        s,
        "estimate: {} ({} bytes, SHA-256 {})",
        g.estimate_file, g.estimate_bytes, g.estimate_sha256
    );
    for c in &g.criteria {
        let _ = writeln!(s, "  {}", c.summary());
        let _ = writeln!(s, "      on your variant: {}", c.references_summary());
    }
    for n in &g.notices {
        let _ = writeln!(s, "  note: {n}");
    }
    let _ = writeln!(
        s,
        "score {} of {} (pass: {}): {}",
        g.score,
        g.max_score,
        g.pass_score,
        if g.pass { "PASS" } else { "FAIL" }
    );
    s
}

/// The roster's students: the column named `student` (or `email`, `id`), or
/// the first; a header row is recognised by such a name.
fn roster_students(path: &Path) -> Result<Vec<String>> {
    let bytes = read_capped(path, 4 << 20)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| anyhow!("{}: not a text file (UTF-8 CSV)", path.display()))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty()).peekable();
    let mut column = 0;
    if let Some(first) = lines.peek() {
        let names: Vec<String> = first
            .split(',')
            .map(|c| c.trim().trim_matches('"').to_ascii_lowercase())
            .collect();
        if let Some(k) = names
            .iter()
            .position(|n| matches!(n.as_str(), "student" | "email" | "id" | "sid"))
        {
            column = k;
            lines.next();
        }
    }
    let students: Vec<String> = lines
        .map(|l| {
            l.split(',')
                .nth(column)
                .unwrap_or("")
                .trim()
                .trim_matches('"')
                .to_owned()
        })
        .filter(|s| !s.is_empty())
        .collect();
    if students.is_empty() {
        bail!("{}: no student in the roster", path.display());
    }
    Ok(students)
}

/// The estimate of `student` in `dir`, if there is one.
fn estimate_of(dir: &Path, student: &str, output_file: &str) -> Option<PathBuf> {
    if student.contains(['/', '\\']) || student.starts_with('.') {
        return None;
    }
    ["tum", "csv", "txt", "g2o", "zip"]
        .iter()
        .map(|ext| dir.join(format!("{student}.{ext}")))
        .chain([dir.join(student).join(output_file)])
        .find(|p| p.is_file())
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// Grades every student of the roster; one CSV row each (a missing or refused
/// estimate scores 0 and says why).
fn grade_class(assignment: &Assignment, roster: &Path, dir: &Path) -> Result<String> {
    let students = roster_students(roster)?;
    let mut csv = String::from("student,variant,score,max_score,pass");
    for c in &assignment.criteria {
        let _ = write!(csv, ",{}", c.metric.name());
    }
    csv.push_str(",estimate,estimate_sha256,error\n");
    for student in &students {
        let prepared = prepare(assignment, student)?;
        let row = match estimate_of(dir, student, &assignment.output.file) {
            None => Err(anyhow!(
                "no estimate: looked for {student}.tum, .csv, .txt, .g2o, .zip and {student}/{}",
                assignment.output.file
            )),
            Some(path) => grade_file(&prepared, &path),
        };
        let _ = write!(csv, "{},{}", csv_field(student), prepared.variant.code);
        match row {
            Ok(g) => {
                let _ = write!(csv, ",{},{},{}", g.score, g.max_score, g.pass);
                for c in &g.criteria {
                    let _ = write!(csv, ",{}", c.value.map_or(String::new(), |v| v.to_string()));
                }
                let _ = writeln!(
                    csv,
                    ",{},{},",
                    csv_field(&g.estimate_file),
                    g.estimate_sha256
                );
            }
            Err(e) => {
                let _ = write!(csv, ",0,{},false", assignment.max_score());
                for _ in &assignment.criteria {
                    csv.push(',');
                }
                let _ = writeln!(csv, ",,,{}", csv_field(&format!("{e:#}")));
            }
        }
    }
    Ok(csv)
}
