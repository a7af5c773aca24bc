//! A student's own estimates, brought into any lesson: a TUM or CSV trajectory
//! (with or without covariances), a landmark CSV, (in the two-view lesson) a
//! relative pose of two views or (in a lesson with a true occupancy map) a ROS
//! map, its YAML with its PGM or PNG image, dropped on the page, opened
//! from the File menu or named by `estimate=` in the URL. Each becomes one more
//! estimator of the lesson, drawn on its map in a colour of its own up to the time
//! bar's time, and scored against the lesson's truth with the same metrics as
//! the lesson's own estimators (`slamlab_sim::metrics`, equal to evo), in the
//! "Your estimates" window: ATE and RPE, NEES where covariances were given, and
//! the position error over time beside the built-in estimators'; for a relative
//! pose, the rotation error and the angle between the translation directions;
//! for a map, the mapping lesson's agreement and coverage against the true map
//! (`grid::occupancy_agreement`, `grid::occupancy_coverage`).
//!
//! Written once for every lesson: a lesson only says what its trajectories are
//! ([`crate::lesson::Lesson::trajectories`]); the frame holds the estimates, the
//! shell routes files to them and draws the overlay and the window.

use crate::palette;
use egui::{Color32, Pos2, Stroke};
use slamlab_core::Pose2;
use slamlab_core::grid::{Cell, OccupancyGrid};
use slamlab_core::vision::RelativePose;
use slamlab_sim::io::relative_pose;
use slamlab_sim::io::trajectory::{self, LandmarkRow, TrajectoryFormat};
use slamlab_sim::metrics::{
    Alignment, EvaluationSettings, NamedTrajectory, Trajectory, TrajectoryRole, evaluate,
};
use std::sync::Arc;

pub use crate::query::MAX_ESTIMATES;

/// The colours of students' estimates (Paul Tol's muted scheme, apart from the
/// lessons' own Okabe-Ito colours).
pub const COLORS: [Color32; 5] = [
    Color32::from_rgb(0x88, 0x22, 0x55),
    Color32::from_rgb(0x44, 0xAA, 0x99),
    Color32::from_rgb(0x99, 0x99, 0x33),
    Color32::from_rgb(0x33, 0x22, 0x88),
    Color32::from_rgb(0xAA, 0x44, 0x99),
];

/// The first of [`COLORS`] not among `used` (the colours a student's files
/// already have); with every colour taken, the next in turn.
pub fn free_color(used: impl Iterator<Item = Color32>) -> Color32 {
    let used: Vec<Color32> = used.collect();
    COLORS
        .iter()
        .copied()
        .find(|c| !used.contains(c))
        .unwrap_or(COLORS[used.len() % COLORS.len()])
}

/// What an estimate file holds.
#[derive(Clone, Debug, PartialEq)]
pub enum EstimateContent {
    /// A trajectory.
    Trajectory(Trajectory),
    /// Landmark positions.
    Landmarks(Vec<LandmarkRow>),
    /// A relative pose of two views (`X_b = R X_a + t`).
    RelativePose(RelativePose),
    /// An occupancy map (a ROS map: YAML and image).
    Map(Arc<OccupancyGrid>),
}

/// One estimate a student brought in.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The file's name.
    pub name: String,
    /// Its colour.
    pub color: Color32,
    /// What it holds.
    pub content: EstimateContent,
    /// Drawn on the map.
    pub visible: bool,
}

/// One estimator's score against the lesson's reference, as the window and the
/// test hook show it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EstimateScore {
    /// The estimator's name (a file's name for a student's estimate).
    pub name: String,
    /// A student's estimate (not one of the lesson's).
    pub dropped: bool,
    /// RMSE of the absolute position error, metres (SE(2)-aligned when
    /// [`Estimates::align`] is on).
    pub ate_rmse: Option<f64>,
    /// The largest position error, metres.
    pub ate_max: Option<f64>,
    /// RMSE of the relative translation error over one pose, metres.
    pub rpe_rmse: Option<f64>,
    /// The average NEES (covariances only).
    pub anees: Option<f64>,
    /// The share of NEES values inside the 95 % band.
    pub nees_in_band: Option<f64>,
    /// Pairs compared.
    pub pairs: usize,
    /// For landmarks: the RMS distance to the true landmarks, metres.
    pub landmark_rmse: Option<f64>,
    /// For a relative pose: the angle of `R_trueᵀ R`, degrees.
    pub rotation_error_deg: Option<f64>,
    /// For a relative pose: the angle between the estimated and the true
    /// direction of translation, degrees.
    pub direction_error_deg: Option<f64>,
    /// For a map: the share of the true map's known cells it classifies as
    /// the truth does, over the cells it knows (`grid::occupancy_agreement`).
    pub map_agreement: Option<f64>,
    /// For a map: the share of the true map's known cells it knows
    /// (`grid::occupancy_coverage`, as the grid-mapping assignment grades it).
    pub map_coverage: Option<f64>,
    /// Why there is no score, or what to know about it.
    pub note: Option<String>,
    /// Position error over time `[t, e]`, for the plot.
    #[serde(skip)]
    pub errors: Vec<[f64; 2]>,
    /// The line's colour.
    #[serde(skip)]
    pub color: Color32,
}

/// The estimates a lesson holds, and their scores.
#[derive(Debug, Default)]
pub struct Estimates {
    items: Vec<Estimate>,
    version: u64,
    /// The "Your estimates" window is open.
    pub open: bool,
    /// Align each trajectory to the reference (SE(2)) before the absolute error.
    pub align: bool,
    scores: Vec<EstimateScore>,
    scored: Option<(u64, u64, bool)>,
    /// The maps' scores by the maps they compare.
    map_scores: MapScores,
    /// The maps' overlays on the GPU, by estimate name and version.
    textures: MapTextures,
}

/// Map scores by the two maps they compare (the same `Arc`s, the same
/// score): the run is scored again every tick, but a map is compared with the
/// true map again only when it is another map (the mapping lesson's built map
/// is a new one only after its grid changed; a student's never changes).
#[derive(Debug, Default)]
struct MapScores {
    /// The last scoring's: (map, true map, agreement, coverage).
    last: Vec<MapScore>,
    /// This scoring's so far.
    now: Vec<MapScore>,
    /// Comparisons made, for the tests.
    compared: usize,
}

type MapScore = (
    Arc<OccupancyGrid>,
    Arc<OccupancyGrid>,
    Option<f64>,
    Option<f64>,
);

impl MapScores {
    /// The agreement and coverage of `map` against `truth`, from the last
    /// scoring when it compared the same two.
    fn of(
        &mut self,
        map: &Arc<OccupancyGrid>,
        truth: &Arc<OccupancyGrid>,
    ) -> (Option<f64>, Option<f64>) {
        let same = |(m, t, _, _): &&MapScore| Arc::ptr_eq(m, map) && Arc::ptr_eq(t, truth);
        let (agreement, coverage) = match self.last.iter().chain(&self.now).find(same) {
            Some((_, _, a, c)) => (*a, *c),
            None => {
                self.compared += 1;
                (
                    slamlab_sim::grid::occupancy_agreement(map, truth),
                    slamlab_sim::grid::occupancy_coverage(map, truth),
                )
            }
        };
        self.now
            .push((map.clone(), truth.clone(), agreement, coverage));
        (agreement, coverage)
    }

    /// Ends a scoring: what it compared is what the next one looks up.
    fn finish(&mut self) {
        self.last = std::mem::take(&mut self.now);
    }
}

/// The maps' overlays on the GPU: (estimate name, estimates version, texture).
#[derive(Default)]
struct MapTextures(Vec<(String, u64, egui::TextureHandle)>);

impl std::fmt::Debug for MapTextures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|(name, v, _)| (name, v)))
            .finish()
    }
}

/// Is this file part of a ROS map (its YAML or its PGM or PNG image)?
pub use super::laser_inputs::is_map_file;

/// Reads a ROS map from the files dropped or opened together: the YAML and the
/// image it names (`image:`, matched by file name), as the laser lessons read a
/// dropped map (`kidnap::session::load_dropped_map`), but never a lone image: a
/// student's map is scored where it lies, so it needs its YAML's resolution and
/// origin. Returns the YAML's name and the grid; a refusal names the file and why.
pub fn read_map_files(files: &[(String, Vec<u8>)]) -> Result<(String, OccupancyGrid), String> {
    use slamlab_sim::io::ros_map::MAX_YAML_BYTES;
    let lower = |n: &str| n.to_ascii_lowercase();
    let yaml = files
        .iter()
        .find(|(n, _)| lower(n).ends_with(".yaml") || lower(n).ends_with(".yml"));
    let Some((yaml_name, yaml_bytes)) = yaml else {
        let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
        return Err(format!(
            "{}: a map needs its YAML (resolution, origin) with the image: drop or open both together",
            names.join(", ")
        ));
    };
    if yaml_bytes.len() > MAX_YAML_BYTES {
        return Err(format!(
            "{yaml_name} has {} bytes, more than the {MAX_YAML_BYTES} bytes a map's YAML may have",
            yaml_bytes.len()
        ));
    }
    let (name, grid, _) = slamlab_sim::kidnap::session::load_dropped_map(files)?;
    Ok((name, grid))
}

/// Is this file a student's estimate rather than a lesson's input (a map, a log,
/// a graph)? TUM (`.tum`, or a `.txt` whose first line has eight numbers), CSV
/// files and relative poses (a `.txt` of 12 or 7 numbers) are.
pub fn is_estimate_file(name: &str, bytes: &[u8]) -> bool {
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".tum") || lower.ends_with(".csv") {
        return true;
    }
    lower.ends_with(".txt")
        && (matches!(trajectory::detect_format(bytes), Ok(TrajectoryFormat::Tum))
            || relative_pose::is_relative_pose(bytes))
}

impl Estimates {
    /// The estimates, in the order they came.
    pub fn items(&self) -> &[Estimate] {
        &self.items
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Reads a dropped or opened file; returns what to tell the student. The
    /// estimates already there stay whatever the file holds.
    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<String, String> {
        trajectory::check_size(bytes.len() as u64).map_err(|e| format!("{name}: {e}"))?;
        if self.items.len() >= MAX_ESTIMATES {
            return Err(format!(
                "{name}: the lesson holds {MAX_ESTIMATES} estimates at most; remove one first"
            ));
        }
        let is_landmarks = name.to_ascii_lowercase().ends_with(".csv") && {
            let first = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)])
                .lines()
                .map(str::trim)
                .find(|l| !l.is_empty() && !l.starts_with('#'))
                .unwrap_or("")
                .to_ascii_lowercase();
            first.starts_with("id") || matches!(first.split(',').count(), 3 | 6)
        };
        let (content, notices) = if is_landmarks {
            let rows = trajectory::read_landmarks(bytes).map_err(|e| format!("{name}: {e}"))?;
            (EstimateContent::Landmarks(rows), Vec::new())
        } else if relative_pose::is_relative_pose(bytes) {
            let file =
                relative_pose::read_relative_pose(bytes).map_err(|e| format!("{name}: {e}"))?;
            (EstimateContent::RelativePose(file.pose), file.notices)
        } else {
            let file =
                trajectory::read_trajectory(name, bytes).map_err(|e| format!("{name}: {e}"))?;
            (EstimateContent::Trajectory(file.trajectory), file.notices)
        };
        let color = self.free_color();
        let what = match &content {
            EstimateContent::Trajectory(t) => format!(
                "{} poses{}",
                t.len(),
                if t.covariances().is_some() {
                    " with covariances"
                } else {
                    ""
                }
            ),
            EstimateContent::Landmarks(rows) => format!("{} landmarks", rows.len()),
            EstimateContent::RelativePose(_) => "a relative pose of two views".to_owned(),
            EstimateContent::Map(_) => "a map".to_owned(),
        };
        self.items.push(Estimate {
            name: name.to_owned(),
            color,
            content,
            visible: true,
        });
        self.version += 1;
        self.open = true;
        let mut message = format!("Your estimate {name}: {what}");
        for n in notices {
            message.push_str("; ");
            message.push_str(&n);
        }
        Ok(message)
    }

    /// Reads a ROS map (its YAML and image, dropped or opened together) as one
    /// more estimate, named after its YAML; returns what to tell the student.
    /// Any resolution, origin and size is taken: it is scored where it covers
    /// the true map, each true cell looked up at its centre (see
    /// `grid::occupancy_agreement`). Drawn once asked for (*draw* in the window).
    pub fn add_map(&mut self, files: &[(String, Vec<u8>)]) -> Result<String, String> {
        for (name, bytes) in files {
            trajectory::check_size(bytes.len() as u64).map_err(|e| format!("{name}: {e}"))?;
        }
        let (name, grid) = read_map_files(files)?;
        if self.items.len() >= MAX_ESTIMATES {
            return Err(format!(
                "{name}: the lesson holds {MAX_ESTIMATES} estimates at most; remove one first"
            ));
        }
        let (w, h, r) = (grid.width(), grid.height(), grid.resolution());
        let color = self.free_color();
        self.items.push(Estimate {
            name: name.clone(),
            color,
            content: EstimateContent::Map(Arc::new(grid)),
            visible: false,
        });
        self.version += 1;
        self.open = true;
        Ok(format!(
            "Your map {name}: {w} x {h} cells of {r} m, scored against the true map (draw it from \"Your estimates\")"
        ))
    }

    /// The first colour no estimate has.
    fn free_color(&self) -> Color32 {
        free_color(self.items.iter().map(|e| e.color))
    }

    /// Draws estimate `index` on the map or not.
    pub fn set_visible(&mut self, index: usize, visible: bool) {
        if let Some(e) = self.items.get_mut(index) {
            e.visible = visible;
        }
    }

    /// Removes estimate `index`.
    pub fn remove(&mut self, index: usize) {
        if index < self.items.len() {
            self.items.remove(index);
            self.version += 1;
        }
    }

    /// Whether the scores are older than the run (`run_version`: what changes
    /// when the run does) or the estimates.
    pub fn is_stale(&self, run_version: u64) -> bool {
        self.scored != Some((run_version, self.version, self.align))
    }

    /// Scores the lesson's estimators and the student's against the lesson's
    /// truth (or, without one, against its first estimator).
    pub fn score(&mut self, run_version: u64, lesson: &LessonOutput) -> &[EstimateScore] {
        self.scores = score_all(&self.items, lesson, self.align, &mut self.map_scores);
        self.scored = Some((run_version, self.version, self.align));
        &self.scores
    }

    /// The scores last computed.
    pub fn last_scores(&self) -> &[EstimateScore] {
        &self.scores
    }
}

/// What a lesson gives its estimates to be scored against: its trajectories, its
/// landmark maps and its relative poses, each with the truth named `truth`.
#[derive(Clone, Debug, Default)]
pub struct LessonOutput {
    /// The truth and the estimators' paths.
    pub trajectories: Vec<NamedTrajectory>,
    /// The true landmarks (`truth`) and each estimator's.
    pub landmarks: Vec<(String, Vec<LandmarkRow>)>,
    /// The true relative pose of the two views shown (`truth`) and the lesson's
    /// estimate of it.
    pub relative_poses: Vec<(String, RelativePose)>,
    /// The true occupancy map (`truth`) and each estimator's map as a ROS map
    /// (three states, as File → Export map writes it).
    pub maps: Vec<(String, Arc<OccupancyGrid>)>,
}

/// A score with nothing in it yet.
fn empty_score(name: &str, dropped: bool, color: Color32) -> EstimateScore {
    EstimateScore {
        name: name.to_owned(),
        dropped,
        ate_rmse: None,
        ate_max: None,
        rpe_rmse: None,
        anees: None,
        nees_in_band: None,
        pairs: 0,
        landmark_rmse: None,
        rotation_error_deg: None,
        direction_error_deg: None,
        map_agreement: None,
        map_coverage: None,
        note: None,
        errors: Vec::new(),
        color,
    }
}

/// A relative pose scored against the true one.
fn score_relative_pose(
    name: &str,
    dropped: bool,
    color: Color32,
    pose: &RelativePose,
    truth: Option<&RelativePose>,
) -> EstimateScore {
    let mut score = empty_score(name, dropped, color);
    match truth {
        Some(t) => match slamlab_sim::metrics::relative_pose_error(
            &pose.rotation,
            &pose.translation,
            &t.rotation,
            &t.translation,
        ) {
            Some(e) => {
                score.rotation_error_deg = Some(e.rotation_deg);
                score.direction_error_deg = Some(e.translation_direction_deg);
            }
            None => score.note = Some("a translation of length zero has no direction".to_owned()),
        },
        None => {
            score.note =
                Some("this lesson shows no pair of views with a true relative pose".to_owned());
        }
    }
    score
}

/// A map scored against the true map with the mapping lesson's metric: the
/// agreement over the cells it knows and the share of the true map it knows,
/// each true free or occupied cell looked up at its centre in `map` (so a map
/// of another resolution, origin or size is compared where it covers the
/// truth; cells outside it are unknown).
fn score_map(
    name: &str,
    dropped: bool,
    color: Color32,
    map: &Arc<OccupancyGrid>,
    truth: Option<&Arc<OccupancyGrid>>,
    scores: &mut MapScores,
) -> EstimateScore {
    let mut score = empty_score(name, dropped, color);
    match truth {
        Some(truth) => {
            (score.map_agreement, score.map_coverage) = scores.of(map, truth);
            if score.map_agreement.is_none() {
                score.note = Some(
                    "the map knows none of the true map's cells (another place, or another origin?)"
                        .to_owned(),
                );
            }
        }
        None => {
            score.note = Some("this run has no true map to score a map against".to_owned());
        }
    }
    score
}

/// The reference: the lesson's truth, or without one its first estimator.
fn reference_of(trajectories: &[NamedTrajectory]) -> Option<&NamedTrajectory> {
    trajectories
        .iter()
        .find(|t| t.role == TrajectoryRole::Truth)
        .or_else(|| {
            trajectories
                .iter()
                .find(|t| t.role == TrajectoryRole::Estimate)
        })
}

fn score_trajectory(
    name: &str,
    dropped: bool,
    color: Color32,
    estimate: &Trajectory,
    reference: &Trajectory,
    align: bool,
) -> EstimateScore {
    let settings = EvaluationSettings {
        alignment: if align {
            Alignment::Se2
        } else {
            Alignment::None
        },
        ..EvaluationSettings::default()
    };
    let mut score = empty_score(name, dropped, color);
    match evaluate(reference, estimate, &settings) {
        Ok(e) => {
            score.ate_rmse = Some(e.ape.translation.rmse);
            score.ate_max = Some(e.ape.translation.max);
            score.rpe_rmse = e.rpe.as_ref().map(|r| r.translation.rmse);
            if let Some(n) = &e.nees {
                score.anees = n.anees;
                score.nees_in_band = n.share_in_band;
            }
            score.pairs = e.pairing.pairs;
            score.errors = e
                .pair_times(reference)
                .into_iter()
                .zip(&e.ape.translation_m)
                .map(|(t, err)| [t, *err])
                .collect();
            score.note = e.notices.first().cloned();
        }
        Err(why) => score.note = Some(why.to_string()),
    }
    score
}

fn score_all(
    items: &[Estimate],
    lesson: &LessonOutput,
    align: bool,
    map_scores: &mut MapScores,
) -> Vec<EstimateScore> {
    let true_pose = lesson
        .relative_poses
        .iter()
        .find(|(name, _)| name == "truth")
        .map(|(_, p)| p);
    let mut all: Vec<EstimateScore> = lesson
        .relative_poses
        .iter()
        .filter(|(name, _)| name != "truth")
        .map(|(name, p)| {
            score_relative_pose(name, false, palette::estimator_color(name), p, true_pose)
        })
        .collect();
    let reference = reference_of(&lesson.trajectories);
    all.extend(
        lesson
            .trajectories
            .iter()
            .filter(|t| {
                reference.is_some_and(|r| !std::ptr::eq(*t, r)) && t.role != TrajectoryRole::Truth
            })
            .map(|t| {
                score_trajectory(
                    &t.name,
                    false,
                    if t.role == TrajectoryRole::Odometry {
                        palette::DEAD_RECKONING
                    } else {
                        palette::estimator_color(&t.name)
                    },
                    &t.trajectory,
                    reference.map_or(&t.trajectory, |r| &r.trajectory),
                    align,
                )
            }),
    );
    let true_map = lesson
        .maps
        .iter()
        .find(|(name, _)| name == "truth")
        .map(|(_, m)| m);
    for (name, m) in lesson.maps.iter().filter(|(name, _)| name != "truth") {
        let estimator = name.trim_end_matches(" (map)");
        all.push(score_map(
            name,
            false,
            palette::estimator_color(estimator),
            m,
            true_map,
            map_scores,
        ));
    }
    let true_landmarks = lesson.landmarks.iter().find(|(name, _)| name == "truth");
    for item in items {
        match &item.content {
            EstimateContent::Trajectory(t) => all.push(match reference {
                Some(r) => score_trajectory(&item.name, true, item.color, t, &r.trajectory, align),
                None => {
                    let mut s = empty_score(&item.name, true, item.color);
                    s.note =
                        Some("this lesson has no trajectory to compare a path with".to_owned());
                    s
                }
            }),
            EstimateContent::RelativePose(p) => all.push(score_relative_pose(
                &item.name, true, item.color, p, true_pose,
            )),
            EstimateContent::Map(m) => {
                all.push(score_map(
                    &item.name, true, item.color, m, true_map, map_scores,
                ));
            }
            EstimateContent::Landmarks(rows) => {
                let (rmse, note) = match true_landmarks {
                    Some((_, truth)) => {
                        let errors: Vec<f64> = rows
                            .iter()
                            .filter_map(|r| {
                                let t = truth.iter().find(|t| t.id == r.id)?;
                                Some(slamlab_core::math::hypot(r.x - t.x, r.y - t.y))
                            })
                            .collect();
                        if errors.is_empty() {
                            (None, Some("no landmark id matches the lesson's".to_owned()))
                        } else {
                            let n = errors.len() as f64;
                            (
                                Some((errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt()),
                                Some(format!(
                                    "{} of {} landmarks matched by id",
                                    errors.len(),
                                    rows.len()
                                )),
                            )
                        }
                    }
                    None => (None, Some("this lesson has no true landmarks".to_owned())),
                };
                let mut score = empty_score(&item.name, true, item.color);
                score.landmark_rmse = rmse;
                score.note = note;
                all.push(score);
            }
        }
    }
    map_scores.finish();
    all
}

/// The last pose of `t` at or before `now` and the poses up to it.
fn up_to(t: &Trajectory, now: f64) -> usize {
    t.stamps().partition_point(|&s| s <= now + 1e-9)
}

/// The image of a map's overlay: its occupied cells in `color`, its free cells
/// a faint tint of it, unknown cells clear (row 0 at the top: the highest `j`).
fn map_image(grid: &OccupancyGrid, color: Color32) -> egui::ColorImage {
    let (w, h) = (grid.width(), grid.height());
    let [r, g, b, _] = color.to_array();
    let occupied = Color32::from_rgba_unmultiplied(r, g, b, 230);
    let free = Color32::from_rgba_unmultiplied(r, g, b, 28);
    let mut pixels = vec![Color32::TRANSPARENT; w * h];
    for (k, cell) in grid.cells().iter().enumerate() {
        let (i, j) = (k % w, k / w);
        pixels[(h - 1 - j) * w + i] = match cell {
            Cell::Occupied => occupied,
            Cell::Free => free,
            Cell::Unknown => Color32::TRANSPARENT,
        };
    }
    egui::ColorImage::new([w, h], pixels)
}

/// Draws a map over the lesson's as a textured quad (its origin may be turned).
fn draw_map(
    painter: &egui::Painter,
    t: &crate::widgets::map_canvas::MapTransform,
    grid: &OccupancyGrid,
    texture: egui::TextureId,
) {
    let (gw, gh) = grid.size_m();
    let corner = |gx: f64, gy: f64| {
        let (x, y) = grid.grid_frame_to_world(gx, gy);
        t.xy(x, y)
    };
    let corners = [
        (corner(0.0, gh), egui::pos2(0.0, 0.0)),
        (corner(gw, gh), egui::pos2(1.0, 0.0)),
        (corner(gw, 0.0), egui::pos2(1.0, 1.0)),
        (corner(0.0, 0.0), egui::pos2(0.0, 1.0)),
    ];
    if corners
        .iter()
        .any(|(p, _)| !crate::widgets::map_canvas::finite(*p))
    {
        return;
    }
    let mut mesh = egui::Mesh::with_texture(texture);
    for (pos, uv) in corners {
        mesh.vertices.push(egui::epaint::Vertex {
            pos,
            uv,
            color: Color32::WHITE,
        });
    }
    mesh.indices.extend_from_slice(&[0, 1, 2, 0, 2, 3]);
    painter.add(egui::Shape::mesh(mesh));
}

/// Draws the visible estimates on the lesson's map, up to `now`: a
/// trajectory's path, the current pose with its 95 % ellipse and heading wedge
/// when the file gave covariances; landmarks as crosses; a map's occupied
/// cells in its colour (free cells faintly) over the lesson's map.
pub fn map_overlay(ctx: &egui::Context, estimates: &mut Estimates, now: f64) {
    let Some(p) = crate::widgets::map_canvas::placement(ctx) else {
        return;
    };
    let painter = egui::Painter::new(ctx.clone(), p.layer, p.rect);
    let t = &p.transform;
    let version = estimates.version;
    estimates
        .textures
        .0
        .retain(|(name, v, _)| *v == version && estimates.items.iter().any(|e| &e.name == name));
    for e in estimates.items.iter().filter(|e| e.visible) {
        match &e.content {
            EstimateContent::Map(grid) => {
                let texture = match estimates.textures.0.iter().find(|(n, _, _)| n == &e.name) {
                    Some((_, _, handle)) => handle.id(),
                    None => {
                        let handle = ctx.load_texture(
                            format!("estimate-map-{}", e.name),
                            map_image(grid, e.color),
                            egui::TextureOptions::NEAREST,
                        );
                        let id = handle.id();
                        estimates.textures.0.push((e.name.clone(), version, handle));
                        id
                    }
                };
                draw_map(&painter, t, grid, texture);
            }
            EstimateContent::Trajectory(traj) => {
                let n = up_to(traj, now);
                if n == 0 {
                    continue;
                }
                // At most a few thousand segments on screen.
                let step = (n / 4000).max(1);
                let points: Vec<Pos2> = traj.poses()[..n]
                    .iter()
                    .step_by(step)
                    .chain(std::iter::once(&traj.poses()[n - 1]))
                    .map(|q| t.pose(q))
                    .filter(|q| crate::widgets::map_canvas::finite(*q))
                    .collect();
                painter.add(egui::Shape::line(points, Stroke::new(2.0, e.color)));
                let pose: Pose2 = traj.poses()[n - 1];
                let covariance = traj
                    .covariances()
                    .map_or_else(nalgebra::Matrix3::zeros, |c| c[n - 1]);
                crate::widgets::map_canvas::draw_estimate(
                    &painter,
                    t,
                    &pose,
                    &covariance,
                    crate::widgets::map_canvas::EstimateStyle {
                        color: e.color,
                        ellipse: traj.covariances().is_some(),
                        wedge_radius: 14.0,
                        dot: true,
                    },
                );
            }
            EstimateContent::RelativePose(_) => {}
            EstimateContent::Landmarks(rows) => {
                for r in rows {
                    let c = t.xy(r.x, r.y);
                    if !crate::widgets::map_canvas::finite(c) {
                        continue;
                    }
                    let d = 5.0;
                    let stroke = Stroke::new(2.0, e.color);
                    painter.line_segment([c + egui::vec2(-d, -d), c + egui::vec2(d, d)], stroke);
                    painter.line_segment([c + egui::vec2(-d, d), c + egui::vec2(d, -d)], stroke);
                }
            }
        }
    }
}

/// A window of a student's own results in the bottom right corner of the
/// screen, beside the map rather than over all of it: 42 % of the screen's
/// width, kept between 300 and 470 points (and on screen), and `height` points
/// high. Shared by "Your estimates" and the pose-graph lesson's "Your
/// solutions"; the notices box keeps clear of it ([`corner_windows`]).
pub fn show_corner_window<R>(
    ctx: &egui::Context,
    title: &str,
    open: &mut bool,
    height: f32,
    add_contents: impl FnOnce(&mut egui::Ui) -> R,
) -> Option<R> {
    let screen = ctx.content_rect();
    let size = egui::vec2(
        (0.42 * screen.width())
            .clamp(300.0, 470.0)
            .min(screen.width() - 16.0),
        height.min(screen.height() - 40.0),
    );
    let shown = egui::Window::new(title)
        .open(open)
        .default_size(size)
        .max_width(size.x)
        .default_pos(screen.right_bottom() - size - egui::vec2(8.0, 8.0))
        .constrain(true)
        .show(ctx, add_contents)?;
    let pass = ctx.cumulative_pass_nr();
    let rect = shown.response.rect;
    ctx.data_mut(|d| {
        let rects: &mut Vec<(u64, egui::Rect)> = d.get_temp_mut_or_default(corner_windows_id());
        rects.retain(|(p, _)| *p + 1 >= pass);
        rects.push((pass, rect));
    });
    shown.inner
}

fn corner_windows_id() -> egui::Id {
    egui::Id::unique("slamlab_corner_windows")
}

/// The corner windows shown in this pass or the one before
/// ([`show_corner_window`]): what the notices box keeps clear of.
pub fn corner_windows(ctx: &egui::Context) -> Vec<egui::Rect> {
    let pass = ctx.cumulative_pass_nr();
    ctx.data(|d| {
        d.get_temp::<Vec<(u64, egui::Rect)>>(corner_windows_id())
            .unwrap_or_default()
            .into_iter()
            .filter(|(p, _)| *p + 1 >= pass)
            .map(|(_, r)| r)
            .collect()
    })
}

/// The longest name a score table shows whole; a longer one is cut, whole
/// in its tooltip.
const NAME_CHARS: usize = 18;

/// One table of the "Your estimates" window: the scores of one kind (paths,
/// maps, landmarks, relative poses) under their own headings, each row a
/// colour, for a student's estimate a switch to draw it and a button to
/// remove it, a name (its note in the tooltip) and the numbers.
struct ScoreTable<'a> {
    id: &'static str,
    /// The headings of the numbers, each with its tooltip.
    columns: &'a [(&'a str, &'a str)],
    /// The rows: a score and its numbers, as shown.
    rows: Vec<(&'a EstimateScore, Vec<String>)>,
}

impl ScoreTable<'_> {
    /// Draws the table; a student's estimate drawn or removed is noted in
    /// `toggled` or `remove` (its index among `items`).
    fn ui(
        self,
        ui: &mut egui::Ui,
        items: &[Estimate],
        toggled: &mut Option<(usize, bool)>,
        remove: &mut Option<usize>,
    ) {
        if self.rows.is_empty() {
            return;
        }
        egui::Grid::new(self.id).striped(true).show(ui, |ui| {
            ui.label("");
            ui.strong("estimator");
            for (heading, hover) in self.columns {
                ui.strong(*heading).on_hover_text(*hover);
            }
            ui.end_row();
            for (s, numbers) in self.rows {
                let (rect, _) =
                    ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::hover());
                ui.painter().rect_filled(rect, 2.0, s.color);
                let shown = short_name(&s.name);
                let hover = match &s.note {
                    Some(note) => format!("{}: {note}", s.name),
                    None => s.name.clone(),
                };
                // A student's estimate: its switch and its remove button before
                // its name, in reach however narrow the window.
                ui.horizontal(|ui| {
                    if let Some(k) = items.iter().position(|e| s.dropped && e.name == s.name) {
                        let mut drawn = items[k].visible;
                        if ui
                            .checkbox(&mut drawn, "")
                            .on_hover_text("Draw this estimate on the lesson's map")
                            .changed()
                        {
                            *toggled = Some((k, drawn));
                        }
                        if ui
                            .small_button("×")
                            .on_hover_text("Remove this estimate")
                            .clicked()
                        {
                            *remove = Some(k);
                        }
                    }
                    ui.label(shown).on_hover_text(hover);
                });
                for n in numbers {
                    ui.label(n);
                }
                ui.end_row();
            }
        });
    }
}

/// `name` as a narrow table shows it: cut to [`NAME_CHARS`] characters with
/// an ellipsis (the whole name goes in its tooltip).
pub fn short_name(name: &str) -> String {
    if name.chars().count() > NAME_CHARS {
        let cut: String = name.chars().take(NAME_CHARS - 1).collect();
        format!("{cut}…")
    } else {
        name.to_owned()
    }
}

/// A number with `digits` decimals, or a dash for none (the score tables).
pub fn number(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".to_owned(), |v| format!("{v:.digits$}"))
}

/// The "Your estimates" window: each estimator's score (the lesson's and the
/// student's) in a table of its kind, a plot of the position error over time,
/// the alignment switch, and for each dropped estimate a switch to draw it and
/// a button to remove it.
pub fn window_ui(ctx: &egui::Context, estimates: &mut Estimates, has_truth: bool) {
    let mut open = estimates.open;
    // At most half the window's height.
    let height = (0.5 * ctx.content_rect().height()).clamp(180.0, 380.0);
    let mut remove = None;
    let mut toggled = None;
    show_corner_window(ctx, "Your estimates", &mut open, height, |ui| {
        ui.label(format!(
            "Scored against {} up to the time bar's time, as `slamlab evaluate` and evo score them.",
            if has_truth { "the truth" } else { "the lesson's first estimator (no truth here)" }
        ));
        ui.checkbox(
            &mut estimates.align,
            "Align each to the reference first (SE(2), evo's --align)",
        );
        let scores = &estimates.scores;
        let is_map = |s: &EstimateScore| s.map_agreement.is_some() || s.map_coverage.is_some();
        let is_pose =
            |s: &EstimateScore| s.rotation_error_deg.is_some() || s.direction_error_deg.is_some();
        let is_path = |s: &EstimateScore| !is_map(s) && !is_pose(s) && s.landmark_rmse.is_none();
        // ANEES only where some path has covariances.
        let anees = scores.iter().any(|s| is_path(s) && s.anees.is_some());
        let path_columns: &[(&str, &str)] = &[
            ("ATE m", "The RMSE of the absolute position error"),
            ("max m", "The largest position error"),
            (
                "RPE m",
                "The RMSE of the relative translation error over one pose",
            ),
            (
                "ANEES",
                "The average normalized estimation error squared (covariances only): about 3 when they are right",
            ),
        ];
        let tables = [
            ScoreTable {
                id: "estimate_scores",
                columns: &path_columns[..if anees { 4 } else { 3 }],
                rows: scores
                    .iter()
                    .filter(|s| is_path(s))
                    .map(|s| {
                        let mut n = vec![
                            number(s.ate_rmse, 3),
                            number(s.ate_max, 3),
                            number(s.rpe_rmse, 4),
                        ];
                        if anees {
                            n.push(number(s.anees, 2));
                        }
                        (s, n)
                    })
                    .collect(),
            },
            ScoreTable {
                id: "estimate_map_scores",
                columns: &[
                    (
                        "agree",
                        "The share of the true map's free and occupied cells this map classifies the same, over the cells it knows (the mapping lesson's map agreement, as a ROS map: occupied above 0.65, free below 0.196)",
                    ),
                    (
                        "cover",
                        "The share of the true map's free and occupied cells this map knows at all (as the grid-mapping assignment grades it)",
                    ),
                ],
                rows: scores
                    .iter()
                    .filter(|s| is_map(s))
                    .map(|s| {
                        (
                            s,
                            vec![number(s.map_agreement, 3), number(s.map_coverage, 3)],
                        )
                    })
                    .collect(),
            },
            ScoreTable {
                id: "estimate_landmark_scores",
                columns: &[(
                    "landmarks m",
                    "The RMS distance to the true landmarks of the same id",
                )],
                rows: scores
                    .iter()
                    .filter(|s| s.landmark_rmse.is_some())
                    .map(|s| (s, vec![number(s.landmark_rmse, 3)]))
                    .collect(),
            },
            ScoreTable {
                id: "estimate_pose_scores",
                columns: &[
                    ("R °", "The rotation error: the angle of R_true^T R"),
                    (
                        "t °",
                        "The angle between the estimated and the true direction of translation (a monocular t has no length)",
                    ),
                ],
                rows: scores
                    .iter()
                    .filter(|s| is_pose(s))
                    .map(|s| {
                        (
                            s,
                            vec![
                                number(s.rotation_error_deg, 3),
                                number(s.direction_error_deg, 2),
                            ],
                        )
                    })
                    .collect(),
            },
        ];
        // What does not fit the corner scrolls sideways.
        egui::ScrollArea::horizontal().show(ui, |ui| {
            for table in tables {
                table.ui(ui, &estimates.items, &mut toggled, &mut remove);
            }
        });
        if estimates.items.is_empty() {
            ui.weak("Drop a trajectory (TUM t x y z qx qy qz qw, or CSV t,x,y,theta[,covariance]), a landmark CSV (id,x,y), in the two-view lesson a relative pose (.txt: R row by row then t, or tx ty tz qx qy qz qw), or in the mapping lesson a ROS map (its YAML with its image) on the page, or use File → Open your estimate. File → Export trajectories gives the lesson's own in these formats.");
        }
        let series: Vec<(String, Color32, Vec<[f64; 2]>)> = scores
            .iter()
            .filter(|s| !s.errors.is_empty())
            .map(|s| (s.name.clone(), s.color, s.errors.clone()))
            .collect();
        if !series.is_empty() {
            ui.label("Position error (m) over time (s)");
            egui_plot::Plot::new("estimate_errors")
                .height((ui.available_height() - 8.0).clamp(70.0, 160.0))
                .allow_scroll(false)
                .show(ui, |plot| {
                    for (name, color, points) in series {
                        plot.line(
                            egui_plot::Line::new(name, egui_plot::PlotPoints::from(points))
                                .color(color)
                                .width(1.5),
                        );
                    }
                });
        }
    });
    if let Some((k, shown)) = toggled {
        estimates.set_visible(k, shown);
    }
    if let Some(k) = remove {
        estimates.remove(k);
    }
    estimates.open = open;
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_sim::io::trajectory::write_tum;

    fn line(n: usize, dy: f64) -> Trajectory {
        Trajectory::new(
            (0..n).map(|k| k as f64 * 0.1).collect(),
            (0..n)
                .map(|k| Pose2::new(k as f64 * 0.1, dy, 0.0))
                .collect(),
        )
    }

    #[test]
    fn a_dropped_trajectory_is_scored_beside_the_lessons() {
        let mut estimates = Estimates::default();
        let text = write_tum(&line(50, 0.2));
        assert!(is_estimate_file("mine.txt", text.as_bytes()));
        assert!(!is_estimate_file("map.yaml", b"image: map.pgm"));
        let said = estimates.add("mine.txt", text.as_bytes()).unwrap();
        assert_eq!(said, "Your estimate mine.txt: 50 poses");
        let lesson = LessonOutput {
            trajectories: vec![
                NamedTrajectory::new("truth", TrajectoryRole::Truth, line(30, 0.0)),
                NamedTrajectory::new("ekf", TrajectoryRole::Estimate, line(30, 0.05)),
            ],
            ..LessonOutput::default()
        };
        assert!(estimates.is_stale(30));
        let scores = estimates.score(30, &lesson).to_vec();
        assert!(!estimates.is_stale(30));
        assert_eq!(scores.len(), 2);
        assert_eq!(scores[0].name, "ekf");
        assert!((scores[0].ate_rmse.unwrap() - 0.05).abs() < 1e-12);
        // The student's is scored over the 30 poses the run has so far.
        assert_eq!(scores[1].pairs, 30);
        assert!((scores[1].ate_rmse.unwrap() - 0.2).abs() < 1e-12);
        // Refusals say why and keep what is there.
        let refused = estimates.add("bad.csv", b"0,1,2,0\n0,1,2,0\n").unwrap_err();
        assert!(refused.starts_with("bad.csv: line 2"), "{refused}");
        assert_eq!(estimates.items().len(), 1);
        estimates.remove(0);
        assert!(estimates.is_empty());
    }

    /// A relative pose dropped in the two-view lesson is scored as the lesson's
    /// own RANSAC estimate is: the true pose written and dropped back has no
    /// error; one turned by 2° about the camera's axis has a rotation error of 2°.
    #[test]
    fn a_dropped_relative_pose_is_scored_against_the_true_one() {
        use nalgebra::{Rotation3, Vector3};
        use slamlab_sim::io::relative_pose::write_relative_pose;
        let truth = RelativePose {
            rotation: Rotation3::from_euler_angles(0.0, 0.05, 0.0).into_inner(),
            translation: Vector3::new(0.1, 0.0, 1.0),
        };
        let turned = RelativePose {
            rotation: Rotation3::from_euler_angles(0.0, 0.0, 2.0_f64.to_radians()).into_inner()
                * truth.rotation,
            translation: truth.translation,
        };
        let mut estimates = Estimates::default();
        for (name, pose) in [("same.txt", &truth), ("turned.txt", &turned)] {
            let text = write_relative_pose(pose);
            assert!(is_estimate_file(name, text.as_bytes()));
            let said = estimates.add(name, text.as_bytes()).unwrap();
            assert_eq!(
                said,
                format!("Your estimate {name}: a relative pose of two views")
            );
        }
        let lesson = LessonOutput {
            relative_poses: vec![("truth".to_owned(), truth), ("ransac".to_owned(), turned)],
            ..LessonOutput::default()
        };
        let scores = estimates.score(1, &lesson).to_vec();
        let names: Vec<&str> = scores.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["ransac", "same.txt", "turned.txt"]);
        assert!(scores[1].rotation_error_deg.unwrap() < 1e-6);
        assert!(scores[1].direction_error_deg.unwrap() < 1e-6);
        for s in [&scores[0], &scores[2]] {
            assert!((s.rotation_error_deg.unwrap() - 2.0).abs() < 1e-9, "{s:?}");
        }
        // Without a true pose (another lesson), the score says why it is empty.
        let other = estimates.score(2, &LessonOutput::default()).to_vec();
        assert!(other[0].rotation_error_deg.is_none());
        assert!(
            other[0]
                .note
                .as_deref()
                .unwrap()
                .contains("no pair of views")
        );
    }

    /// A map is compared with the true map once while it stays the same map
    /// (the same `Arc`), however often the run is scored; another map is
    /// compared anew, and each time gives the same numbers.
    #[test]
    fn a_map_is_compared_once_until_it_changes() {
        let grid = |occupied: usize| {
            let cells = (0..100)
                .map(|k| {
                    if k < occupied {
                        Cell::Occupied
                    } else {
                        Cell::Free
                    }
                })
                .collect();
            Arc::new(OccupancyGrid::new(10, 10, 0.1, Pose2::new(0.0, 0.0, 0.0), cells).unwrap())
        };
        let truth = grid(10);
        let built = grid(20);
        let output = |built: &Arc<OccupancyGrid>| LessonOutput {
            maps: vec![
                ("truth".to_owned(), truth.clone()),
                ("scan-to-map (map)".to_owned(), built.clone()),
            ],
            ..LessonOutput::default()
        };
        let mut estimates = Estimates::default();
        let first = estimates.score(1, &output(&built)).to_vec();
        assert_eq!(first[0].map_agreement, Some(0.9));
        assert_eq!(first[0].map_coverage, Some(1.0));
        for tick in 2..10 {
            assert_eq!(estimates.score(tick, &output(&built)), first.as_slice());
        }
        assert_eq!(estimates.map_scores.compared, 1);
        let grown = grid(10);
        let again = estimates.score(10, &output(&grown)).to_vec();
        assert_eq!(again[0].map_agreement, Some(1.0));
        assert_eq!(estimates.map_scores.compared, 2);
    }
}
