//! Where a lidar lesson's files come from, gathered the one way for the
//! mapping and Cartographer lessons: the log and its reference a link names
//! (`log=`, `reference=`, read after the first frame, the log first), and the
//! files dropped on the window or picked, sorted into a ROS map, a log and its
//! reference (a corrected log, told by its name). The lesson decides what each
//! file does; this only says what arrived, in the order it arrived.

use crate::widgets::dropped_files::{DropInbox, sort_read};
use crate::widgets::fetch::{self, Fetched, LinkedFile};
use crate::widgets::file_picker::FilePicker;
use slamlab_sim::grid::laser_file::MAX_LASER_FILE_BYTES;

/// One file (or a ROS map's files) that arrived for the lesson.
#[derive(Debug, PartialEq)]
pub enum LaserInput {
    /// A laser file to map: its name, bytes, and the link's location when it
    /// came from `log=`.
    Log {
        /// The file's name (a location's last part).
        name: String,
        /// Its bytes.
        bytes: Vec<u8>,
        /// Where `log=` said it is, for the share link.
        location: Option<String>,
    },
    /// A corrected log to score the run against: its name, bytes, and the
    /// link's location when it came from `reference=`.
    Reference {
        /// The file's name.
        name: String,
        /// Its bytes.
        bytes: Vec<u8>,
        /// Where `reference=` said it is, for the share link.
        location: Option<String>,
    },
    /// A ROS map (its YAML and image) for the simulated robot to explore.
    Map(Vec<(String, Vec<u8>)>),
    /// A file that could not be read: the note that says which and why.
    Refused(String),
}

/// The lesson's routes for files: the drop inbox, the file picker and the
/// files its link names.
#[derive(Debug)]
pub struct LaserInputs {
    inbox: DropInbox,
    picker: FilePicker,
    log: Option<LinkedFile>,
    reference: Option<LinkedFile>,
}

impl Default for LaserInputs {
    fn default() -> Self {
        Self {
            inbox: DropInbox::default(),
            picker: FilePicker::multiple(),
            log: None,
            reference: None,
        }
    }
}

/// Whether a file's name says it is a corrected log (a reference).
pub fn is_reference_name(name: &str) -> bool {
    name.to_ascii_lowercase().contains("corrected")
}

/// Whether a file's name says it is part of a ROS map (its YAML or image).
pub fn is_map_file(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    [".yaml", ".yml", ".pgm", ".png"]
        .iter()
        .any(|e| lower.ends_with(e))
}

impl LaserInputs {
    /// Reads the log at `log` and the reference at `reference` (the link's
    /// `log=` and `reference=`) from the next frame on.
    pub fn link(&mut self, log: Option<String>, reference: Option<String>) {
        self.log = log.map(LinkedFile::new);
        self.reference = reference.map(LinkedFile::new);
    }

    /// Is a file the link named still being read?
    pub fn is_fetching(&self) -> bool {
        self.log.is_some() || self.reference.is_some()
    }

    /// The file picker's button (logs, bags and ROS maps; several at once).
    pub fn picker_ui(&mut self, ui: &mut egui::Ui) {
        self.picker.ui(
            ui,
            "Open log, bag or map…",
            crate::widgets::laser_file::LASER_FILE_TYPES,
            MAX_LASER_FILE_BYTES as usize,
            "path/to/intel.clf.bz2",
        );
    }

    /// What arrived since the last frame, in order: the linked log (the
    /// reference waits until the log is in), the linked reference, then the
    /// files dropped or picked. A batch with a map file is a map; otherwise its
    /// first log is the log and its first corrected log the reference.
    pub fn poll(&mut self, ctx: &egui::Context) -> Vec<LaserInput> {
        let mut arrived = Vec::new();
        if let Some((location, result)) = LinkedFile::poll(&mut self.log, ctx) {
            arrived.push(linked_input(
                location,
                result,
                |name, bytes, location| LaserInput::Log {
                    name,
                    bytes,
                    location,
                },
                "log",
                "the simulated robot maps instead",
            ));
        }
        if self.log.is_none()
            && let Some((location, result)) = LinkedFile::poll(&mut self.reference, ctx)
        {
            arrived.push(linked_input(
                location,
                result,
                |name, bytes, location| LaserInput::Reference {
                    name,
                    bytes,
                    location,
                },
                "reference",
                "the mapping goes on without a score",
            ));
        }
        let picked = self.picker.poll_all();
        if let Some(batch) = self.inbox.poll(ctx).or(picked) {
            let (files, refused) = sort_read(batch);
            arrived.extend(refused.into_iter().map(LaserInput::Refused));
            if files.iter().any(|(name, _)| is_map_file(name)) {
                arrived.push(LaserInput::Map(files));
            } else {
                let (references, logs): (Vec<_>, Vec<_>) = files
                    .into_iter()
                    .partition(|(name, _)| is_reference_name(name));
                if let Some((name, bytes)) = logs.into_iter().next() {
                    arrived.push(LaserInput::Log {
                        name,
                        bytes,
                        location: None,
                    });
                }
                if let Some((name, bytes)) = references.into_iter().next() {
                    arrived.push(LaserInput::Reference {
                        name,
                        bytes,
                        location: None,
                    });
                }
            }
        }
        arrived
    }
}

/// A file the link named (the `what`: log or reference), as it arrived: the
/// input `make` builds of its name, bytes and location, or, when it could not
/// be read, the note that says so and what the lesson does `instead`.
fn linked_input(
    location: String,
    result: Fetched,
    make: fn(String, Vec<u8>, Option<String>) -> LaserInput,
    what: &str,
    instead: &str,
) -> LaserInput {
    match result {
        Ok(bytes) => make(
            fetch::file_name(&location).to_owned(),
            bytes,
            Some(location),
        ),
        Err(why) => LaserInput::Refused(format!(
            "Could not load the {what} {location}: {why}; {instead}"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_linked_log_is_refused_before_its_reference_is_read() {
        let ctx = egui::Context::default();
        let mut inputs = LaserInputs::default();
        inputs.link(
            Some("no/such/intel.clf".to_owned()),
            Some("no/such/intel-corrected.log".to_owned()),
        );
        assert!(inputs.poll(&ctx).is_empty(), "the reads start");
        assert!(inputs.is_fetching());
        let first = inputs.poll(&ctx);
        assert_eq!(first.len(), 1, "{first:?}");
        assert!(
            matches!(&first[0], LaserInput::Refused(m)
                if m.starts_with("Could not load the log no/such/intel.clf: ")
                    && m.ends_with("; the simulated robot maps instead")),
            "{first:?}"
        );
        // The reference's read started in the same frame; it arrives next.
        let second = inputs.poll(&ctx);
        assert!(
            matches!(&second[..], [LaserInput::Refused(m)]
                if m.starts_with("Could not load the reference no/such/intel-corrected.log: ")),
            "{second:?}"
        );
        assert!(!inputs.is_fetching());
        assert!(inputs.poll(&ctx).is_empty());
    }

    #[test]
    fn names_tell_maps_and_references() {
        assert!(is_reference_name("intel-CORRECTED.log.gz"));
        assert!(!is_reference_name("intel.clf"));
        assert!(is_map_file("lab.YAML") && is_map_file("lab.pgm") && is_map_file("a.png"));
        assert!(!is_map_file("intel.clf.bz2"));
    }
}
