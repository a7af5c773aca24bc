//! The lesson catalogue. Each lesson has an id (the URL's `lesson=` value), a title
//! for the menu and a one-line summary. A new lesson adds an entry here and a
//! variant to [`crate::ActiveLesson`].

/// One entry of the lesson menu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LessonInfo {
    /// The URL's `lesson=` value, e.g. `landmark-slam`.
    pub id: &'static str,
    /// The title in the menu and the top bar.
    pub title: &'static str,
    /// One line on what the student sees.
    pub summary: &'static str,
}

/// Every lesson, in menu order. The first is the default.
pub const LESSONS: &[LessonInfo] = &[LessonInfo {
    id: "landmark-slam",
    title: "Landmark SLAM",
    summary: "A robot drives among landmarks; EKF-SLAM and UKF-SLAM estimate its pose and the \
              map, with 95% ellipses, NEES/NIS consistency plots and the covariance heatmap.",
}];

/// The lesson that opens when none (or an unknown one) is asked for.
pub const DEFAULT_LESSON: &str = "landmark-slam";

/// Looks a lesson up by id.
pub fn find(id: &str) -> Option<&'static LessonInfo> {
    LESSONS.iter().find(|l| l.id == id)
}

/// The default lesson's entry.
pub fn default_lesson() -> &'static LessonInfo {
    find(DEFAULT_LESSON).unwrap_or(&LESSONS[0])
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
}
