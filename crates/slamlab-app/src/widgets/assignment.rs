//! Homework in the page: `assignment=ekf-slam&student=ada@uni.edu` (a built-in
//! assignment) or `assignment=hw3.json` (an instructor's assignment file beside
//! the page, fetched as `map=` and `estimate=` files are).
//!
//! The *Assignment* window shows the task, the student's variant, *Download
//! inputs* (the same zip, byte for byte, as `slamlab export-inputs` writes for the
//! same student: [`Prepared::zip`]), and takes the student's output (dropped on
//! the page or opened here). Each handed-in file is graded by
//! [`Prepared::grade`], exactly as `slamlab grade` grades it: each criterion with
//! the student's value, the threshold, the points and pass or fail, beside the
//! reference estimators' values on the same variant, and the score. A report
//! (JSON, and a picture of the page) names the assignment, the variant and the
//! SHA-256 of the graded file.
//!
//! The desk knows no lesson: the shell opens the assignment's lesson with
//! [`Prepared::lesson_pairs`] (the variant's seed and parameters), routes dropped
//! estimates here, and draws a graded trajectory on the lesson's map through the
//! lesson's estimates ([`crate::widgets::estimates`]). New kinds of assignment
//! work here unchanged: only `Prepared`'s generic API is used.

use crate::export::ExportFile;
use crate::palette;
use crate::widgets::fetch::Fetch;
use crate::widgets::file_picker::{FilePicker, PickedFile};
use slamlab_sim::coursework::grade::format_value;
use slamlab_sim::coursework::{Assignment, Grade, Prepared};

/// The most graded files the window keeps (the oldest goes first).
pub const MAX_HANDED_IN: usize = 16;

/// Is `source` an assignment file (`hw3.json`, `homework/hw3.json`) rather than
/// a built-in assignment's name?
pub fn is_file(source: &str) -> bool {
    source.to_ascii_lowercase().ends_with(".json") || source.contains('/')
}

/// The lesson's pairs of an assignment link: the variant's (its seed and the
/// assignment's parameters: [`Prepared::lesson_pairs`]), then the link's other
/// lesson pairs (`estimator=ekf,ukf`). A link pair that would change the
/// variant's run is left out with a notice that names it; the same value (a
/// share link of the page) is no change.
pub fn variant_pairs(
    variant: &[(String, String)],
    link: &[(String, String)],
) -> (Vec<(String, String)>, Vec<String>) {
    let same = |a: &str, b: &str| {
        a == b || matches!((a.parse::<f64>(), b.parse::<f64>()), (Ok(x), Ok(y)) if x == y)
    };
    let mut pairs = variant.to_vec();
    let mut notices = Vec::new();
    for (key, value) in link {
        match variant.iter().find(|(k, _)| k == key) {
            Some((_, theirs)) if !same(theirs, value) => notices.push(format!(
                "link: {key} = {value} is left out: the assignment's variant sets {key} = {theirs}, the run your inputs come from"
            )),
            Some(_) => {}
            None => pairs.push((key.clone(), value.clone())),
        }
    }
    (pairs, notices)
}

/// Where the desk is: reading the assignment, waiting for the student's id,
/// ready, or stopped by a problem.
#[derive(Debug)]
enum Stage {
    /// The assignment file is being read (the fetch starts in the first frame).
    Fetching(Option<Fetch>),
    /// The assignment is known; the student has not said who they are.
    NeedsStudent(Box<Assignment>),
    /// The student's variant, run.
    Ready(Box<Prepared>),
    /// Why there is no assignment.
    Failed(String),
}

/// One graded file.
#[derive(Clone, Debug)]
pub struct HandedIn {
    /// The grade (file name, SHA-256, criteria, score).
    pub grade: Grade,
}

/// What the window asks the shell to do.
#[derive(Debug)]
pub enum DeskAction {
    /// Save a file (the inputs' zip, the report).
    Save(ExportFile),
    /// Save the report of the grade shown (JSON).
    Report,
    /// Save a picture of the window with the grade shown.
    Picture,
    /// The variant changed (the student typed their id): open the lesson on it.
    OpenVariant,
    /// Files picked with "Open your estimate…", to hand in.
    HandIn(Vec<PickedFile>),
}

/// The homework of the page: the assignment, the student's variant and the
/// files graded so far.
#[derive(Debug)]
pub struct AssignmentDesk {
    source: String,
    student: Option<String>,
    stage: Stage,
    handed_in: Vec<HandedIn>,
    selected: usize,
    /// The window is open.
    pub open: bool,
    /// The last refusal of a handed-in file (or of the student's id).
    pub message: Option<String>,
    picker: FilePicker,
    student_field: String,
    /// Fold the task text in the next frame (a grade arrived).
    fold_task: bool,
}

impl AssignmentDesk {
    /// The desk for `assignment=source` and `student=`: a built-in assignment
    /// is run at once; a file is fetched in the first frames ([`Self::poll`]).
    pub fn new(source: &str, student: Option<&str>) -> Self {
        let mut desk = Self {
            source: source.to_owned(),
            student: student.map(str::to_owned),
            stage: Stage::Fetching(None),
            handed_in: Vec::new(),
            selected: 0,
            open: true,
            message: None,
            picker: FilePicker::multiple(),
            student_field: student.unwrap_or_default().to_owned(),
            fold_task: false,
        };
        if !is_file(source) {
            desk.stage = match slamlab_sim::assignments::builtin(source) {
                Ok(assignment) => desk.run_variant(assignment),
                Err(e) => Stage::Failed(format!("assignment = '{source}': {e}")),
            };
        }
        desk
    }

    /// The variant of the student (if known) of `assignment`.
    fn run_variant(&self, assignment: Assignment) -> Stage {
        match &self.student {
            None => Stage::NeedsStudent(Box::new(assignment)),
            Some(student) => match slamlab_sim::assignments::prepare(&assignment, student) {
                Ok(prepared) => Stage::Ready(Box::new(prepared)),
                Err(e) => Stage::Failed(format!("assignment {}: {e}", assignment.id)),
            },
        }
    }

    /// Reads the assignment file once it arrives. True when the variant became
    /// ready this frame (the shell then opens its lesson); a refusal is
    /// [`Self::problem`].
    pub fn poll(&mut self, ctx: &egui::Context) -> bool {
        let Stage::Fetching(fetch) = &mut self.stage else {
            return false;
        };
        let Some(fetch) = fetch else {
            self.stage = Stage::Fetching(Some(Fetch::start(&self.source, ctx)));
            return false;
        };
        let Some(result) = fetch.poll() else {
            return false;
        };
        let name = self
            .source
            .rsplit('/')
            .next()
            .unwrap_or(&self.source)
            .to_owned();
        self.stage = match result
            .map_err(|why| format!("assignment = '{}': {why}", self.source))
            .and_then(|bytes| {
                slamlab_sim::assignments::read(&name, &bytes).map_err(|e| e.to_string())
            }) {
            Ok(assignment) => self.run_variant(assignment),
            Err(why) => Stage::Failed(why),
        };
        self.prepared().is_some()
    }

    /// The student's variant, run, once it is ready.
    pub fn prepared(&self) -> Option<&Prepared> {
        match &self.stage {
            Stage::Ready(p) => Some(p),
            _ => None,
        }
    }

    /// The assignment, once it is read.
    pub fn assignment(&self) -> Option<&Assignment> {
        match &self.stage {
            Stage::Ready(p) => Some(&p.assignment),
            Stage::NeedsStudent(a) => Some(a),
            _ => None,
        }
    }

    /// Why there is no assignment, if there is none.
    pub fn problem(&self) -> Option<&str> {
        match &self.stage {
            Stage::Failed(why) => Some(why),
            _ => None,
        }
    }

    /// `assignment=` as the link gave it.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The student, once known.
    pub fn student(&self) -> Option<&str> {
        self.student.as_deref()
    }

    /// Makes the desk `student`'s: runs their variant. The files graded for
    /// another variant stay in the list (each grade names its variant).
    pub fn set_student(&mut self, student: &str) -> Result<(), String> {
        let student = student.trim();
        if student.is_empty() || student.chars().count() > crate::query::MAX_STUDENT_CHARS {
            return Err(format!(
                "Type your id (1 to {} characters, such as your e-mail address): the same id gives the same inputs everywhere",
                crate::query::MAX_STUDENT_CHARS
            ));
        }
        let Some(assignment) = self.assignment().cloned() else {
            return Err("There is no assignment to make a variant of".to_owned());
        };
        self.student = Some(student.to_owned());
        self.stage = self.run_variant(assignment);
        match &self.stage {
            Stage::Failed(why) => Err(why.clone()),
            _ => Ok(()),
        }
    }

    /// Grades a handed-in file; the files graded before stay whatever this one
    /// holds. The refusal is [`Prepared::grade`]'s (another student's variant,
    /// another assignment, a file that is no trajectory), naming the file.
    pub fn hand_in(&mut self, name: &str, bytes: &[u8]) -> Result<&Grade, String> {
        let Some(prepared) = self.prepared() else {
            return Err(format!(
                "{name}: there is no assignment variant to grade it against yet{}",
                if self.student.is_none() {
                    " (type your id in the Assignment window first)"
                } else {
                    ""
                }
            ));
        };
        match prepared.grade(name, bytes) {
            Ok(grade) => {
                if self.handed_in.len() >= MAX_HANDED_IN {
                    self.handed_in.remove(0);
                }
                self.handed_in.push(HandedIn { grade });
                self.selected = self.handed_in.len() - 1;
                self.message = None;
                self.open = true;
                self.fold_task = self.handed_in.len() == 1;
                Ok(&self.handed_in[self.selected].grade)
            }
            Err(e) => {
                let text = e.to_string();
                let why = if text.starts_with(name) {
                    text
                } else {
                    format!("{name}: {text}")
                };
                self.message = Some(why.clone());
                self.open = true;
                Err(why)
            }
        }
    }

    /// The files graded so far, oldest first.
    pub fn handed_in(&self) -> &[HandedIn] {
        &self.handed_in
    }

    /// The grade shown in the window (the latest unless the student picked
    /// another).
    pub fn selected_grade(&self) -> Option<&Grade> {
        self.handed_in.get(self.selected).map(|h| &h.grade)
    }

    /// The inputs' zip, as *Download inputs* saves it (with `answers/` when the
    /// assignment includes them).
    pub fn inputs_zip(&self) -> Result<ExportFile, String> {
        inputs_zip(
            self.prepared()
                .ok_or_else(|| "No variant yet: type your id first".to_owned())?,
        )
    }

    /// The file names of the report of `grade`: `slamlab-<id>-<variant>-grade`.
    pub fn report_stem(grade: &Grade) -> String {
        format!("slamlab-{}-{}-grade", grade.assignment, grade.variant)
    }

    /// The report of the selected grade as JSON: the grade as `slamlab grade
    /// --json` prints it (assignment, student, variant, seed, each criterion with
    /// its references, score, max_score, pass, the estimate's name, size and
    /// SHA-256), with the steps of the variant's run and `link`, the page's query
    /// that opens the same variant.
    pub fn report_json(&self, link: &str) -> Option<ExportFile> {
        let grade = self.selected_grade()?;
        let mut value = serde_json::to_value(grade).ok()?;
        if let Some(map) = value.as_object_mut() {
            map.insert("format".to_owned(), "slamlab-grade-report".into());
            map.insert("version".to_owned(), 1.into());
            if let Some(p) = self.prepared() {
                map.insert("steps".to_owned(), p.steps.into());
            }
            map.insert("link".to_owned(), link.into());
        }
        let text = serde_json::to_string_pretty(&value).ok()?;
        Some(ExportFile {
            name: format!("{}.json", Self::report_stem(grade)),
            mime: "application/json",
            bytes: (text + "\n").into_bytes(),
        })
    }

    /// What the browser and UI tests read: the assignment, the variant, and
    /// each graded file's score.
    pub fn test_state(&self) -> serde_json::Value {
        let stage = match &self.stage {
            Stage::Fetching(_) => "reading",
            Stage::NeedsStudent(_) => "needs-student",
            Stage::Ready(_) => "ready",
            Stage::Failed(_) => "failed",
        };
        let graded: Vec<serde_json::Value> = self
            .handed_in
            .iter()
            .map(|h| {
                let g = &h.grade;
                serde_json::json!({
                    "file": g.estimate_file,
                    "sha256": g.estimate_sha256,
                    "variant": g.variant,
                    "score": g.score,
                    "max_score": g.max_score,
                    "pass": g.pass,
                    "criteria": g.criteria,
                })
            })
            .collect();
        serde_json::json!({
            "source": self.source,
            "stage": stage,
            "id": self.assignment().map(|a| a.id.clone()),
            "lesson": self.assignment().map(|a| a.lesson.clone()),
            "student": self.student,
            "variant": self.prepared().map(|p| p.variant.code.clone()),
            "seed": self.prepared().map(|p| p.variant.seed),
            "steps": self.prepared().map(|p| p.steps),
            "graded": graded,
            "message": self.message,
            "problem": self.problem(),
        })
    }

    /// The *Assignment* panel, on the right of the window beside the lesson
    /// (never over its map): the task, the variant, *Download inputs*, the
    /// hand-in, and the grade of the selected file beside the references.
    /// Call it before the lesson's panels, so the map fits the space left.
    pub fn panel_ui(&mut self, ui: &mut egui::Ui) -> Vec<DeskAction> {
        let mut actions = Vec::new();
        if let Some(files) = self.picker.poll_all() {
            actions.push(DeskAction::HandIn(files));
        }
        if !self.open {
            return actions;
        }
        let width = ui.available_width();
        egui::Panel::right("slamlab_assignment")
            .resizable(true)
            .default_size((0.36 * width).clamp(220.0, 360.0))
            .size_range(200.0..=(0.6 * width).max(220.0))
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.heading("Assignment");
                    ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                        if ui
                            .small_button("Hide")
                            .on_hover_text("Hide the Assignment panel (the Assignment button in the top bar shows it again)")
                            .clicked()
                        {
                            self.open = false;
                        }
                    });
                });
                egui::ScrollArea::vertical()
                    .id_salt("slamlab_assignment_scroll")
                    .auto_shrink([false, false])
                    .show(ui, |ui| self.contents_ui(ui, &mut actions));
            });
        actions
    }

    fn contents_ui(&mut self, ui: &mut egui::Ui, actions: &mut Vec<DeskAction>) {
        match &self.stage {
            Stage::Fetching(_) => {
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("Reading {}…", self.source));
                });
                return;
            }
            Stage::Failed(why) => {
                ui.colored_label(palette::VERMILLION, why);
                ui.label(format!(
                    "The built-in assignments are {}; an assignment file is named by its path beside the page (assignment=hw3.json).",
                    slamlab_sim::assignments::builtin_names().join(", ")
                ));
                return;
            }
            _ => {}
        }
        let fold_task = std::mem::take(&mut self.fold_task);
        if let Some(a) = self.assignment() {
            ui.label(egui::RichText::new(&a.title).strong());
            // Open at first; folded once a grade is there to read (the
            // student opens it again with a click).
            let id = ui.make_persistent_id("slamlab_assignment_task");
            let mut task = egui::collapsing_header::CollapsingState::load_with_default_open(
                ui.ctx(),
                id,
                true,
            );
            if fold_task {
                task.set_open(false);
            }
            let height = (0.2 * ui.ctx().content_rect().height()).clamp(60.0, 150.0);
            task.show_header(ui, |ui| ui.strong("Task")).body(|ui| {
                egui::ScrollArea::vertical()
                    .id_salt("assignment_task")
                    .max_height(height)
                    .show(ui, |ui| {
                        for paragraph in a.task.trim().split("\n\n") {
                            ui.label(paragraph.trim());
                        }
                    });
            });
        }
        if let Stage::NeedsStudent(_) = &self.stage {
            ui.label("Your id (such as your e-mail address) gives you your own inputs:");
            let mut go = false;
            ui.horizontal(|ui| {
                let label = ui.label("id");
                let field = ui
                    .add(
                        egui::TextEdit::singleline(&mut self.student_field)
                            .hint_text("you@uni.edu")
                            .desired_width(180.0),
                    )
                    .labelled_by(label.id);
                go = ui.button("Open my variant").clicked()
                    || (field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)));
            });
            if go {
                let typed = self.student_field.clone();
                match self.set_student(&typed) {
                    Ok(()) => actions.push(DeskAction::OpenVariant),
                    Err(why) => self.message = Some(why),
                }
            }
            if let Some(m) = &self.message {
                ui.colored_label(palette::VERMILLION, m);
            }
            return;
        }
        let Stage::Ready(p) = &self.stage else {
            return;
        };
        let a = &p.assignment;
        ui.label(format!(
            "Variant {} of {} (seed {}): {} steps, {} s. Hand in {}.",
            p.variant.code,
            p.variant.student,
            p.variant.seed,
            p.steps,
            format_value(p.truth().span().map_or(0.0, |s| s.1), ""),
            a.output.file
        ));
        let mut download = false;
        ui.horizontal_wrapped(|ui| {
            download = ui
                .button("Download inputs")
                .on_hover_text(format!(
                    "Your inputs ({}), README.txt and starter.py as a zip: the same files as `slamlab export-inputs {} --student '{}'`",
                    a.inputs
                        .iter()
                        .map(|f| f.name())
                        .collect::<Vec<_>>()
                        .join(", "),
                    a.id,
                    p.variant.student
                ))
                .clicked();
            self.picker.ui(
                ui,
                "Open your estimate…",
                ".tum,.txt,.csv,.g2o,.zip,.yaml,.pgm,.png,text/plain,text/csv",
                slamlab_sim::io::trajectory::MAX_TRAJECTORY_BYTES as usize,
                "path/to/estimate.tum",
            );
        });
        if download {
            match inputs_zip(p) {
                Ok(file) => actions.push(DeskAction::Save(file)),
                Err(why) => self.message = Some(why),
            }
        }
        ui.weak(format!(
            "Or drop your {} ({}) on the page.",
            a.output.file,
            a.output.format.name()
        ));
        if let Some(m) = &self.message {
            ui.colored_label(palette::VERMILLION, m);
        }
        if self.handed_in.is_empty() {
            ui.label(
                egui::RichText::new(format!(
                    "Scored by {}; pass at {} of {} points.",
                    a.criteria
                        .iter()
                        .map(|c| format!(
                            "{} {} {} ({} points)",
                            c.metric.label(),
                            c.direction().symbol(),
                            format_value(c.threshold, c.metric.unit()),
                            c.points
                        ))
                        .collect::<Vec<_>>()
                        .join(", "),
                    a.pass_score(),
                    a.max_score()
                ))
                .small(),
            );
            return;
        }
        ui.separator();
        if self.handed_in.len() > 1 {
            ui.horizontal_wrapped(|ui| {
                ui.label("Graded:");
                for (k, h) in self.handed_in.iter().enumerate() {
                    let g = &h.grade;
                    let text = format!(
                        "{} {}/{}",
                        g.estimate_file,
                        points(g.score),
                        points(g.max_score)
                    );
                    if ui.selectable_label(k == self.selected, text).clicked() {
                        self.selected = k;
                    }
                }
            });
        }
        let Some(g) = self.handed_in.get(self.selected).map(|h| &h.grade) else {
            return;
        };
        grade_ui(ui, g);
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Report (JSON)")
                .on_hover_text(
                    "The grade as a file: the assignment, your variant, each criterion, the score and the SHA-256 of your file",
                )
                .clicked()
            {
                actions.push(DeskAction::Report);
            }
            if ui
                .button("Picture (PNG)")
                .on_hover_text("The page as it is now: the lesson with your estimate, and this grade")
                .clicked()
            {
                actions.push(DeskAction::Picture);
            }
        });
    }
}

/// Points as a student reads them: `70`, `12.5`.
pub fn points(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e12 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

/// The variant's inputs as one zip (with `answers/` when the assignment
/// includes them), named as the command line's folder.
fn inputs_zip(prepared: &Prepared) -> Result<ExportFile, String> {
    let bytes = prepared
        .zip(prepared.assignment.answers_included)
        .map_err(|e| e.to_string())?;
    Ok(ExportFile {
        name: format!("{}.zip", prepared.folder_name()),
        mime: "application/zip",
        bytes,
    })
}

/// One grade: the file, each criterion beside the references, the score.
fn grade_ui(ui: &mut egui::Ui, g: &Grade) {
    ui.label(format!(
        "{} (SHA-256 {}…)",
        g.estimate_file,
        &g.estimate_sha256[..g.estimate_sha256.len().min(12)]
    ))
    .on_hover_text(&g.estimate_sha256);
    let references: Vec<String> = g
        .criteria
        .first()
        .map(|c| c.references.iter().map(|r| r.name.clone()).collect())
        .unwrap_or_default();
    // One column per criterion (an assignment has a few), one row per
    // number: narrow enough for a panel beside the map.
    egui::Grid::new("assignment_grade")
        .striped(true)
        .show(ui, |ui| {
            ui.label("");
            for c in &g.criteria {
                ui.strong(&c.label).on_hover_text(&c.metric);
            }
            ui.end_row();
            ui.strong("yours");
            for c in &g.criteria {
                let value = c
                    .value
                    .map_or("no value".to_owned(), |v| format_value(v, &c.unit));
                let colour = if c.pass {
                    palette::GREEN
                } else {
                    palette::VERMILLION
                };
                ui.colored_label(
                    colour,
                    egui::RichText::new(format!(
                        "{value}, {}",
                        if c.pass { "pass" } else { "fail" }
                    ))
                    .strong(),
                )
                .on_hover_text(c.summary());
            }
            ui.end_row();
            ui.label("pass if");
            for c in &g.criteria {
                let sign = if c.direction == "at-least" {
                    "≥"
                } else {
                    "≤"
                };
                ui.label(format!("{sign} {}", format_value(c.threshold, &c.unit)));
            }
            ui.end_row();
            ui.label("points");
            for c in &g.criteria {
                ui.label(format!("{} of {}", points(c.earned), points(c.points)));
            }
            ui.end_row();
            for name in &references {
                ui.label(name).on_hover_text(format!(
                    "The reference estimator {name} on your variant's inputs"
                ));
                for c in &g.criteria {
                    let text = c
                        .references
                        .iter()
                        .find(|r| &r.name == name)
                        .and_then(|r| r.value)
                        .map_or("–".to_owned(), |v| format_value(v, &c.unit));
                    ui.weak(text);
                }
                ui.end_row();
            }
        });
    let verdict = format!(
        "Score {} of {} (pass: {}): {}",
        points(g.score),
        points(g.max_score),
        points(g.pass_score),
        if g.pass { "PASS" } else { "FAIL" }
    );
    ui.label(egui::RichText::new(verdict).strong().color(if g.pass {
        palette::GREEN
    } else {
        palette::VERMILLION
    }));
    for n in &g.notices {
        ui.label(egui::RichText::new(n).small().weak());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_sim::io::trajectory::write_tum;

    #[test]
    fn built_in_names_and_files_are_told_apart() {
        assert!(!is_file("ekf-slam"));
        assert!(is_file("hw3.json"));
        assert!(is_file("HW3.JSON"));
        assert!(is_file("homework/hw3"));
    }

    #[test]
    fn the_variant_sets_the_run_and_the_link_adds_the_rest() {
        let pair = |k: &str, v: &str| (k.to_owned(), v.to_owned());
        let variant = [pair("range-std", "0.2"), pair("seed", "42")];
        let link = [
            pair("seed", "42"),
            pair("range-std", "0.20"),
            pair("estimator", "ekf,ukf"),
            pair("seed", "7"),
        ];
        let (pairs, notices) = variant_pairs(&variant, &link);
        assert_eq!(
            pairs,
            [
                pair("range-std", "0.2"),
                pair("seed", "42"),
                pair("estimator", "ekf,ukf")
            ]
        );
        assert_eq!(
            notices,
            [
                "link: seed = 7 is left out: the assignment's variant sets seed = 42, the run your inputs come from"
            ]
        );
    }

    #[test]
    fn an_unknown_assignment_says_which_there_are() {
        let desk = AssignmentDesk::new("ekf-slamm", Some("ada@uni.edu"));
        let why = desk.problem().unwrap_or_default();
        assert!(
            why.contains("'ekf-slamm'") && why.contains("ekf-slam, mcl"),
            "{why}"
        );
        assert!(desk.prepared().is_none());
    }

    /// The desk grades as `slamlab grade` does (the library's grade, to the
    /// bit); another student's file is refused with the grader's message and
    /// the grade already there stays.
    #[test]
    fn the_desk_grades_as_the_library_does_and_keeps_what_it_has() {
        let mut desk = AssignmentDesk::new("ekf-slam", None);
        assert!(desk.prepared().is_none());
        assert!(
            desk.hand_in("x.tum", b"")
                .unwrap_err()
                .contains("type your id")
        );
        assert!(desk.set_student("  ").is_err());
        desk.set_student("ada@uni.edu").unwrap();
        let prepared = desk.prepared().unwrap();
        let dead_reckoning = prepared
            .references()
            .unwrap()
            .iter()
            .find(|(n, _)| n == "dead-reckoning")
            .map(|(_, t)| write_tum(t))
            .unwrap();
        let expected = prepared.grade("dr.tum", dead_reckoning.as_bytes()).unwrap();
        let grade = desk.hand_in("dr.tum", dead_reckoning.as_bytes()).unwrap();
        assert_eq!(grade, &expected);
        assert!(!grade.pass);
        // Alan's variant is longer or shorter: refused, Ada's grade stays.
        let other = AssignmentDesk::new("ekf-slam", Some("alan@uni.edu"));
        let theirs = other.prepared().unwrap().references().unwrap()[0].1.clone();
        let why = desk
            .hand_in("theirs.tum", write_tum(&theirs).as_bytes())
            .unwrap_err();
        assert!(why.starts_with("theirs.tum: the estimate has"), "{why}");
        assert!(why.contains("another student's variant"), "{why}");
        assert_eq!(desk.handed_in().len(), 1);
        assert_eq!(desk.message.as_deref(), Some(why.as_str()));
        // The report names the assignment, the variant and the file's SHA-256.
        let report = desk
            .report_json("assignment=ekf-slam&student=ada%40uni.edu")
            .unwrap();
        assert_eq!(
            report.name,
            format!("slamlab-ekf-slam-{}-grade.json", expected.variant)
        );
        let json: serde_json::Value = serde_json::from_slice(&report.bytes).unwrap();
        assert_eq!(json["assignment"], "ekf-slam");
        assert_eq!(json["variant"], expected.variant.as_str());
        assert_eq!(json["seed"], expected.seed);
        assert_eq!(
            json["estimate_sha256"],
            slamlab_sim::coursework::sha256_hex(dead_reckoning.as_bytes())
        );
        assert_eq!(json["score"], expected.score);
        assert_eq!(json["max_score"], 100.0);
        assert_eq!(json["pass"], false);
        assert_eq!(json["criteria"].as_array().map(Vec::len), Some(2));
        assert_eq!(json["steps"], desk.prepared().unwrap().steps);
    }

    /// *Download inputs* is the command line's folder, zipped: the same bytes.
    #[test]
    fn the_download_is_the_libraries_zip() {
        let desk = AssignmentDesk::new("ekf-slam", Some("ada@uni.edu"));
        let file = desk.inputs_zip().unwrap();
        let prepared = desk.prepared().unwrap();
        assert_eq!(file.name, format!("{}.zip", prepared.folder_name()));
        assert_eq!(file.bytes, prepared.zip(false).unwrap());
        assert!(file.bytes.starts_with(b"PK\x03\x04"));
    }
}
