//! The laser file a lidar lesson maps, opened the one way for every lesson and
//! every route (file picker, drop, `log=`): a CARMEN log or a ROS 2 bag (MCAP),
//! told apart by its bytes. For a bag it keeps the messages, the topics read
//! and the choice between topics (`scan-topic=`, `odom-topic=` in the URL, two
//! menus in the panel), and what the reader assumed, as notices.

use slamlab_sim::grid::{BagTopics, LaserFile};
use slamlab_sim::io::ros2_bag::{Ros2Bag, TopicChoice};
use std::sync::Arc;

/// What the file pickers of the lidar lessons accept: CARMEN logs, bags (a ROS 1
/// `.bag` or a `.db3` too, so that the reader can say how to convert it) and
/// ROS maps.
pub const LASER_FILE_TYPES: &str = ".clf,.log,.gz,.bz2,.txt,.mcap,.bag,.db3,.yaml,.yml,.pgm,.png";

/// The URL's keys for a bag's topics.
pub const TOPIC_KEYS: [&str; 2] = ["scan-topic", "odom-topic"];

/// An open bag: its name, its messages and the topics read.
#[derive(Debug, Clone)]
struct OpenBag {
    name: String,
    bag: Arc<Ros2Bag>,
    topics: BagTopics,
}

/// The topics asked for and the open bag, if the lesson maps one.
#[derive(Debug, Default)]
pub struct LaserFileState {
    /// The topics asked for (by the URL or the menus); `None`: the bag's default.
    choice: TopicChoice,
    bag: Option<OpenBag>,
    /// What the reader assumed or dropped for the file being mapped.
    notices: Vec<String>,
}

impl LaserFileState {
    /// The state for a lesson opened with the link's `pairs`, and the pairs
    /// left for its parameters: those for which `read_later` holds (files the
    /// lesson reads after the first frame: `log=`, `reference=`, a map file)
    /// are set aside, and the laser file's own are read here.
    pub fn from_link(
        pairs: &[(String, String)],
        read_later: impl Fn(&str, &str) -> bool,
    ) -> (Self, Vec<(String, String)>) {
        let pairs: Vec<(String, String)> = pairs
            .iter()
            .filter(|(k, v)| !read_later(k, v))
            .cloned()
            .collect();
        Self::from_pairs(&pairs)
    }

    /// The state for a lesson opened with `pairs`: the topics asked for, and
    /// the pairs left for the lesson's parameters.
    pub fn from_pairs(pairs: &[(String, String)]) -> (Self, Vec<(String, String)>) {
        let value = |key: &str| {
            pairs
                .iter()
                .rev()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.trim().to_owned())
                .filter(|v| !v.is_empty())
        };
        let state = Self {
            choice: TopicChoice {
                scan: value(TOPIC_KEYS[0]),
                odom: value(TOPIC_KEYS[1]),
            },
            ..Self::default()
        };
        let rest = pairs
            .iter()
            .filter(|(k, _)| !TOPIC_KEYS.contains(&k.as_str()))
            .cloned()
            .collect();
        (state, rest)
    }

    /// Opens a laser file's bytes with the topics asked for. On success the
    /// lesson maps the file's input; on failure nothing changes here and the
    /// message names the file and what is wrong.
    pub fn open(&mut self, name: &str, bytes: &[u8]) -> Result<LaserFile, String> {
        let file = LaserFile::from_bytes(name, bytes, &self.choice)
            .map_err(|why| format!("Could not read the log {name}: {why}"))?;
        self.opened(name, &file);
        Ok(file)
    }

    fn opened(&mut self, name: &str, file: &LaserFile) {
        self.notices = file
            .notices
            .iter()
            .map(|n| format!("{name}: {n}"))
            .collect();
        self.bag = match (&file.bag, &file.topics) {
            (Some(bag), Some(topics)) => Some(OpenBag {
                name: name.to_owned(),
                bag: bag.clone(),
                topics: topics.clone(),
            }),
            _ => None,
        };
    }

    /// The lesson maps something else now (a simulated robot).
    pub fn close(&mut self) {
        self.bag = None;
        self.notices.clear();
    }

    /// What the reader assumed for the file being mapped.
    pub fn notices(&self) -> &[String] {
        &self.notices
    }

    /// The topics of the open bag, if one is open.
    pub fn topics(&self) -> Option<&BagTopics> {
        self.bag.as_ref().map(|b| &b.topics)
    }

    /// The pairs that reopen the open bag with the topics chosen (none for
    /// the bag's own default, nor without a bag).
    pub fn share_pairs(&self) -> Vec<(String, String)> {
        if self.bag.is_none() {
            return Vec::new();
        }
        [
            (TOPIC_KEYS[0], &self.choice.scan),
            (TOPIC_KEYS[1], &self.choice.odom),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.as_ref().map(|v| (k.to_owned(), v.clone())))
        .collect()
    }

    /// The menus to choose a bag's LaserScan topic and its odometry (each
    /// shown only when the bag offers a choice). A new choice reads the bag
    /// again: `Some(Ok(file))` to map, or `Some(Err(message))` (the choice
    /// is then undone and the lesson keeps what it maps).
    pub fn topics_ui(&mut self, ui: &mut egui::Ui) -> Option<Result<LaserFile, String>> {
        let open = self.bag.clone()?;
        let mut wanted: Option<TopicChoice> = None;
        let menus = [
            (
                "scan topic",
                "LaserScan topic",
                &open.topics.scan_choices,
                &open.topics.scan,
            ),
            (
                "odometry",
                "nav_msgs/Odometry topic, or tf: the odom → base transform on /tf",
                &open.topics.odometry_choices,
                &open.topics.odometry,
            ),
        ];
        for (k, (label, hover, choices, current)) in menus.into_iter().enumerate() {
            if choices.len() < 2 {
                continue;
            }
            ui.horizontal(|ui| {
                ui.label(label);
                egui::ComboBox::from_id_salt(("bag_topic", k))
                    .selected_text(current.as_str())
                    .show_ui(ui, |ui| {
                        for c in choices {
                            if ui.selectable_label(c == current, c.as_str()).clicked()
                                && c != current
                            {
                                let mut choice = self.choice.clone();
                                if k == 0 {
                                    choice.scan = Some(c.clone());
                                } else {
                                    choice.odom = Some(c.clone());
                                }
                                wanted = Some(choice);
                            }
                        }
                    })
                    .response
                    .on_hover_text(hover)
                    .widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, label));
            });
        }
        let choice = wanted?;
        Some(self.choose(choice))
    }

    /// Reads the open bag again with `choice`.
    pub fn choose(&mut self, choice: TopicChoice) -> Result<LaserFile, String> {
        let Some(open) = self.bag.clone() else {
            return Err("no bag is open: the topics apply to a ROS 2 bag".to_owned());
        };
        let file = LaserFile::with_topics(&open.name, open.bag.clone(), &choice)
            .map_err(|why| format!("Could not map {} with these topics: {why}", open.name))?;
        self.choice = choice;
        self.opened(&open.name, &file);
        Ok(file)
    }
}

/// The note after a file was opened: what it is and what the lesson maps.
pub fn loaded_note(name: &str, file: &LaserFile) -> String {
    let truth = if file.input.truth.is_some() {
        "with its true poses (a simulated run)"
    } else {
        "no ground truth"
    };
    match &file.topics {
        Some(t) => format!(
            "Loaded {name} ({}): {} scans over {:.0} s from {}, odometry {}; {truth}",
            file.format,
            file.input.scans.len(),
            file.input.duration(),
            t.scan,
            t.odometry
        ),
        None => format!(
            "Loaded {name}: {} scans over {:.0} s; {truth}",
            file.input.scans.len(),
            file.input.duration()
        ),
    }
}
