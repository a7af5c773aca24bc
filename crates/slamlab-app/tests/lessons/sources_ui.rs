//! The Sources window: the menu bar opens it with every document's title and
//! author, a link in a lesson's explanation opens it on that document, it fits a
//! small window, and no panel cites a document without naming it.

use crate::common::{harness, harness_sized, label_visible};
use egui_kittest::kittest::{NodeT as _, Queryable as _};
use slamlab_app::time_control::TimeAction;
use slamlab_app::widgets::sources;

/// The three course texts: title and author.
const DOCUMENTS: [(&str, &str); 3] = [
    (
        "SLAM for Ground Robots: Theories and Applications",
        "Linjian Xiang",
    ),
    (
        "ME 597 Autonomous Mobile Robotics, Section 8: Mapping II",
        "Steven Waslander",
    ),
    (
        "A Low-cost SLAM Fusion Algorithm for Robot Localization",
        "Ruifan Wu",
    ),
];

#[test]
fn the_sources_menu_entry_lists_every_document_with_its_author() {
    let mut h = harness("lesson=landmark-slam&seed=7");
    h.run();
    assert!(!sources::is_open(&h.ctx));
    assert!(!label_visible(&h, DOCUMENTS[0].0));
    h.get_by_label("Sources").click();
    h.run();
    assert!(sources::is_open(&h.ctx), "the menu entry opens the window");
    assert_eq!(sources::highlighted(&h.ctx), None);
    for (title, author) in DOCUMENTS {
        assert!(label_visible(&h, title), "{title} is listed");
        assert!(label_visible(&h, author), "{author} is listed");
    }
    assert!(label_visible(&h, "Probabilistic Robotics"));
    assert!(label_visible(&h, "University of Alberta"));
    assert!(label_visible(&h, "University of Waterloo"));

    // The window's close button closes it.
    h.get_by_label("Close window").click();
    h.run();
    assert!(!sources::is_open(&h.ctx));
}

#[test]
fn a_source_link_in_the_landmark_explanation_opens_that_document() {
    let mut h = harness("lesson=landmark-slam&seed=7");
    h.run();
    let link = h.get_by_label("Source: Xiang's thesis, §3.2 EKF-SLAM");
    link.scroll_to_me();
    h.run();
    h.get_by_label("Source: Xiang's thesis, §3.2 EKF-SLAM")
        .click();
    h.run();
    assert!(sources::is_open(&h.ctx));
    assert_eq!(sources::highlighted(&h.ctx), Some("xiang"));
    assert!(label_visible(&h, "Linjian Xiang"));
    assert!(label_visible(&h, "§3.2, Eq. 3.5-3.20"));
}

/// Labels that cite a document without naming it ("thesis Eq. 3.5", "Euler
/// (slides)", "corrected in the errata", "thesis 000 Algorithm 6").
fn unnamed_citations(h: &egui_kittest::Harness<'_, slamlab_app::SlamLabApp>) -> Vec<String> {
    const BARE: [&str; 7] = [
        "thesis Eq",
        "(slides)",
        "the errata",
        "thesis Experiment",
        "thesis Algorithm",
        "thesis 00",
        "slides 00",
    ];
    const NAMES: [&str; 3] = ["Xiang", "Waslander", "Wu"];
    h.query_all_by_label_contains("")
        .filter_map(|node| node.accesskit_node().label())
        .filter(|label| {
            BARE.iter()
                .any(|b| label.to_lowercase().contains(&b.to_lowercase()))
        })
        .filter(|label| !NAMES.iter().any(|n| label.contains(n)))
        .collect()
}

#[test]
fn no_lesson_cites_a_document_without_naming_it() {
    for entry in slamlab_app::registry::LESSONS {
        let mut h = harness(&format!("lesson={}&seed=3", entry.id));
        h.run();
        assert!(
            h.query_all_by_label_contains("Source").count() > 1,
            "lesson {} links its explanation to the Sources window",
            entry.id
        );
        let mut seen = 0;
        for step in 0..12 {
            let bad = unnamed_citations(&h);
            assert!(
                bad.is_empty(),
                "lesson {} after {step} phases: {bad:?}",
                entry.id
            );
            seen += h.query_all_by_label_contains("").count();
            h.state_mut().apply_time_action(TimeAction::StepPhase);
            h.run();
        }
        assert!(seen > 12, "lesson {} shows labels", entry.id);
    }
}

#[test]
fn the_sources_window_fits_a_small_window() {
    let size = egui::vec2(800.0, 500.0);
    let mut h = harness_sized("lesson=landmark-slam&seed=7", size);
    h.run();
    sources::open_sources(&h.ctx, Some("waslander"));
    h.run();
    let screen = egui::Rect::from_min_size(egui::Pos2::ZERO, size);
    let rect = sources::window_rect(&h.ctx).unwrap_or_else(|| panic!("the window was drawn"));
    assert!(
        screen.expand(0.5).contains_rect(rect),
        "the Sources window {rect:?} lies inside the {size:?} screen"
    );
    for node in h.query_all_by_label("Sources") {
        let bounds = node.rect();
        assert!(
            screen.expand(0.5).contains_rect(bounds),
            "{bounds:?} is on screen"
        );
    }
    // The highlighted entry is scrolled into view.
    let title = h.get_by_label("Waslander's slides");
    assert!(
        rect.contains_rect(title.rect()),
        "the highlighted entry is inside the window"
    );
}
