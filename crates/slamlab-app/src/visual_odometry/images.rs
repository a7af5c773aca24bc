//! The lesson's centre: the two images of one VO step side by side, with the
//! features and matches as RANSAC classifies them, the sample drawn, the truly
//! wrong matches on request and, under the pointer, a feature's epipolar line
//! in the other image (thesis Eq. 4.14: `x_rᵀ F x_l = 0`, so the match of a left
//! pixel lies on the line `F x_l` of the right image); below, the top view of
//! the trajectories.

use super::VoView;
use crate::palette;
use crate::widgets::plots::{Figure, KeyEntry, Mark, figure_plot, figure_ui, key_ui};
use egui::{Color32, Pos2, Rect, Sense, Stroke, pos2, vec2};
use egui_plot::{Line, LineStyle, PlotPoints, Points};
use nalgebra::{Matrix3, Vector2, Vector3};
use slamlab_core::vision::{Correspondence, Intrinsics, epipolar_line, sampson_squared};
use slamlab_sim::visual_odometry::{TwoViewSession, VoRun};

/// Colour of a match RANSAC keeps.
pub const INLIER: Color32 = palette::GREEN;
/// Colour of a match RANSAC rejects.
pub const OUTLIER: Color32 = palette::VERMILLION;
/// Colour of the sample drawn.
pub const SAMPLE: Color32 = palette::ORANGE;
/// Colour of an epipolar line.
pub const EPIPOLAR: Color32 = palette::BLUE;
/// Colour of a match before any hypothesis.
pub const UNCLASSIFIED: Color32 = palette::DEAD_RECKONING;
/// Colour of the VO trajectory scaled by the wheel speeds.
pub const VO_SCALED: Color32 = palette::BLUE;
/// Colour of the VO trajectory with unit steps.
pub const VO_UNIT: Color32 = palette::ORANGE;

/// Pixels to screen: an image of `camera`'s size drawn in `rect`.
#[derive(Clone, Copy, Debug)]
pub(super) struct ImageFrame {
    rect: Rect,
    scale: f32,
}

impl ImageFrame {
    fn new(rect: Rect, camera: &Intrinsics) -> Self {
        let scale = (rect.width() / camera.width as f32).min(rect.height() / camera.height as f32);
        Self { rect, scale }
    }

    pub(super) fn to_screen(self, pixel: &Vector2<f64>) -> Pos2 {
        self.rect.min + vec2(pixel.x as f32, pixel.y as f32) * self.scale
    }

    /// The part of the line `a u + b v + c = 0` inside the image, on screen.
    pub(super) fn clip(self, line: &Vector3<f64>, camera: &Intrinsics) -> Option<[Pos2; 2]> {
        let (w, h) = (camera.width, camera.height);
        let mut ends: Vec<Vector2<f64>> = Vec::with_capacity(4);
        if line.y.abs() > 1e-12 {
            for u in [0.0, w] {
                let v = -(line.x * u + line.z) / line.y;
                if (0.0..=h).contains(&v) {
                    ends.push(Vector2::new(u, v));
                }
            }
        }
        if line.x.abs() > 1e-12 {
            for v in [0.0, h] {
                let u = -(line.y * v + line.z) / line.x;
                if (0.0..=w).contains(&u) {
                    ends.push(Vector2::new(u, v));
                }
            }
        }
        let first = *ends.first()?;
        let far = ends
            .iter()
            .copied()
            .max_by(|a, b| (a - first).norm().total_cmp(&(b - first).norm()))?;
        ((far - first).norm() > 1e-9).then(|| [self.to_screen(&first), self.to_screen(&far)])
    }
}

/// The images above, the top view below. Returns the feature under the
/// pointer (right image?, match index).
pub fn centre_ui(
    ui: &mut egui::Ui,
    run: &VoRun,
    pair: usize,
    session: Option<&TwoViewSession>,
    view: &VoView,
    hovered: Option<(bool, usize)>,
) -> Option<(bool, usize)> {
    // The images take at most 45% of the height, and never more than half the
    // width each; the top view the rest.
    let max_height = 0.45 * ui.available_height();
    let Some(session) = session else {
        ui.label("This run has no VO step: give it more frames.");
        return None;
    };
    let camera = *session.camera();
    let truth = palette::truth_color(ui.visuals().dark_mode);

    let key = match_key(session, view);
    let step = run.steps.get(pair);
    if let Some(step) = step {
        ui.add(
            egui::Label::new(
                egui::RichText::new(format!(
                    "VO step {pair}: frame {} (left) and frame {} (right)",
                    step.from, step.to
                ))
                .strong(),
            )
            .wrap(),
        );
    }
    let Panels {
        painter,
        response,
        left,
        right,
    } = panels(ui, &key, &camera, max_height);

    let matches = session.matches();
    let wrong = session.wrong();
    let classified = session.iteration() > 0 || session.estimate().is_some();
    let mask = session.inlier_mask();
    let colour_of = |i: usize| {
        if !classified {
            UNCLASSIFIED
        } else if mask.get(i).copied().unwrap_or(false) {
            INLIER
        } else {
            OUTLIER
        }
    };
    draw_matches(
        &painter,
        (left, right),
        matches,
        colour_of,
        view.match_lines,
        view.true_outliers.then_some((wrong, truth)),
    );
    // The sample drawn last.
    if let Some(report) = session
        .last_report()
        .filter(|_| session.estimate().is_none())
    {
        for &i in &report.sample {
            if let Some(m) = matches.get(i) {
                let (a, b) = (left.to_screen(&m.left), right.to_screen(&m.right));
                painter.line_segment([a, b], Stroke::new(2.0, SAMPLE));
                painter.circle_stroke(a, 5.0, Stroke::new(2.0, SAMPLE));
                painter.circle_stroke(b, 5.0, Stroke::new(2.0, SAMPLE));
            }
        }
    }

    // The feature under the pointer and its epipolar line.
    let now_hovered = response
        .hover_pos()
        .and_then(|pointer| nearest_match((left, right), matches, pointer));
    let shown = now_hovered.or(hovered.filter(|_| response.hover_pos().is_some()));
    if let Some((right_side, i)) = shown
        && let Some(m) = matches.get(i)
    {
        let (a, b) = (left.to_screen(&m.left), right.to_screen(&m.right));
        painter.circle_stroke(a, 6.0, Stroke::new(2.0, EPIPOLAR));
        painter.circle_stroke(b, 6.0, Stroke::new(2.0, EPIPOLAR));
        let f: Option<Matrix3<f64>> = session.fundamental();
        let mut tip = format!(
            "match {i}: ({:.1}, {:.1}) px to ({:.1}, {:.1}) px",
            m.left.x, m.left.y, m.right.x, m.right.y
        );
        match f {
            Some(f) => {
                let (line, frame) = if right_side {
                    (epipolar_line(&f.transpose(), &m.right), left)
                } else {
                    (epipolar_line(&f, &m.left), right)
                };
                if let Some(ends) = line.and_then(|l| frame.clip(&l, &camera)) {
                    painter.line_segment(ends, Stroke::new(1.5, EPIPOLAR));
                }
                let d = sampson_squared(&f, m).sqrt();
                tip.push_str(&format!(
                    "\nSampson distance to the best E: {d:.2} px (inlier up to {:.1} px): {}",
                    session.config().threshold_px,
                    if mask.get(i).copied().unwrap_or(false) {
                        "inlier"
                    } else {
                        "outlier"
                    }
                ));
                tip.push_str(if right_side {
                    "\nThe blue line in the left image is F^T x_r: where this feature's match must lie."
                } else {
                    "\nThe blue line in the right image is F x_l: where this feature's match must lie."
                });
            }
            None => tip.push_str("\nNo hypothesis yet: step RANSAC to see epipolar lines."),
        }
        if wrong.get(i).copied().unwrap_or(false) {
            tip.push_str("\nTruth: this match is wrong.");
        }
        response.clone().on_hover_text_at_pointer(tip);
    }

    ui.add_space(4.0);
    top_view_ui(ui, run, pair, truth);
    now_hovered
}

/// Two image panels placed and painted: where they are on screen, the
/// hover response over them and a painter clipped to them.
pub(super) struct Panels {
    /// A painter clipped to both panels and the room around them, for what
    /// is drawn on the images.
    pub painter: egui::Painter,
    /// The pointer over the area.
    pub response: egui::Response,
    /// The first image.
    pub left: ImageFrame,
    /// The second image.
    pub right: ImageFrame,
}

/// Draws `key` (what the images show), then allocates two images of
/// `camera`'s size side by side under it, centred, each at most half the
/// width and `max_height` points high, and paints their backgrounds and
/// borders.
pub(super) fn panels(
    ui: &mut egui::Ui,
    key: &[KeyEntry],
    camera: &Intrinsics,
    max_height: f32,
) -> Panels {
    key_ui(ui, key);
    let available = ui.available_size();
    let gap = 12.0;
    let widest = ((available.x - gap) / 2.0).max(40.0);
    let aspect = (camera.height / camera.width) as f32;
    let image_height = (widest * aspect).min(max_height).max(30.0);
    let image_width = (image_height / aspect).min(widest);
    let image_height = image_width * aspect;
    let total_width = 2.0 * image_width + gap;
    let (area, response) = ui.allocate_exact_size(
        vec2(available.x.max(total_width), image_height + 4.0),
        Sense::hover(),
    );
    let left_rect = Rect::from_min_size(
        pos2(area.center().x - total_width / 2.0, area.top()),
        vec2(image_width, image_height),
    );
    let right_rect = left_rect.translate(vec2(image_width + gap, 0.0));
    let painter = ui.painter_at(area);
    let text = ui.visuals().text_color();
    let background = if ui.visuals().dark_mode {
        Color32::from_gray(34)
    } else {
        Color32::from_gray(250)
    };
    for rect in [left_rect, right_rect] {
        painter.rect_filled(rect, 0.0, background);
        painter.rect_stroke(
            rect,
            0.0,
            Stroke::new(1.0, text.gamma_multiply(0.5)),
            egui::StrokeKind::Inside,
        );
    }
    Panels {
        painter: ui.painter_at(area),
        response,
        left: ImageFrame::new(left_rect, camera),
        right: ImageFrame::new(right_rect, camera),
    }
}

/// The matches on the two images: with `match_lines` a faint line across
/// the images for each (Fig. 4.14); in the right image each match's flow
/// (from where the feature was in the left image), a rejected match's faint;
/// a dot in both images in its colour; and, with `rings`, a ring in the given
/// colour around each match flagged wrong.
pub(super) fn draw_matches(
    painter: &egui::Painter,
    (left, right): (ImageFrame, ImageFrame),
    matches: &[Correspondence],
    colour_of: impl Fn(usize) -> Color32,
    match_lines: bool,
    rings: Option<(&[bool], Color32)>,
) {
    // Lines across the images (Fig. 4.14), faint, under everything.
    if match_lines {
        for (i, m) in matches.iter().enumerate() {
            painter.line_segment(
                [left.to_screen(&m.left), right.to_screen(&m.right)],
                Stroke::new(0.6, colour_of(i).gamma_multiply(0.35)),
            );
        }
    }
    // A rejected match's flow crosses the image: drawn faint, so that the
    // inliers' short, consistent flow stays readable.
    for (i, m) in matches.iter().enumerate() {
        let c = colour_of(i);
        let alpha = if c == OUTLIER { 0.15 } else { 0.6 };
        painter.line_segment(
            [right.to_screen(&m.left), right.to_screen(&m.right)],
            Stroke::new(0.8, c.gamma_multiply(alpha)),
        );
    }
    for (i, m) in matches.iter().enumerate() {
        let c = colour_of(i);
        painter.circle_filled(left.to_screen(&m.left), 2.0, c);
        painter.circle_filled(right.to_screen(&m.right), 2.0, c);
    }
    if let Some((wrong, colour)) = rings {
        for (i, m) in matches.iter().enumerate() {
            if wrong.get(i).copied().unwrap_or(false) {
                for p in [left.to_screen(&m.left), right.to_screen(&m.right)] {
                    painter.circle_stroke(p, 4.5, Stroke::new(1.0, colour));
                }
            }
        }
    }
}

/// The match whose feature is under `pointer` (within 10 points), as (right
/// image?, index).
pub(super) fn nearest_match(
    (left, right): (ImageFrame, ImageFrame),
    matches: &[Correspondence],
    pointer: Pos2,
) -> Option<(bool, usize)> {
    let nearest = |frame: ImageFrame, right_side: bool| {
        matches
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let p = frame.to_screen(if right_side { &m.right } else { &m.left });
                (i, p.distance(pointer))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .filter(|(_, d)| *d < 10.0)
            .map(|(i, _)| (right_side, i))
    };
    if left.rect.expand(6.0).contains(pointer) {
        nearest(left, false)
    } else if right.rect.expand(6.0).contains(pointer) {
        nearest(right, true)
    } else {
        None
    }
}

/// Whose inliers the colours show: nothing yet, the best hypothesis so far (not
/// the sample just drawn), or the final estimate's.
pub fn classified_by(session: &TwoViewSession) -> &'static str {
    if session.estimate().is_some() {
        "the final E"
    } else if session.iteration() > 0 {
        "the best E so far"
    } else {
        ""
    }
}

/// The key of the two images: every mark drawn on them, and whose inliers the
/// colours show.
pub fn match_key(session: &TwoViewSession, view: &VoView) -> Vec<KeyEntry> {
    let by = classified_by(session);
    let mut key = if by.is_empty() {
        vec![KeyEntry::new(
            "match, not classified yet",
            UNCLASSIFIED,
            Mark::Dots,
        )]
    } else {
        vec![
            KeyEntry::new(format!("inlier of {by}"), INLIER, Mark::Dots),
            KeyEntry::new(format!("outlier of {by}"), OUTLIER, Mark::Dots),
        ]
    };
    key.push(KeyEntry::new(
        "flow (right image: from the feature's place on the left)",
        if by.is_empty() { UNCLASSIFIED } else { INLIER },
        Mark::Solid,
    ));
    if view.match_lines {
        key.push(KeyEntry::new(
            "match line (faint, across the images)",
            UNCLASSIFIED,
            Mark::Solid,
        ));
    }
    key.push(KeyEntry::new(
        "the sample drawn (while RANSAC runs)",
        SAMPLE,
        Mark::Solid,
    ));
    if view.true_outliers {
        key.push(KeyEntry::new(
            "truly wrong (ring)",
            UNCLASSIFIED,
            Mark::Dots,
        ));
    }
    key.push(KeyEntry::new(
        "epipolar line (hover a feature)",
        EPIPOLAR,
        Mark::Solid,
    ));
    key
}

/// The top view: truth, wheel odometry, VO scaled by the wheel speeds and VO
/// with unit steps, the station, and the step shown.
fn top_view_ui(ui: &mut egui::Ui, run: &VoRun, pair: usize, truth: Color32) {
    let height = ui.available_height().max(80.0);
    let xy = |poses: &[slamlab_sim::visual_odometry::odometry::TopPose]| -> Vec<[f64; 2]> {
        poses.iter().map(|p| [p.x, p.y]).collect()
    };
    let key = vec![
        KeyEntry::new("truth", truth, Mark::Solid),
        KeyEntry::new("wheel odometry", palette::DEAD_RECKONING, Mark::Dashed),
        KeyEntry::new("VO scaled by wheel speeds", VO_SCALED, Mark::Solid),
        KeyEntry::new("VO, unit steps", VO_UNIT, Mark::Solid),
        KeyEntry::new("this step", SAMPLE, Mark::Dots),
        KeyEntry::new("docking station", truth.gamma_multiply(0.6), Mark::Solid),
    ];
    figure_ui(
        ui,
        &Figure {
            title: "Top view of the docking approach",
            hover: "The vehicle's path seen from above (x forward along the approach, y left), \
                    at the VO frames. Monocular VO knows each step's direction, never its \
                    length: scaled by the wheel speeds (the thesis's choice) it follows the \
                    truth; with unit steps it overshoots. The box is the docking station.",
            key,
            y_label: "y (m)",
            height,
        },
        |h, y| {
            figure_plot("vo_top_view", "x (m)", y, h)
                .data_aspect(1.0)
                .include_x(-1.0)
                .include_y(-4.0)
                .include_y(4.0)
        },
        |plot_ui| {
            let station = slamlab_sim::visual_odometry::world::STATION_X;
            plot_ui.line(
                Line::new(
                    "docking station",
                    PlotPoints::new(vec![
                        [station, -1.5],
                        [station + 2.0, -1.5],
                        [station + 2.0, 1.5],
                        [station, 1.5],
                        [station, -1.5],
                    ]),
                )
                .color(truth.gamma_multiply(0.6))
                .width(1.0),
            );
            plot_ui.line(
                Line::new("wheel odometry", PlotPoints::new(xy(&run.wheel_odometry)))
                    .color(palette::DEAD_RECKONING)
                    .style(LineStyle::dashed_dense())
                    .width(1.5),
            );
            plot_ui.line(
                Line::new(
                    "VO, unit steps",
                    PlotPoints::new(xy(&run.visual_odometry_unit_scale)),
                )
                .color(VO_UNIT)
                .width(1.5),
            );
            plot_ui.line(
                Line::new(
                    "VO scaled by wheel speeds",
                    PlotPoints::new(xy(&run.visual_odometry)),
                )
                .color(VO_SCALED)
                .width(2.0),
            );
            plot_ui.line(
                Line::new("truth", PlotPoints::new(xy(&run.truth)))
                    .color(truth)
                    .width(1.2),
            );
            let here: Vec<[f64; 2]> = run
                .truth
                .iter()
                .skip(pair)
                .take(2)
                .map(|p| [p.x, p.y])
                .collect();
            plot_ui.points(
                Points::new("this step", PlotPoints::new(here))
                    .color(SAMPLE)
                    .radius(4.0),
            );
        },
    );
}
