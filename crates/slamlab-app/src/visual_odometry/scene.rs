//! A two-view scene in the centre instead of the docking run: `two-view=N`
//! in the link, which a `two-view` assignment's variant gives
//! ([`slamlab_sim::visual_odometry::assignment::TwoViewRun`]: the scene of
//! `slamlab experiment two-view` drawn from the student's seed, the very
//! matches `slamlab export-inputs two-view` writes to `matches.csv`).
//!
//! The two 640 x 480 images show the matches handed out, coloured by the
//! reference RANSAC's (eight-point, Hartley-normalized) inliers; the truly
//! wrong matches are ringed only when the assignment includes its answers or
//! once the student has dropped a relative pose (graded), so that the task is
//! not given away before it is done. Below, the top view: camera a at the
//! origin, the true camera b, each reference's b and each dropped answer's b
//! in its colour, every b placed at the true baseline along its direction of
//! travel (a monocular `t` has no length).

use super::images::{self, INLIER, OUTLIER, Panels, UNCLASSIFIED};
use crate::palette;
use crate::widgets::estimates::{Estimate, EstimateContent};
use crate::widgets::plots::{Figure, KeyEntry, Mark, figure_plot, figure_ui};
use egui::Color32;
use egui_plot::{Line, PlotPoints, Points};
use slamlab_core::vision::{RelativePose, rotation_angle};
use slamlab_core::{Pose2, math};
use slamlab_sim::params;
use slamlab_sim::visual_odometry::VoScenario;
use slamlab_sim::visual_odometry::assignment::{
    ANSWERS_KEY, MAX_MATCHES, MIN_MATCHES, SCENE_KEY, TwoViewRun,
};

/// The reference whose inliers colour the matches (the assignment's
/// reference solution).
pub const REFERENCE: &str = "eight-point";

/// The length of a camera's heading tick in the top view, metres.
const TICK_M: f64 = 0.5;

/// A two-view scene and how it is shown.
#[derive(Debug)]
pub struct TwoViewScene {
    /// The scene: camera, matches, truth, references.
    pub run: TwoViewRun,
    /// The centre shows the scene (else the docking run).
    pub show: bool,
    /// Ring the truly wrong matches when they may be shown.
    pub mark_wrong: bool,
    /// The feature under the pointer: (right image?, match index).
    hovered: Option<(bool, usize)>,
}

/// What the link asks for: `two-view=N` (the scene's matches) and
/// `two-view-answers=on`, with the notices of bad values; the other pairs are
/// the lesson's parameters.
#[derive(Debug, Default)]
pub struct SceneLink {
    /// The number of matches, when the link asks for a scene.
    pub matches: Option<usize>,
    /// The wrong matches may be shown from the start.
    pub answers: bool,
    /// The link's problems ("link: …").
    pub notices: Vec<String>,
}

impl SceneLink {
    /// Splits the scene's keys from `pairs` (returned: the rest).
    pub fn from_pairs(pairs: &[(String, String)]) -> (Self, Vec<(String, String)>) {
        let mut link = Self::default();
        let mut rest = Vec::new();
        for (key, value) in pairs {
            if key == SCENE_KEY {
                match value.trim().parse::<u64>() {
                    Ok(n) if (MIN_MATCHES..=MAX_MATCHES).contains(&n) => {
                        link.matches = usize::try_from(n).ok();
                    }
                    _ => link.notices.push(format!(
                        "link: {SCENE_KEY} = {value}: the number of matches of a two-view scene, {MIN_MATCHES} to {MAX_MATCHES}; the docking run opens"
                    )),
                }
            } else if key == ANSWERS_KEY {
                match value.trim() {
                    "on" | "1" | "true" => link.answers = true,
                    "off" | "0" | "false" => link.answers = false,
                    _ => link.notices.push(format!(
                        "link: {ANSWERS_KEY} = {value}: on or off; the wrong matches are marked once an answer is graded"
                    )),
                }
            } else {
                rest.push((key.clone(), value.clone()));
            }
        }
        (link, rest)
    }
}

impl TwoViewScene {
    /// The scene of `scenario`'s seed and parameters with `matches` matches,
    /// shown.
    pub fn new(scenario: &VoScenario, matches: usize, answers: bool) -> Self {
        let mut run = TwoViewRun::simulate(scenario, matches);
        run.answers_included = answers;
        Self {
            run,
            show: true,
            mark_wrong: true,
            hovered: None,
        }
    }

    /// Draws the scene again when `scenario` changes what it is made of (its
    /// seed, the noise, the share of wrong matches, the references' RANSAC).
    pub fn follow(&mut self, scenario: &VoScenario) {
        if scenario.settings != self.run.scenario.settings {
            let answers = self.run.answers_included;
            self.run = TwoViewRun::simulate(scenario, self.run.matches.len());
            self.run.answers_included = answers;
            self.hovered = None;
        }
    }

    /// The link's pairs that draw this scene again.
    pub fn share_pairs(&self) -> Vec<(String, String)> {
        let mut pairs = vec![(SCENE_KEY.to_owned(), self.run.matches.len().to_string())];
        if self.run.answers_included {
            pairs.push((ANSWERS_KEY.to_owned(), "on".to_owned()));
        }
        pairs
    }

    /// The reference RANSAC's inliers (empty: it found no pose).
    pub fn inliers(&self) -> &[bool] {
        self.run
            .inliers
            .iter()
            .find(|(name, _)| name == REFERENCE)
            .map_or(&[], |(_, i)| i.as_slice())
    }

    /// May the truly wrong matches be told apart: the assignment includes its
    /// answers, or a relative pose was dropped (graded).
    pub fn wrong_may_show(&self, estimates: &[Estimate]) -> bool {
        self.run.answers_included
            || estimates
                .iter()
                .any(|e| matches!(e.content, EstimateContent::RelativePose(_)))
    }

    /// The true relative pose and the references', by name (the estimates
    /// window scores a dropped pose against `truth`).
    pub fn relative_poses(&self) -> Vec<(String, RelativePose)> {
        std::iter::once(("truth".to_owned(), self.run.truth))
            .chain(
                self.run
                    .references
                    .iter()
                    .filter_map(|(name, pose)| Some((name.clone(), (*pose)?))),
            )
            .collect()
    }

    /// The header's line.
    pub fn subtitle(&self) -> String {
        let s = &self.run.scenario.settings;
        format!(
            "two views, seed {}: {} matches, {:.0}% wrong, {} px noise; {} RANSAC keeps {}",
            s.seed,
            self.run.matches.len(),
            100.0 * s.outliers,
            params::format_number(s.noise_px),
            REFERENCE,
            self.inliers().iter().filter(|i| **i).count()
        )
    }

    /// The panel's section: what the scene is, and its switches.
    pub fn controls_ui(&mut self, ui: &mut egui::Ui, estimates: &[Estimate]) {
        ui.strong("Your two views");
        let s = &self.run.scenario.settings;
        ui.label(format!(
            "The two-view scene of seed {} (a 640 x 480 camera with a 60° field of view, a 2 m \
             baseline): {} matches, about {:.0}% of them wrong, {} px noise: the K.txt and \
             matches.csv of the assignment.",
            s.seed,
            self.run.matches.len(),
            100.0 * s.outliers,
            params::format_number(s.noise_px)
        ));
        ui.checkbox(&mut self.show, "Show the two views (not the docking run)")
            .on_hover_text(
                "The docking approach is the lesson's own run: RANSAC stepped one sample at a time",
            );
        let may_show = self.wrong_may_show(estimates);
        ui.add_enabled(
            may_show,
            egui::Checkbox::new(&mut self.mark_wrong, "Ring the truly wrong matches"),
        )
        .on_hover_text("The matches that were made wrong (a random pixel in the second image)")
        .on_disabled_hover_text(
            "Shown once your relative pose is graded (drop it on the page), or from the start \
             when the assignment includes its answers",
        );
    }

    /// The two images with the matches, then the top view. `match_lines`:
    /// a line across the images for each match.
    pub fn centre_ui(&mut self, ui: &mut egui::Ui, estimates: &[Estimate], match_lines: bool) {
        let max_height = 0.45 * ui.available_height();
        let truth = palette::truth_color(ui.visuals().dark_mode);
        let inliers = self.inliers();
        let rings = self.mark_wrong && self.wrong_may_show(estimates);
        ui.add(
            egui::Label::new(
                egui::RichText::new(format!(
                    "Your two views: view a (left) and view b (right), {} matches",
                    self.run.matches.len()
                ))
                .strong(),
            )
            .wrap(),
        );
        let found = !inliers.is_empty();
        let mut key = if found {
            vec![
                KeyEntry::new(format!("inlier of {REFERENCE} RANSAC"), INLIER, Mark::Dots),
                KeyEntry::new(
                    format!("outlier of {REFERENCE} RANSAC"),
                    OUTLIER,
                    Mark::Dots,
                ),
            ]
        } else {
            vec![KeyEntry::new(
                format!("match ({REFERENCE} RANSAC found no pose)"),
                UNCLASSIFIED,
                Mark::Dots,
            )]
        };
        key.push(KeyEntry::new(
            "flow (right image: from the feature's place on the left)",
            if found { INLIER } else { UNCLASSIFIED },
            Mark::Solid,
        ));
        if rings {
            key.push(KeyEntry::new("truly wrong (ring)", truth, Mark::Dots));
        }
        let Panels {
            painter,
            response,
            left,
            right,
        } = images::panels(ui, &key, &self.run.camera, max_height);
        let colour_of = |i: usize| match inliers.get(i) {
            Some(true) => INLIER,
            Some(false) => OUTLIER,
            None => UNCLASSIFIED,
        };
        images::draw_matches(
            &painter,
            (left, right),
            &self.run.matches,
            colour_of,
            match_lines,
            rings.then_some((self.run.wrong.as_slice(), truth)),
        );
        let now = response
            .hover_pos()
            .and_then(|p| images::nearest_match((left, right), &self.run.matches, p));
        let shown = now.or(self.hovered.filter(|_| response.hover_pos().is_some()));
        if let Some((_, i)) = shown
            && let Some(m) = self.run.matches.get(i)
        {
            let stroke = egui::Stroke::new(2.0, images::EPIPOLAR);
            painter.circle_stroke(left.to_screen(&m.left), 6.0, stroke);
            painter.circle_stroke(right.to_screen(&m.right), 6.0, stroke);
            let mut tip = format!(
                "match {i} (line {} of matches.csv): ({:.1}, {:.1}) px to ({:.1}, {:.1}) px\n{} of {REFERENCE} RANSAC",
                i + 2,
                m.left.x,
                m.left.y,
                m.right.x,
                m.right.y,
                match inliers.get(i) {
                    Some(true) => "an inlier",
                    Some(false) => "an outlier",
                    None => "not classified",
                }
            );
            if rings && self.run.wrong.get(i).copied().unwrap_or(false) {
                tip.push_str("\nTruth: this match is wrong.");
            }
            response.clone().on_hover_text_at_pointer(tip);
        }
        self.hovered = now;
        ui.add_space(4.0);
        self.top_view_ui(ui, estimates, truth);
    }

    /// Each camera b of the top view: (name, colour, pose), the truth first,
    /// then the references, then the dropped answers.
    pub fn top_view(
        &self,
        estimates: &[Estimate],
        truth: Color32,
    ) -> Vec<(String, Color32, Pose2)> {
        let mut out = vec![(
            "true b".to_owned(),
            truth,
            self.run.top_view_of(&self.run.truth),
        )];
        for (name, pose) in &self.run.references {
            if let Some(pose) = pose {
                out.push((
                    format!("b by {name}"),
                    reference_color(name),
                    self.run.top_view_of(pose),
                ));
            }
        }
        for e in answers(estimates) {
            if let EstimateContent::RelativePose(pose) = &e.content {
                out.push((
                    format!("b by {}", e.name),
                    e.color,
                    self.run.top_view_of(pose),
                ));
            }
        }
        out
    }

    fn top_view_ui(&self, ui: &mut egui::Ui, estimates: &[Estimate], truth: Color32) {
        let height = ui.available_height().max(80.0);
        let cameras = self.top_view(estimates, truth);
        let text = ui.visuals().text_color();
        let mut key = vec![KeyEntry::new("camera a (origin)", text, Mark::Dots)];
        key.extend(cameras.iter().enumerate().map(|(k, (name, colour, _))| {
            let name = if k == 0 {
                format!("{name} (ring)")
            } else {
                name.clone()
            };
            KeyEntry::new(name, *colour, Mark::Dots)
        }));
        let baseline = self.run.truth.translation.norm();
        figure_ui(
            ui,
            &Figure {
                title: "Top view of the two cameras",
                hover: "Seen from above: camera a at the origin looking along x (forward), y to \
                        its left; a tick shows where each camera looks. Each camera b is \
                        placed at the true baseline along its direction of travel (-Rᵀt): two \
                        views cannot tell how far the camera moved, only where to.",
                key,
                y_label: "y, left (m)",
                height,
            },
            |h, y| {
                figure_plot("vo_two_view_top", "x, forward (m)", y, h)
                    .data_aspect(1.0)
                    .include_x(-baseline - 0.5)
                    .include_x(baseline + 0.5)
                    .include_y(-baseline - 0.5)
                    .include_y(baseline + 0.5)
            },
            |plot_ui| {
                let tick = |p: &Pose2| {
                    vec![
                        [p.x, p.y],
                        [
                            p.x + TICK_M * math::cos(p.theta),
                            p.y + TICK_M * math::sin(p.theta),
                        ],
                    ]
                };
                plot_ui.line(
                    Line::new("camera a", PlotPoints::new(tick(&Pose2::IDENTITY)))
                        .color(text)
                        .width(2.0),
                );
                plot_ui.points(
                    Points::new("camera a", PlotPoints::new(vec![[0.0, 0.0]]))
                        .color(text)
                        .radius(4.0),
                );
                // The references, then the answers over them, the truth
                // last: a ring around its place, so that an answer on it
                // stays visible inside.
                let order = (1..cameras.len()).chain(std::iter::once(0));
                for (k, (name, colour, pose)) in order.filter_map(|k| Some((k, cameras.get(k)?))) {
                    let truth = k == 0;
                    plot_ui.line(
                        Line::new(
                            name.clone(),
                            PlotPoints::new(vec![[0.0, 0.0], [pose.x, pose.y]]),
                        )
                        .color(colour.gamma_multiply(0.35))
                        .width(1.0),
                    );
                    plot_ui.line(
                        Line::new(name.clone(), PlotPoints::new(tick(pose)))
                            .color(*colour)
                            .width(if truth { 1.2 } else { 2.0 }),
                    );
                    plot_ui.points(
                        Points::new(name.clone(), PlotPoints::new(vec![[pose.x, pose.y]]))
                            .color(*colour)
                            .filled(!truth)
                            .radius(if truth { 8.0 } else { 4.0 }),
                    );
                }
            },
        );
    }

    /// For the UI and browser tests: the scene shown (its matches to the
    /// bit, the true pose), the reference's inliers, whether the wrong ones
    /// show, and the top view.
    pub fn test_state(&self, estimates: &[Estimate]) -> serde_json::Value {
        let r = &self.run.truth.rotation;
        let t = &self.run.truth.translation;
        let top: Vec<serde_json::Value> = self
            .top_view(estimates, Color32::WHITE)
            .into_iter()
            .map(|(name, _, p)| serde_json::json!({ "name": name, "pose": [p.x, p.y, p.theta] }))
            .collect();
        serde_json::json!({
            "showing": self.show,
            "seed": self.run.scenario.settings.seed,
            "matches": self.run.matches.len(),
            "pixels": self
                .run
                .matches
                .iter()
                .map(|m| [m.left.x, m.left.y, m.right.x, m.right.y])
                .collect::<Vec<_>>(),
            "truth": {
                "rotation": [r[(0, 0)], r[(0, 1)], r[(0, 2)], r[(1, 0)], r[(1, 1)], r[(1, 2)], r[(2, 0)], r[(2, 1)], r[(2, 2)]],
                "translation": [t.x, t.y, t.z],
                "rotation_deg": rotation_angle(r).to_degrees(),
            },
            "inliers": self.inliers().iter().filter(|i| **i).count(),
            "wrong": self.run.wrong.iter().filter(|w| **w).count(),
            "answers_included": self.run.answers_included,
            "wrong_shown": self.mark_wrong && self.wrong_may_show(estimates),
            "top_view": top,
        })
    }
}

/// The colour of a reference's camera b: the solution's blue, the five-point
/// sky blue, the starter's naive answer dead reckoning's grey.
fn reference_color(name: &str) -> Color32 {
    match name {
        REFERENCE => palette::BLUE,
        "five-point" => palette::SKY_BLUE,
        "naive" => palette::DEAD_RECKONING,
        _ => palette::PURPLE,
    }
}

/// The note over the explanation and the plots while the two views show:
/// they are the docking run's.
pub fn docking_note(ui: &mut egui::Ui) {
    ui.label(
        egui::RichText::new(
            "These are the docking run's (the centre shows the two views): untick \"Show the \
             two views\" in the parameters panel to see it.",
        )
        .small()
        .weak(),
    );
}

/// The dropped relative poses (the student's answers), drawn ones only.
fn answers(estimates: &[Estimate]) -> Vec<&Estimate> {
    estimates
        .iter()
        .filter(|e| e.visible && matches!(e.content, EstimateContent::RelativePose(_)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(list: &[(&str, &str)]) -> Vec<(String, String)> {
        list.iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect()
    }

    /// The scene's keys are taken out of the lesson's pairs; a bad value is
    /// a notice naming it, and the docking run opens.
    #[test]
    fn the_links_scene_keys_are_read_and_bad_values_said() {
        let (link, rest) = SceneLink::from_pairs(&pairs(&[
            ("seed", "3"),
            ("two-view", "215"),
            ("two-view-answers", "on"),
            ("outliers", "0.3"),
        ]));
        assert_eq!((link.matches, link.answers), (Some(215), true));
        assert!(link.notices.is_empty());
        assert_eq!(rest, pairs(&[("seed", "3"), ("outliers", "0.3")]));
        for (value, answers) in [("3", "maybe"), ("x", "2"), ("5001", "yes"), ("-1", "")] {
            let (link, rest) = SceneLink::from_pairs(&pairs(&[
                ("two-view", value),
                ("two-view-answers", answers),
            ]));
            assert_eq!((link.matches, link.answers), (None, false), "{value}");
            assert_eq!(link.notices.len(), 2, "{:?}", link.notices);
            assert!(link.notices[0].contains(&format!("two-view = {value}")));
            assert!(link.notices[0].contains("16 to 5000"));
            assert!(rest.is_empty());
        }
    }
}
