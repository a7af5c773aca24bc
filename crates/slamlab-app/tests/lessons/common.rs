//! What every lesson's UI tests share: the harness, typed access to the open
//! lesson, and pixel counts of the colours that must be on screen.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;

/// The window the tests open, points.
pub const SIZE: egui::Vec2 = egui::vec2(1400.0, 900.0);

/// The app opened with `query` in a window of `size`.
pub fn harness_sized(query: &str, size: egui::Vec2) -> Harness<'static, SlamLabApp> {
    let query = query.to_owned();
    Harness::builder()
        .with_size(size)
        .with_max_steps(40)
        .build_eframe(move |cc| SlamLabApp::new(cc, &query))
}

/// The app opened with `query` in a window of `size`, in `theme` (for rendered checks).
pub fn harness_themed(
    query: &str,
    size: egui::Vec2,
    theme: egui::Theme,
) -> Harness<'static, SlamLabApp> {
    let query = query.to_owned();
    Harness::builder()
        .with_size(size)
        .with_max_steps(40)
        .with_theme(theme)
        .build_eframe(move |cc| SlamLabApp::new(cc, &query))
}

/// The rendered window, or `None` with a note where there is no GPU adapter (the
/// rendered checks are skipped then; the rest of the test still runs).
pub fn render_or_skip(h: &mut Harness<'_, SlamLabApp>) -> Option<image::RgbaImage> {
    match h.render() {
        Ok(image) => Some(image),
        Err(err) => {
            eprintln!("skipping the rendered checks: no GPU adapter ({err})");
            None
        }
    }
}

/// The rendered window ([`render_or_skip`]), saved as `name` in the folder
/// `$SLAMLAB_UI_SHOTS` names, when it does, for a look.
pub fn shot(h: &mut Harness<'_, SlamLabApp>, name: &str) -> Option<image::RgbaImage> {
    let image = render_or_skip(h)?;
    if let Some(dir) = std::env::var_os("SLAMLAB_UI_SHOTS") {
        let _ = image.save(std::path::Path::new(&dir).join(name));
    }
    Some(image)
}

/// The app opened with `query` in a [`SIZE`] window.
pub fn harness(query: &str) -> Harness<'static, SlamLabApp> {
    harness_sized(query, SIZE)
}

/// The open lesson as type `L` (the test fails when another lesson is open).
pub fn lesson_of<'h, L: 'static>(h: &'h Harness<'_, SlamLabApp>) -> &'h L {
    match h.state().lesson_as::<L>() {
        Some(l) => l,
        None => panic!("{} is not the open lesson", std::any::type_name::<L>()),
    }
}

/// The open lesson as type `L`, to change it.
pub fn lesson_of_mut<'h, L: 'static>(h: &'h mut Harness<'_, SlamLabApp>) -> &'h mut L {
    match h.state_mut().lesson_as_mut::<L>() {
        Some(l) => l,
        None => panic!("{} is not the open lesson", std::any::type_name::<L>()),
    }
}

/// `lesson(&h)` and `lesson_mut(&mut h)`: the open lesson as type `$lesson`, the
/// one lesson a test module is about (the test fails when another is open).
macro_rules! lesson_accessors {
    ($lesson:ty) => {
        fn lesson<'h>(h: &'h egui_kittest::Harness<'_, slamlab_app::SlamLabApp>) -> &'h $lesson {
            $crate::common::lesson_of(h)
        }

        fn lesson_mut<'h>(
            h: &'h mut egui_kittest::Harness<'_, slamlab_app::SlamLabApp>,
        ) -> &'h mut $lesson {
            $crate::common::lesson_of_mut(h)
        }
    };
}
pub(crate) use lesson_accessors;

/// Checks the notices of the open lesson: `count` of them, and for each entry
/// of `words` one notice that contains all of its words (the parameter and
/// what was used or expected).
pub fn assert_notices(h: &Harness<'_, SlamLabApp>, count: usize, words: &[&[&str]]) {
    let notices = h.state().notices();
    assert_eq!(notices.len(), count, "{notices:?}");
    for words in words {
        assert!(
            notices.iter().any(|n| words.iter().all(|w| n.contains(w))),
            "no notice has all of {words:?}: {notices:?}"
        );
    }
}

/// The rectangle of the area `id` in the last frame (a window's is its title).
pub fn area_rect(h: &Harness<'_, SlamLabApp>, id: egui::Id) -> egui::Rect {
    h.ctx
        .memory(|m| m.area_rect(id))
        .unwrap_or_else(|| panic!("no area {id:?} on screen"))
}

/// The rectangles of the window titled `title` and of the notices box: the
/// window no wider than its corner (42 % of the screen's width, its frame
/// and shadow beside), and the two apart.
pub fn assert_corner_window_beside_the_notices(
    h: &Harness<'_, SlamLabApp>,
    title: &str,
) -> (egui::Rect, egui::Rect) {
    let window = area_rect(h, egui::Id::unique(Some(title)));
    let notices = area_rect(h, egui::Id::unique("slamlab_notices"));
    let screen = h.ctx.content_rect();
    let corner = (0.42 * screen.width()).clamp(300.0, 470.0);
    eprintln!("{title} {window:?}, the notices {notices:?}, the screen {screen:?}");
    assert!(
        window.width() <= corner + 20.0,
        "{title} is {} wide, its corner {corner}",
        window.width()
    );
    assert!(
        !window.intersects(notices),
        "the notices {notices:?} lie under {title} {window:?}"
    );
    (window, notices)
}

/// No key of `keys` lies on the data rectangle `data` of a figure (they
/// overlap by half a point at most either way); `figure` names it in the
/// message (its title, the window's size).
pub fn assert_keys_off(keys: &[egui::Rect], data: egui::Rect, figure: &str) {
    for key in keys {
        let overlap = key.intersect(data);
        assert!(
            !(overlap.width() > 0.5 && overlap.height() > 0.5),
            "{figure}: a key {key:?} lies on the data {data:?}"
        );
    }
}

/// Pixels whose every channel is within `tolerance` of `rgb`.
pub fn count_pixels(rgba: &[u8], rgb: [u8; 3], tolerance: i32) -> usize {
    rgba.chunks_exact(4)
        .filter(|p| (0..3).all(|c| (i32::from(p[c]) - i32::from(rgb[c])).abs() <= tolerance))
        .count()
}

/// Pixels within `tolerance` of `target` as the sum of the channels' absolute
/// differences.
pub fn count_pixels_near(rgba: &[u8], target: [u8; 3], tolerance: i32) -> usize {
    rgba.chunks_exact(4)
        .filter(|p| {
            (0..3)
                .map(|c| (i32::from(p[c]) - i32::from(target[c])).abs())
                .sum::<i32>()
                <= tolerance
        })
        .count()
}

/// Is a widget whose label contains `text` on screen?
pub fn label_visible(h: &Harness<'_, SlamLabApp>, text: &str) -> bool {
    h.query_all_by_label_contains(text).next().is_some()
}

/// Calls `visit` with every text shape of the last frame (labels and painted
/// text alike) and its clip rectangle, in drawing order.
pub fn visit_texts(
    h: &Harness<'_, SlamLabApp>,
    mut visit: impl FnMut(&egui::epaint::TextShape, egui::Rect),
) {
    fn walk(
        shape: &egui::Shape,
        clip: egui::Rect,
        visit: &mut dyn FnMut(&egui::epaint::TextShape, egui::Rect),
    ) {
        match shape {
            egui::Shape::Text(t) => visit(t, clip),
            egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| walk(s, clip, visit)),
            _ => {}
        }
    }
    for clipped in &h.output().shapes {
        walk(&clipped.shape, clipped.clip_rect, &mut visit);
    }
}

/// Every text drawn in the last frame (labels and painted text alike), with its
/// rectangle on screen and its clip.
pub fn drawn_texts(h: &Harness<'_, SlamLabApp>) -> Vec<(String, egui::Rect, egui::Rect)> {
    let mut out = Vec::new();
    visit_texts(h, |t, clip| {
        out.push((t.galley.text().to_owned(), t.visual_bounding_rect(), clip));
    });
    out
}

/// Is a text containing `needle` drawn in the last frame, at least partly inside
/// its clip and the window (on screen, not scrolled away)?
pub fn text_drawn(h: &Harness<'_, SlamLabApp>, needle: &str) -> bool {
    let screen = h.ctx.content_rect();
    drawn_texts(h).iter().any(|(text, rect, clip)| {
        let shown = rect.intersect(*clip).intersect(screen);
        text.contains(needle) && shown.width() > 1.0 && shown.height() > 1.0
    })
}

/// Saves `image` as the snapshot `name` for review (`egui_kittest`'s compared
/// snapshots, threshold 2). A differing snapshot is not a failure here: the
/// tests assert the colours they need, and the GPU's small differences vary.
pub fn snapshot(image: &image::RgbaImage, name: &str) {
    let _ = egui_kittest::try_image_snapshot_options(
        image,
        name,
        &egui_kittest::SnapshotOptions::new().threshold(2.0),
    );
}

/// The test state of `query` after `ticks` headless steps, as JSON text and
/// parsed.
pub fn headless(query: &str, ticks: u64) -> (String, serde_json::Value) {
    let json = SlamLabApp::headless_state(query, ticks);
    let state = match serde_json::from_str(&json) {
        Ok(state) => state,
        Err(err) => panic!("the test state of {query} is not JSON ({err}): {json}"),
    };
    (json, state)
}

/// A JSON array of numbers as numbers (the test fails on anything else).
pub fn numbers(value: &serde_json::Value) -> Vec<f64> {
    let Some(items) = value.as_array() else {
        panic!("not an array: {value}");
    };
    items
        .iter()
        .map(|v| v.as_f64().unwrap_or_else(|| panic!("not a number: {v}")))
        .collect()
}

/// The Intel lab's log and its corrected reference from the shared data
/// (`$SLAMLAB_SHARED/data/laser`, else `../shared` beside the repository), or
/// `None` with a note when they are not there.
pub fn intel_log_and_reference() -> Option<(Vec<u8>, Vec<u8>)> {
    let dir = std::env::var_os("SLAMLAB_SHARED")
        .map_or_else(
            || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
            std::path::PathBuf::from,
        )
        .join("data/laser");
    match (
        std::fs::read(dir.join("intel.clf.bz2")),
        std::fs::read(dir.join("intel-corrected.log.gz")),
    ) {
        (Ok(log), Ok(reference)) => Some((log, reference)),
        _ => {
            eprintln!(
                "skipped: the Intel log and its reference are not in {}",
                dir.display()
            );
            None
        }
    }
}
