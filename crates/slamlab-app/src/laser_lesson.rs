//! What the two lidar lessons (mapping and Cartographer) do alike with their
//! files, written once: they open from a link that may name a log and its
//! reference (`log=`, `reference=`, read after the first frame), hand each
//! file that arrives (dropped, picked or linked) to the lesson, and put the
//! linked files back into the share link. A lesson says only what a log, a
//! reference and a map do to its run ([`LaserLesson`]).

use crate::lesson::{self, Lesson, LessonFrame, LessonStart, LessonView};
use crate::widgets::laser_file::LaserFileState;
use crate::widgets::laser_inputs::{LaserInput, LaserInputs};
use slamlab_core::grid::OccupancyGrid;
use slamlab_sim::grid::MappingInput;
use std::sync::Arc;

/// A reference that came before its log: its name, bytes and where
/// `reference=` read it from.
pub type PendingReference = (String, Vec<u8>, Option<String>);

/// A lesson that maps laser logs: where its files are, and what each kind of
/// file does to it (its note is its frame's, [`Lesson::frame_mut`]).
pub trait LaserLesson: Lesson + Sized + 'static {
    /// Maps a log dropped or picked.
    fn open_log(&mut self, name: &str, bytes: &[u8]);
    /// Maps the log `log=` named, read from `location`.
    fn open_linked_log(&mut self, name: &str, bytes: &[u8], location: String);
    /// The input being mapped when it was read from a log (a reference is
    /// matched to a log's scans); `None` for a simulated run.
    fn logged_input(&self) -> Option<Arc<MappingInput>>;
    /// Where a reference waits for its log.
    fn pending_reference(&mut self) -> &mut Option<PendingReference>;
    /// Starts the run over on `input`, the log with its reference (read from
    /// `location`).
    fn restart_with_reference(&mut self, input: Arc<MappingInput>, location: Option<String>);
    /// Lets the simulated robot explore a ROS map (its YAML and image)
    /// instead of a built-in one; on any problem the run stays, with a note.
    fn load_map_files(&mut self, files: &[(String, Vec<u8>)]);
    /// The laser file's state (a bag's topics, what the reader assumed).
    fn laser_file(&mut self) -> &mut LaserFileState;
    /// The files dropped, picked or named by the link.
    fn laser_inputs(&mut self) -> &mut LaserInputs;

    /// Matches a corrected log (`bytes`) to the log being mapped and starts
    /// over with it as the reference; with no log yet, keeps it for the next.
    fn load_reference(&mut self, name: &str, bytes: Vec<u8>, location: Option<String>) {
        let Some(input) = self.logged_input() else {
            *self.pending_reference() = Some((name.to_owned(), bytes, location));
            *self.frame_mut().note_mut() = Some(format!(
                "{name} is a reference: it is scored against once its log is loaded"
            ));
            return;
        };
        let note = match input.reference_from(&bytes, name) {
            Ok(reference) => {
                let description = reference.description.clone();
                let mut with = (*input).clone();
                with.reference = Some(Arc::new(reference));
                self.restart_with_reference(Arc::new(with), location);
                format!("Reference {name}: {description}")
            }
            Err(why) => format!(
                "Could not use {name} as the reference: {why}; the mapping goes on without a score"
            ),
        };
        *self.frame_mut().note_mut() = Some(note);
    }

    /// Reads a ROS map dropped or picked (its YAML and image, or a lone image,
    /// `kidnap::session::load_dropped_map`): its name, grid and notes; on a
    /// problem the note says what it is and that the run goes on, and there
    /// is no map.
    fn read_map(
        &mut self,
        files: &[(String, Vec<u8>)],
    ) -> Option<(String, Arc<OccupancyGrid>, Vec<String>)> {
        match slamlab_sim::kidnap::session::load_dropped_map(files) {
            Ok((name, grid, notes)) => Some((name, Arc::new(grid), notes)),
            Err(why) => {
                *self.frame_mut().note_mut() =
                    Some(format!("Could not load the map: {why}; the run goes on"));
                None
            }
        }
    }

    /// Hands each file that arrived this frame to the lesson, in the order
    /// it arrived; a file that could not be read becomes the lesson's note.
    fn read_laser_inputs(&mut self, ctx: &egui::Context) {
        for input in self.laser_inputs().poll(ctx) {
            match input {
                LaserInput::Log {
                    name,
                    bytes,
                    location: Some(location),
                } => self.open_linked_log(&name, &bytes, location),
                LaserInput::Log { name, bytes, .. } => self.open_log(&name, &bytes),
                LaserInput::Reference {
                    name,
                    bytes,
                    location,
                } => self.load_reference(&name, bytes, location),
                LaserInput::Map(files) => self.load_map_files(&files),
                LaserInput::Refused(why) => *self.frame_mut().note_mut() = Some(why),
            }
        }
    }
}

/// Opens a lidar lesson from the URL's pairs, with what it stored last time
/// ([`lesson::open_lesson`]): `log=` and `reference=` are read after the first
/// frame (the note says the log is loading), the laser file's own pairs (a
/// bag's topics) go to its state, the rest are the scenario's; `frame` reaches
/// the lesson's frame. When `new` refuses, the default lesson opens with
/// "`title` could not open: why".
pub fn open<S, V, L>(
    start: &LessonStart<'_>,
    default: S,
    new: impl FnOnce(S) -> Result<L, String>,
    frame: impl FnOnce(&mut L) -> &mut LessonFrame<V>,
    title: &str,
) -> Box<dyn Lesson>
where
    S: slamlab_sim::params::Scenario,
    V: LessonView,
    L: LaserLesson,
{
    let location = start.last_value("log");
    let reference = start.last_value("reference");
    let (laser, pairs) =
        LaserFileState::from_link(start.pairs, |k, _| k == "log" || k == "reference");
    let start = &LessonStart {
        pairs: &pairs,
        ..*start
    };
    let mut lesson = match lesson::open_lesson(start, default, new, frame) {
        Ok(lesson) => lesson,
        Err(why) => return lesson::open_instead(start, format!("{title} could not open: {why}")),
    };
    *lesson.laser_file() = laser;
    if let Some(location) = &location {
        *lesson.frame_mut().note_mut() = Some(format!("Loading the log {location}…"));
    }
    lesson.laser_inputs().link(location, reference);
    Box::new(lesson)
}

/// The share link's pairs for the files: `log=` where the log came from a
/// link (`log`), then `reference=` where the reference did, then the laser
/// file's own pairs (a bag's topics). A dropped log has no location: none.
pub fn share_pairs(
    log: Option<&str>,
    reference: Option<&str>,
    laser: &LaserFileState,
) -> Vec<(String, String)> {
    let Some(log) = log else {
        return Vec::new();
    };
    let mut pairs = vec![("log".to_owned(), log.to_owned())];
    if let Some(reference) = reference {
        pairs.push(("reference".to_owned(), reference.to_owned()));
    }
    pairs.extend(laser.share_pairs());
    pairs
}
