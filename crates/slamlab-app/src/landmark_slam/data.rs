//! The world a landmark run plays in: the simulated one, or a recorded data set
//! (UTIAS MRCLAM, the Freiburg course's files, Victoria Park) opened with the file
//! picker, dropped on the window, or named by `data=` in the URL (a file or zip
//! beside the page, as `log=` is for the mapping lesson).
//!
//! The files are read by [`slamlab_sim::io::landmark_data`]; a refusal names the
//! file and line and leaves the running world as it was.

use super::LandmarkSlamLesson;
use crate::widgets::dropped_files::DropInbox;
use crate::widgets::fetch::Fetch;
use crate::widgets::file_picker::{FilePicker, PickedFile};
use crate::widgets::sources;
use slamlab_sim::io::landmark_data::{DataFile, DataSetKind, LandmarkData, read_landmark_data};
use slamlab_sim::world::landmark_scenario::MapMode;
use std::sync::Arc;

/// The URL key that names a data set beside the page.
pub const DATA_KEY: &str = "data";

/// The largest set of files the picker hands over, bytes (the readers cap each
/// file at 64 MiB).
pub const MAX_PICKED_BYTES: usize = 64 << 20;

/// A data set the lesson has open.
#[derive(Clone, Debug)]
pub struct LoadedData {
    /// The data as read.
    pub data: Arc<LandmarkData>,
    /// What the user opened: the zip's or the first file's name.
    pub name: String,
    /// Where `data=` read it from (kept for share links); `None` for a drop or a pick.
    pub location: Option<String>,
    /// A reference pose graph given with the files (Victoria Park's
    /// `victoria_park.txt`): its name and text.
    pub reference: Option<(String, String)>,
}

/// A data set being read from `data=`.
#[derive(Debug)]
struct DataFetch {
    location: String,
    started: bool,
    fetch: Fetch,
}

/// The ways a data set arrives: the picker, a drop, `data=`.
#[derive(Debug)]
pub struct DataInput {
    /// "Open data set…".
    pub picker: FilePicker,
    inbox: DropInbox,
    fetch: Option<DataFetch>,
}

impl Default for DataInput {
    fn default() -> Self {
        Self {
            picker: FilePicker::multiple(),
            inbox: DropInbox::default(),
            fetch: None,
        }
    }
}

/// What arrived this frame.
#[derive(Debug)]
pub enum Arrival {
    /// A data set, read.
    Data(LoadedData),
    /// Files that could not be read or are no data set: the message says which and why.
    Refused(String),
    /// A reference pose graph alone (for the data set already open): its name and text.
    Reference(String, String),
}

impl DataInput {
    /// Reads `location` on the next poll.
    pub fn fetch(&mut self, location: String) {
        self.fetch = Some(DataFetch {
            location,
            started: false,
            fetch: Fetch::default(),
        });
    }

    /// Is a `data=` request under way?
    pub fn is_fetching(&self) -> bool {
        self.fetch.is_some()
    }

    /// A data set that arrived this frame (picked, dropped or fetched), read.
    pub fn poll(&mut self, ctx: &egui::Context) -> Option<Arrival> {
        if let Some(state) = self.fetch.as_mut() {
            if !state.started {
                state.started = true;
                state.fetch = Fetch::start(&state.location, ctx);
            } else if let Some(result) = state.fetch.poll() {
                let location = state.location.clone();
                self.fetch = None;
                let name = location.rsplit('/').next().unwrap_or(&location).to_owned();
                return Some(match result {
                    Ok(bytes) => read(vec![(name, Ok(bytes))], Some(location)),
                    Err(why) => {
                        Arrival::Refused(format!("Could not load the data set {location}: {why}"))
                    }
                });
            }
        }
        let picked = self.picker.poll_all();
        let batch = self.inbox.poll(ctx).or(picked)?;
        Some(read(batch, None))
    }
}

/// Reads the files of one pick, drop or request as one data set.
pub fn read(batch: Vec<PickedFile>, location: Option<String>) -> Arrival {
    let mut files = Vec::new();
    let mut reference = None;
    for (name, bytes) in batch {
        match bytes {
            Ok(bytes) if super::reference::is_reference_graph(&name, &bytes) => {
                let base = name.rsplit(['/', '\\']).next().unwrap_or(&name).to_owned();
                reference = Some((base, String::from_utf8_lossy(&bytes).into_owned()));
            }
            Ok(bytes) => files.push(DataFile::new(name, bytes)),
            Err(why) => return Arrival::Refused(format!("Could not read {name}: {why}")),
        }
    }
    if files.is_empty()
        && let Some((name, text)) = reference
    {
        return Arrival::Reference(name, text);
    }
    let name = match files.as_slice() {
        [] => return Arrival::Refused("No file was given".to_owned()),
        [one] => one.base_name().to_owned(),
        [first, ..] => format!("{} and {} more", first.base_name(), files.len() - 1),
    };
    match read_landmark_data(files) {
        Ok(data) => Arrival::Data(LoadedData {
            data: Arc::new(data),
            name,
            location,
            reference,
        }),
        Err(why) => Arrival::Refused(format!("Could not open {name}: {why}")),
    }
}

/// The `data=` location among the URL's pairs (the last one given).
pub fn location(pairs: &[(String, String)]) -> Option<String> {
    pairs
        .iter()
        .rev()
        .find(|(k, _)| k == DATA_KEY)
        .map(|(_, v)| v.clone())
        .filter(|v| !v.trim().is_empty())
}

/// The key of a data set's entry in the Sources window.
pub fn source_key(kind: DataSetKind) -> &'static str {
    match kind {
        DataSetKind::Mrclam => "mrclam",
        DataSetKind::Freiburg => "freiburg-data",
        DataSetKind::VictoriaPark => "victoria-park",
    }
}

/// The "World" box at the top of the lesson's left panel: which world runs, its
/// source and citation, how to open a data set, and for a data set the robot
/// (MRCLAM) and the mode. The robot and the mode apply at once (a new run).
pub fn world_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) {
    ui.heading("World");
    let world = lesson.session.recorded_world().cloned();
    match &world {
        None => {
            ui.label("Simulated: the robot, its noise and the landmarks come from the parameters.");
        }
        Some(world) => {
            let source = world.source();
            ui.label(egui::RichText::new(&world.name).strong());
            ui.horizontal_wrapped(|ui| {
                ui.label(source.title);
                sources::source_link(ui, source_key(world.kind), "(source and citation)");
            });
            let (played, steps) = lesson.session.recorded_progress().unwrap_or_default();
            ui.label(format!(
                "{played} of {steps} steps played ({:.0} s of data)",
                world.duration()
            ));
            if world.truth.is_none() {
                ui.label(if world.reference.is_empty() {
                    "No true path in these files, so the robot-error and NEES plots stay empty."
                } else {
                    "No true path: the GPS is the only independent reference, and it is no \
                     truth (metres off under the trees, with dropouts), so the error plots stay \
                     empty."
                });
            }
            if !world.reference.is_empty() {
                ui.label(gps_text(super::gps_fit_now(&lesson.session).as_ref()));
            }
            if world.kind == DataSetKind::VictoriaPark {
                let version = lesson.version;
                let lines = lesson.reference.lines(&lesson.session, version);
                if lines.is_empty() {
                    ui.label(
                        egui::RichText::new(
                            "Drop victoria_park.txt (gtsam's pose graph of this drive) to lay \
                             its solved trees over the filters as the reference map.",
                        )
                        .small(),
                    );
                }
                for line in lines {
                    ui.label(line);
                }
            }
        }
    }
    if let Some(LandmarkData::Mrclam(data)) = lesson.data.as_ref().map(|d| d.data.as_ref()) {
        let robots: Vec<u32> = data.robots.iter().map(|r| r.number).collect();
        let mut robot = lesson.session.scenario().robot;
        ui.horizontal(|ui| {
            ui.label("robot");
            for number in &robots {
                ui.radio_value(&mut robot, *number, number.to_string())
                    .on_hover_text(format!(
                        "Replay robot {number}; the others' sightings are drawn greyed"
                    ));
            }
        });
        if robot != lesson.session.scenario().robot
            && lesson.set_param("robot", &robot.to_string()).is_none()
        {
            lesson.reset();
        }
    }
    if world.as_ref().is_some_and(|w| !w.landmarks.is_empty()) {
        let running = lesson.session.scenario().mode;
        let mut mode = running;
        ui.horizontal(|ui| {
            ui.label("mode");
            ui.radio_value(&mut mode, MapMode::Slam, "SLAM")
                .on_hover_text("The landmarks are unknown: each starts at its first sighting");
            ui.radio_value(&mut mode, MapMode::Localization, "localization")
                .on_hover_text("The surveyed landmarks are given as the map");
        });
        if mode != running && lesson.set_param("mode", mode.name()).is_none() {
            lesson.reset();
        }
    }
    lesson.data_input.picker.ui(
        ui,
        "Open data set…",
        ".zip,.dat,.txt",
        MAX_PICKED_BYTES,
        "path/to/MRCLAM_Dataset6.zip",
    );
    ui.label(
        egui::RichText::new(
            "Or drop on the window: the MRCLAM zip (or its .dat files together), the Freiburg \
             course's world.dat with sensor_data.dat, or Victoria Park's inputs.dat, \
             measurements.dat and gps.dat (with victoria_park.txt for the reference map).",
        )
        .small(),
    );
    if world.is_some() && ui.button("Simulated world").clicked() {
        lesson.open_simulated_world();
    }
}

/// What the World box says of the GPS fit: the offset of the GPS's frame
/// and how far the path stays from the fixes once aligned.
pub fn gps_text(fit: Option<&slamlab_sim::landmark_slam::real_data::GpsFit>) -> String {
    match fit {
        None => "GPS: drawn once two fixes pair with the path.".to_owned(),
        Some(f) => format!(
            "GPS (grey dots) aligned to the path: the path turned {:.1}° and moved by \
             ({:.1}, {:.1}) m lies on the GPS's frame, {:.2} m RMS from the {} fixes so far.",
            f.rotation_deg, f.translation_m[0], f.translation_m[1], f.rmse, f.pairs
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_of_no_data_set_is_refused_by_name() {
        let arrival = read(vec![("notes.txt".to_owned(), Ok(b"hello".to_vec()))], None);
        match arrival {
            Arrival::Refused(why) => {
                assert!(why.starts_with("Could not open notes.txt:"), "{why}");
                assert!(why.contains("Freiburg"), "{why}");
            }
            Arrival::Data(_) | Arrival::Reference(..) => panic!("a text file is no data set"),
        }
    }

    #[test]
    fn a_freiburg_line_with_a_missing_column_names_the_file_and_line() {
        let arrival = read(
            vec![
                ("world.dat".to_owned(), Ok(b"1 2.0 1.0\n2 0.0\n".to_vec())),
                (
                    "sensor_data.dat".to_owned(),
                    Ok(b"ODOMETRY 0.1 0.2 0.0\nSENSOR 1 1.0 0.1\n".to_vec()),
                ),
            ],
            None,
        );
        match arrival {
            Arrival::Refused(why) => assert!(why.contains("world.dat, line 2"), "{why}"),
            Arrival::Data(_) | Arrival::Reference(..) => {
                panic!("world.dat's second line lacks its y")
            }
        }
    }

    #[test]
    fn an_isam_pose_graph_is_taken_as_the_reference_map() {
        let graph = b"ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.001\nLANDMARK 1 0 2 2 0.01 0 0.01\n";
        match read(
            vec![("dir/victoria_park.txt".to_owned(), Ok(graph.to_vec()))],
            None,
        ) {
            Arrival::Reference(name, text) => {
                assert_eq!(name, "victoria_park.txt");
                assert!(text.starts_with("ODOMETRY 0 1"));
            }
            other => panic!("{other:?}"),
        }
        // Beside the Freiburg files it is no data file either (and the reading
        // of the data set goes on without it).
        let arrival = read(
            vec![
                ("world.dat".to_owned(), Ok(b"1 2.0 1.0\n".to_vec())),
                (
                    "sensor_data.dat".to_owned(),
                    Ok(b"ODOMETRY 0.1 0.2 0.0\nSENSOR 1 1.0 0.1\n".to_vec()),
                ),
                ("victoria_park.txt".to_owned(), Ok(graph.to_vec())),
            ],
            None,
        );
        match arrival {
            Arrival::Data(loaded) => {
                assert_eq!(
                    loaded.reference.map(|r| r.0).as_deref(),
                    Some("victoria_park.txt")
                );
            }
            other => panic!("{other:?}"),
        }
        // A .txt of another kind is not taken for a graph.
        assert!(!super::super::reference::is_reference_graph(
            "notes.txt",
            b"hello"
        ));
        assert!(!super::super::reference::is_reference_graph(
            "graph.g2o",
            graph
        ));
    }

    #[test]
    fn the_last_data_pair_names_the_location() {
        let pairs = vec![
            ("data".to_owned(), "a.zip".to_owned()),
            ("robot".to_owned(), "2".to_owned()),
            ("data".to_owned(), "data/MRCLAM_Dataset6.zip".to_owned()),
        ];
        assert_eq!(
            location(&pairs).as_deref(),
            Some("data/MRCLAM_Dataset6.zip")
        );
        assert_eq!(location(&pairs[1..2]), None);
    }
}
