//! What the two lidar lessons (mapping and Cartographer) do alike with their
//! files, written once: they open from a link that may name a log and its
//! reference (`log=`, `reference=`, read after the first frame), hand each
//! file that arrives (dropped, picked or linked) to the lesson, and put the
//! linked files back into the share link. A lesson says only what a log, a
//! reference and a map do to its run ([`LaserLesson`]).

use crate::lesson::{self, Lesson, LessonFrame, LessonStart, LessonView};
use crate::widgets::laser_file::LaserFileState;
use crate::widgets::laser_inputs::{LaserInput, LaserInputs};

/// A lesson that maps laser logs: where its files and its frame are, and what
/// each kind of file does to it.
pub trait LaserLesson: Lesson + Sized + 'static {
    /// The lesson's view options.
    type View: LessonView;
    /// The lesson's frame (its note, its notices).
    fn laser_frame(&mut self) -> &mut LessonFrame<Self::View>;
    /// The laser file's state (a bag's topics, what the reader assumed).
    fn laser_file(&mut self) -> &mut LaserFileState;
    /// The files dropped, picked or named by the link.
    fn laser_inputs(&mut self) -> &mut LaserInputs;
    /// Maps a log dropped or picked.
    fn open_log(&mut self, name: &str, bytes: &[u8]);
    /// Maps the log `log=` named, read from `location`.
    fn open_linked_log(&mut self, name: &str, bytes: &[u8], location: String);
    /// Scores the run against a corrected log (`location`: where
    /// `reference=` read it from).
    fn open_reference(&mut self, name: &str, bytes: Vec<u8>, location: Option<String>);
    /// Lets the simulated robot explore a ROS map (its YAML and image).
    fn open_map(&mut self, files: &[(String, Vec<u8>)]);

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
                } => self.open_reference(&name, bytes, location),
                LaserInput::Map(files) => self.open_map(&files),
                LaserInput::Refused(why) => self.laser_frame().note = Some(why),
            }
        }
    }
}

/// Opens a lidar lesson from the URL's pairs, with what it stored last time
/// ([`lesson::open_lesson`]): `log=` and `reference=` are read after the first
/// frame (the note says the log is loading), the laser file's own pairs (a
/// bag's topics) go to its state, the rest are the scenario's. When `new`
/// refuses, the default lesson opens with "`title` could not open: why".
pub fn open<S, L>(
    start: &LessonStart<'_>,
    default: S,
    new: impl FnOnce(S) -> Result<L, String>,
    title: &str,
) -> Box<dyn Lesson>
where
    S: slamlab_sim::params::Scenario,
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
    let mut lesson = match lesson::open_lesson(start, default, new, L::laser_frame) {
        Ok(lesson) => lesson,
        Err(why) => return lesson::open_instead(start, format!("{title} could not open: {why}")),
    };
    *lesson.laser_file() = laser;
    if let Some(location) = &location {
        lesson.laser_frame().note = Some(format!("Loading the log {location}…"));
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
