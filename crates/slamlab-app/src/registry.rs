//! Every lesson the app opens, in menu order: the one place that names them all.
//! Imports run one way: the shell (`lib.rs`) uses this registry, the registry uses
//! the lessons, the lessons use [`crate::lesson`] (the trait), which names none of
//! them. A lesson that hands over to another ([`LessonRequest`]) asks the shell,
//! which asks the registry.

use crate::lesson::{Lesson, LessonExt, LessonRequest, LessonStart};

/// One entry of the lesson menu.
#[derive(Clone, Copy, Debug)]
pub struct LessonEntry {
    /// The URL's `lesson=` value, e.g. `landmark-slam`.
    pub id: &'static str,
    /// The title in the menu and the top bar.
    pub title: &'static str,
    /// One line on what the student sees.
    pub summary: &'static str,
    /// Opens the lesson.
    pub open: fn(&LessonStart<'_>) -> Box<dyn Lesson>,
}

/// Every lesson, in menu order. The first is the default.
pub const LESSONS: &[LessonEntry] = &[
    LessonEntry {
        id: crate::landmark_slam::LESSON_ID,
        title: "Landmark SLAM",
        summary: "A robot drives among landmarks; EKF-SLAM and UKF-SLAM estimate its pose and \
                  the map, with 95% ellipses, NEES/NIS consistency plots and the covariance heatmap.",
        open: crate::landmark_slam::open,
    },
    LessonEntry {
        id: crate::kidnap::LESSON_ID,
        title: "Monte Carlo localization",
        summary: "A robot with a lidar in a maze or an office; a cloud of particles finds it \
                  (global localization) and follows it: predict, weight, resample. Kidnap it.",
        open: crate::kidnap::open,
    },
    LessonEntry {
        id: crate::pose_graph::LESSON_ID,
        title: "Pose-graph optimization",
        summary: "A graph of poses, odometry and loop closures optimized one solver iteration at \
                  a time (GN, LM, first-order); drag vertices, add a wrong loop closure, try \
                  robust kernels, open g2o/TORO files.",
        open: crate::pose_graph::open,
    },
    LessonEntry {
        id: crate::resampling::LESSON_ID,
        title: "Resampling lab",
        summary: "One row of weighted particles and four resamplers side by side: press \
                  resample once or a thousand times and see how many copies each particle \
                  gets, and how much they scatter.",
        open: crate::resampling::open,
    },
    LessonEntry {
        id: crate::fusion::LESSON_ID,
        title: "Sensor fusion",
        summary: "Wheel odometry, an IMU and a 1 Hz SLAM pose fused by robot_localization's EKF; \
                  the SLAM pose taken absolute, relative or differential, side by side.",
        open: crate::fusion::open,
    },
    LessonEntry {
        id: crate::mapping::LESSON_ID,
        title: "Mapping with a lidar",
        summary: "A lidar's scans build an occupancy grid; poses from the truth, raw odometry, \
                  ICP or scan-to-map matching, switched live on the same scans; a simulated \
                  robot or a real CARMEN log (the Intel lab).",
        open: crate::mapping::open,
    },
    LessonEntry {
        id: crate::cartographer::LESSON_ID,
        title: "Submaps, loop closure and the kidnapped robot",
        summary: "Cartographer-style SLAM: scans into submaps, a pose graph with branch-and-bound \
                  loop closures; kidnap the robot while it maps, watch the matching cost give it \
                  away, a new map start and merge into the first.",
        open: crate::cartographer::open,
    },
    LessonEntry {
        id: crate::filters::LESSON_ID,
        title: "Filters: from Bayes to particles",
        summary: "One Gaussian through one nonlinear step by the EKF, the unscented transform \
                  and particles against 100,000 samples; a histogram Bayes filter beside a \
                  Kalman filter in a corridor with doors.",
        open: crate::filters::open,
    },
    LessonEntry {
        id: crate::visual_odometry::LESSON_ID,
        title: "Visual odometry",
        summary: "A camera on a vehicle docking at a station: matched features, the essential \
                  matrix by the eight-point or five-point method inside RANSAC, stepped one \
                  sample at a time, R and t by cheirality, and the trajectory scaled by the \
                  wheel speeds.",
        open: crate::visual_odometry::open,
    },
];

/// The lesson that opens when none (or an unknown one) is asked for.
pub const DEFAULT_LESSON: &str = "landmark-slam";

/// Looks a lesson up by id.
pub fn find(id: &str) -> Option<&'static LessonEntry> {
    LESSONS.iter().find(|l| l.id == id)
}

/// The default lesson's entry.
pub fn default_lesson() -> &'static LessonEntry {
    find(DEFAULT_LESSON).unwrap_or(&LESSONS[0])
}

/// Opens a lesson; if it could not open ([`crate::lesson::open_instead`]), the
/// default lesson opens in its place with the notice that says why.
pub fn open(entry: &LessonEntry, start: &LessonStart<'_>) -> Box<dyn Lesson> {
    or_default((entry.open)(start), entry.id, start.embed)
}

/// Opens the Monte Carlo localization lesson on a map another lesson built
/// ([`LessonRequest::LocalizeInMap`]).
pub fn localize_in_map(name: String, grid: slamlab_core::grid::OccupancyGrid) -> Box<dyn Lesson> {
    or_default(
        crate::kidnap::open_with_map(name, grid),
        crate::kidnap::LESSON_ID,
        false,
    )
}

/// The lesson a [`LessonRequest`] asks for, if it asks for one.
pub fn requested(request: LessonRequest) -> Option<Box<dyn Lesson>> {
    match request {
        LessonRequest::LocalizeInMap { name, grid } => Some(localize_in_map(name, grid)),
        LessonRequest::Save(_) => None,
    }
}

/// `lesson`, or the default lesson with its notice when `lesson` could not open.
fn or_default(lesson: Box<dyn Lesson>, id: &str, embed: bool) -> Box<dyn Lesson> {
    let Some(why) = lesson.could_not_open().map(str::to_owned) else {
        return lesson;
    };
    let fallback = default_lesson();
    let lesson = if fallback.id == id {
        lesson
    } else {
        (fallback.open)(&LessonStart {
            pairs: &[],
            embed,
            stored: None,
            many_runs: None,
        })
    };
    lesson.with_notice(why)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_lesson_is_in_the_catalogue_and_ids_are_unique() {
        assert_eq!(default_lesson().id, DEFAULT_LESSON);
        for (i, a) in LESSONS.iter().enumerate() {
            for b in &LESSONS[i + 1..] {
                assert_ne!(a.id, b.id);
            }
        }
        assert!(find("nope").is_none());
    }

    #[test]
    fn every_lesson_opens_with_its_id_and_a_share_link_that_reopens_it() {
        for entry in LESSONS {
            let lesson = (entry.open)(&LessonStart {
                pairs: &[],
                embed: false,
                stored: None,
                many_runs: None,
            });
            assert_eq!(lesson.id(), entry.id);
            let query = lesson.share_query(true);
            assert!(
                query.starts_with(&format!("lesson={}", entry.id)),
                "{query}"
            );
            assert!(query.ends_with("embed=1"), "{query}");
            assert!(
                lesson.notices().is_empty(),
                "{}: {:?}",
                entry.id,
                lesson.notices()
            );
        }
    }

    #[test]
    fn a_lesson_that_cannot_open_gives_way_to_the_default_with_its_reason() {
        fn broken(start: &LessonStart<'_>) -> Box<dyn Lesson> {
            crate::lesson::open_instead(start, "the lesson's defaults do not build".to_owned())
        }
        let entry = LessonEntry {
            id: "broken",
            title: "Broken",
            summary: "",
            open: broken,
        };
        let start = LessonStart {
            pairs: &[],
            embed: true,
            stored: None,
            many_runs: None,
        };
        let lesson = open(&entry, &start);
        assert_eq!(lesson.id(), DEFAULT_LESSON);
        assert!(lesson.could_not_open().is_none());
        assert!(
            lesson
                .notices()
                .iter()
                .any(|n| n.contains("defaults do not build")),
            "{:?}",
            lesson.notices()
        );
    }

    #[test]
    fn a_map_handed_over_opens_the_localization_lesson_on_it() {
        let cells = vec![slamlab_core::grid::Cell::Free; 40 * 30];
        let grid = slamlab_core::grid::OccupancyGrid::new(
            40,
            30,
            0.1,
            slamlab_core::Pose2::new(0.0, 0.0, 0.0),
            cells,
        )
        .expect("a 40 x 30 grid");
        let request = LessonRequest::LocalizeInMap {
            name: "a test map".to_owned(),
            grid,
        };
        let lesson = requested(request).expect("a lesson to open");
        assert_eq!(lesson.id(), crate::kidnap::LESSON_ID);
        assert!(requested(LessonRequest::Save(Vec::new())).is_none());
    }

    /// The code of every `.rs` file under `path` (a file or a folder), without
    /// comments (an intra-doc link is not an import), by file name.
    fn code_under(path: &std::path::Path) -> Vec<(String, String)> {
        let mut out = Vec::new();
        if path.is_dir() {
            let mut entries: Vec<_> = std::fs::read_dir(path)
                .into_iter()
                .flatten()
                .flatten()
                .map(|e| e.path())
                .collect();
            entries.sort();
            for entry in entries {
                out.extend(code_under(&entry));
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(path).unwrap_or_default();
            let code: Vec<&str> = text
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect();
            out.push((path.display().to_string(), code.join("\n")));
        }
        out
    }

    /// Imports run one way: shell -> registry -> lessons -> `lesson` and the shared
    /// modules. No lesson names the registry, the shell or another lesson, and no
    /// shared module names a lesson or the registry.
    #[test]
    fn imports_run_one_way() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut folders: Vec<String> = std::fs::read_dir(&src)
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.path().join("mod.rs").is_file())
            .filter_map(|e| e.file_name().to_str().map(str::to_owned))
            .filter(|name| name != "widgets")
            .collect();
        folders.sort();
        assert!(folders.len() >= LESSONS.len(), "{folders:?}");
        let names = |name: &str, code: &str| {
            code.contains(&format!("crate::{name}::"))
                || code.contains(&format!("crate::{name};"))
                || code.contains(&format!("crate::{{{name}"))
        };
        let mut wrong = Vec::new();
        for folder in &folders {
            for (file, code) in code_under(&src.join(folder)) {
                for other in folders.iter().filter(|f| *f != folder) {
                    if names(other, &code) {
                        wrong.push(format!("{file} names the lesson {other}"));
                    }
                }
                for shell in ["registry", "SlamLabApp", "Settings", "link_sets_up"] {
                    if names(shell, &code) || code.contains(&format!("crate::{shell}")) {
                        wrong.push(format!("{file} names crate::{shell}"));
                    }
                }
            }
        }
        for shared in [
            "lesson.rs",
            "panels.rs",
            "query.rs",
            "export.rs",
            "time_control.rs",
            "palette.rs",
            "frame_stats.rs",
            "widgets",
        ] {
            for (file, code) in code_under(&src.join(shared)) {
                for lesson in folders.iter().map(String::as_str).chain(["registry"]) {
                    if names(lesson, &code) {
                        wrong.push(format!("{file} names {lesson}"));
                    }
                }
            }
        }
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    }
}
