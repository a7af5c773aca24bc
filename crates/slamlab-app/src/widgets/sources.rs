//! The Sources window: every document the lessons cite, with its title, author,
//! institution or publisher, year, what SLAM Lab takes from it and the sections the
//! panels refer to. Students do not have the documents at hand, so a panel names
//! the document and section ("Eq. 3.17-3.19 of Xiang's thesis") and a
//! [`source_link`] opens this window on that entry.
//!
//! The window's state (open or not, which entry is highlighted) lives in egui's
//! memory under a fixed id, so any panel can open it without reaching the app.

/// One document the lessons cite.
#[derive(Clone, Copy, Debug)]
pub struct Source {
    /// The key a [`source_link`] names it by.
    pub key: &'static str,
    /// The name the panels use for it ("Xiang's thesis").
    pub short: &'static str,
    /// The full title.
    pub title: &'static str,
    /// Who wrote it.
    pub author: &'static str,
    /// The university, publisher or project.
    pub publisher: &'static str,
    /// When it appeared (as far as the document says).
    pub year: &'static str,
    /// What SLAM Lab takes from it.
    pub covers: &'static str,
    /// The sections the panels cite, each with one line on what it is.
    pub sections: &'static [(&'static str, &'static str)],
}

/// Every document the lessons cite, the course texts first.
pub const SOURCES: &[Source] = &[
    Source {
        key: "xiang",
        short: "Xiang's thesis",
        title: "SLAM for Ground Robots: Theories and Applications",
        author: "Linjian Xiang",
        publisher: "MSc thesis, Department of Electrical and Computer Engineering, University of Alberta",
        year: "not printed on the copy (its newest reference is from 2020)",
        covers: "Bayes, Kalman and particle filters, the two-wheel robot's motion model, \
                 EKF-SLAM and UKF-SLAM with their simulation experiments, the beam model of a \
                 range finder, pose-graph SLAM, and the kidnapped robot: AMCL and the costmap \
                 variants CMCL and ACMCL.",
        sections: &[
            (
                "§2.3.1, Algorithms 6 and 7",
                "resampling: the naive (multinomial) sampler and the low-variance sampler. \
                 Algorithm 6's search loop is printed inverted; SLAM Lab takes the first i \
                 whose cumulative weight reaches the draw.",
            ),
            (
                "§2.5, Eq. 2.65-2.70",
                "the two-wheel robot: wheel speeds to (v, w) (Eq. 2.65-2.66) and the exact arc \
                 motion (Eq. 2.70; the first matrix's middle row should read sin, cos, 0).",
            ),
            (
                "§3.2, Eq. 3.5-3.20",
                "EKF-SLAM: start with a known pose (Eq. 3.5), add a landmark through the \
                 inverse observation model (Eq. 3.8-3.16), predict (Eq. 3.17-3.19), update \
                 (Eq. 3.18-3.20).",
            ),
            (
                "§3.3, Eq. 3.21-3.32",
                "UKF-SLAM: new landmark (Eq. 3.21-3.25), predict (Eq. 3.26-3.30), update \
                 (Eq. 3.31-3.32). Slips corrected in SLAM Lab: Eq. 3.28 adds the control \
                 noise twice (it is added once); the gain is K = P_My P_yy^-1; Eq. 3.32 \
                 prints P = P̄ + K P_yy K^T, the correct update subtracts.",
            ),
            (
                "§3.4, Eq. 3.34-3.39, Experiments 1 and 2",
                "the simulation: the motion Jacobians (Eq. 3.34-3.35), the measurement \
                 Jacobian H (Eq. 3.37-3.39; Eq. 3.38-3.39 print (L_x y − y_t) where \
                 (L_y − y_t) is meant), and the two experiments: a circle at v = 1 m/s, \
                 w = π/10 rad/s for 200 iterations, the second with doubled control noise. \
                 The thesis gives no time step; SLAM Lab uses 0.1 s.",
            ),
            (
                "§3.5.1, Algorithm 8",
                "the beam model of a range finder: a particle's weight is the likelihood of \
                 the scan seen from its pose.",
            ),
            (
                "§4.1-4.2, Eq. 4.2 and 4.8",
                "pose-graph SLAM: the cost F(x) = Σ e^T Ω e (Eq. 4.2 prints Ω^-1; Ω is the \
                 information matrix), the sparse Jacobian (Eq. 4.8) and the simulated graph.",
            ),
            (
                "§5.1, Algorithms 9-11, Fig. 5.1, Tables 5.1-5.2",
                "the kidnapped robot: Augmented MCL (Algorithm 9), costmap MCL (Algorithm 10) \
                 and ACMCL (Algorithm 11, whose w_slow and w_fast SLAM Lab updates once per \
                 step, after the particle loop, not inside it as printed), the costmap \
                 (Fig. 5.1) and the recovery results on the Maze and Willow maps.",
            ),
        ],
    },
    Source {
        key: "waslander",
        short: "Waslander's slides",
        title: "ME 597 Autonomous Mobile Robotics, Section 8: Mapping II",
        author: "Prof. Steven Waslander",
        publisher: "lecture slides, University of Waterloo",
        year: "not printed on the slides (their code examples are dated 2014)",
        covers: "EKF-SLAM in slide form (the Euler motion model, measurements ordered \
                 [bearing, range]), FastSLAM 1.0 and 2.0, occupancy-grid FastSLAM with \
                 adaptive resampling, ICP scan matching and pose graphs.",
        sections: &[
            (
                "\"EKF SLAM\" slides",
                "the Euler motion model: x + v cos θ dt, y + v sin θ dt, θ + w dt.",
            ),
            (
                "\"FastSLAM\" slides",
                "Rao-Blackwellized particles with one small EKF per landmark; FastSLAM 2.0's \
                 proposal sharpened by the measurement.",
            ),
            (
                "\"Occupancy Grid SLAM: Resampling\" slide",
                "resample only when N_eff = 1 / Σ w_i² falls below a threshold (half the \
                 particle count on the slide).",
            ),
        ],
    },
    Source {
        key: "wu",
        short: "Wu's thesis",
        title: "A Low-cost SLAM Fusion Algorithm for Robot Localization",
        author: "Ruifan Wu",
        publisher: "MSc thesis, Department of Mechanical Engineering, University of Alberta",
        year: "not printed on the copy (its newest reference is from 2017)",
        covers: "An EKF (ROS robot_localization) fusing a 1 Hz SLAM pose from RTAB-Map with \
                 wheel odometry and an IMU on a Jackal robot, against Vicon ground truth; the \
                 graph optimizers TORO, g2o and GTSAM.",
        sections: &[
            (
                "§3.5",
                "the robot_localization package and its _relative and _differential settings \
                 for a pose input.",
            ),
            (
                "§4.4.1-4.4.3",
                "the graph optimizers: TORO (gradient descent), g2o (Levenberg-Marquardt) \
                 and GTSAM (factor graphs).",
            ),
            (
                "§5.3, Table 5.3",
                "the RMSE of the fused pose against Vicon for _differential and _relative \
                 over six trials.",
            ),
        ],
    },
    Source {
        key: "thrun",
        short: "Probabilistic Robotics",
        title: "Probabilistic Robotics",
        author: "Sebastian Thrun, Wolfram Burgard and Dieter Fox",
        publisher: "MIT Press",
        year: "2005",
        covers: "The textbook both theses build on: the filters, the motion and sensor \
                 models, Monte Carlo localization and the SLAM algorithms.",
        sections: &[
            ("Table 4.4", "the low-variance sampler."),
            (
                "Table 5.6",
                "sample_motion_model_odometry: move a particle by an odometry increment \
                 (rotate, translate, rotate) with noise.",
            ),
        ],
    },
    Source {
        key: "ros",
        short: "ROS amcl and robot_localization",
        title: "The ROS packages amcl and robot_localization",
        author: "amcl: Brian P. Gerkey; robot_localization: Tom Moore",
        publisher: "Robot Operating System (ROS) packages; robot_localization is described by \
                    T. Moore and D. Stouch at IAS-13",
        year: "robot_localization paper 2014",
        covers: "amcl: the Monte Carlo localization lesson's defaults (likelihood-field model, \
                 odometry noise alpha1..4, the estimate as the mean of the heaviest particle \
                 cluster). robot_localization: the fusion lesson's EKF, its omnidirectional \
                 motion model and its _relative and _differential pose inputs.",
        sections: &[],
    },
    Source {
        key: "grisetti",
        short: "Grisetti et al. 2007 (gmapping)",
        title: "Improved Techniques for Grid Mapping With Rao-Blackwellized Particle Filters",
        author: "Giorgio Grisetti, Cyrill Stachniss and Wolfram Burgard",
        publisher: "IEEE Transactions on Robotics 23(1); the gmapping package implements it",
        year: "2007",
        covers: "Grid FastSLAM in the mapping lesson: a map per particle, the improved proposal \
                 (scan matching, then a Gaussian fitted to the likelihood times the motion \
                 prior around the match), weights by its normalizer, and resampling only when \
                 N_eff falls. The parameters keep gmapping's names (srr, srt, str, stt, lstep, \
                 astep, lsigma, ogain, linearUpdate, angularUpdate, delta).",
        sections: &[
            (
                "Eq. 14-16, 19",
                "the improved proposal: K poses x_j around the scan match, τ_j = p(z | x_j, m) · \
                 p(x_j | x_t−1, u), η = Σ τ_j, the Gaussian's mean and covariance from the τ_j, \
                 and the weight update w_t = w_t−1 · η.",
            ),
            (
                "Eq. 20",
                "adaptive resampling: N_eff = 1 / Σ w_i², resample when it drops below half \
                 the particle count.",
            ),
        ],
    },
    Source {
        key: "graph-optimizers",
        short: "g2o, TORO and GTSAM",
        title: "Graph optimizers and their file formats",
        author: "g2o: R. Kümmerle, G. Grisetti, H. Strasdat, K. Konolige, W. Burgard; \
                 TORO: G. Grisetti, S. Grzonka, C. Stachniss, P. Pfaff, W. Burgard; \
                 GTSAM: F. Dellaert",
        publisher: "g2o: ICRA 2011; TORO: IROS 2007; GTSAM: Georgia Institute of Technology",
        year: "2007-2012",
        covers: "The pose-graph lesson's solvers follow them (Levenberg-Marquardt as in g2o, a \
                 TORO-like first-order method) and it opens their .g2o and TORO graph files. \
                 Wu's thesis §4.4 describes all three.",
        sections: &[],
    },
    Source {
        key: "datasets",
        short: "Intel and M3500 datasets",
        title: "Pose-graph benchmark datasets: Intel Research Lab and Manhattan M3500",
        author: "Intel: recorded by Dirk Hähnel; M3500: E. Olson, J. Leonard and S. Teller",
        publisher: "Intel Research Seattle; M3500 from \"Fast iterative alignment of pose \
                    graphs with poor initial estimates\", ICRA",
        year: "M3500: 2006",
        covers: "Standard graphs to drop on the pose-graph lesson as .g2o or TORO files.",
        sections: &[],
    },
    Source {
        key: "mrclam",
        short: "UTIAS MRCLAM data set",
        title: "The UTIAS multi-robot cooperative localization and mapping dataset",
        author: "K. Y. K. Leung, Y. Halpern, T. D. Barfoot and H. H. T. Liu",
        publisher: "University of Toronto Institute for Aerospace Studies; International \
                    Journal of Robotics Research 30(8):969-974",
        year: "2011",
        covers: "A real world for the landmark lesson: five robots' odometry and camera \
                 sightings of fifteen barcoded landmarks, with Vicon ground truth for \
                 everything, so a filter's error and NEES are measured against the truth.",
        sections: &[],
    },
    Source {
        key: "freiburg-data",
        short: "Freiburg course data",
        title: "Robot Mapping: EKF-SLAM exercise data (world.dat, sensor_data.dat)",
        author: "C. Stachniss",
        publisher: "Robot Mapping course, University of Freiburg",
        year: "WS 2013/14",
        covers: "The input of the course's EKF-SLAM, UKF-SLAM and FastSLAM exercises: \
                 odometry as rot1-trans-rot2, range-bearing sightings with known ids, and the \
                 nine true landmarks (no true path).",
        sections: &[],
    },
    Source {
        key: "victoria-park",
        short: "Victoria Park data set",
        title: "Optimization of the simultaneous localization and map-building algorithm for \
                real-time implementation",
        author: "J. Guivant and E. Nebot",
        publisher: "Australian Centre for Field Robotics; IEEE Transactions on Robotics and \
                    Automation 17(3):242-257",
        year: "2001",
        covers: "A car among the trees of a Sydney park: encoder speed and steering (the ACFR \
                 car model), tree detections without identity, and GPS as the only \
                 independent reference.",
        sections: &[],
    },
];

/// The entry named `key`.
pub fn find(key: &str) -> Option<&'static Source> {
    SOURCES.iter().find(|s| s.key == key)
}

/// The window's state in egui's memory.
#[derive(Clone, Copy, Debug, Default)]
struct WindowState {
    open: bool,
    /// The entry to highlight (an index into [`SOURCES`]).
    highlight: Option<usize>,
    /// Scroll the highlighted entry into view on the next frame.
    scroll: bool,
}

fn state_id() -> egui::Id {
    egui::Id::unique("slamlab_sources_window")
}

fn state(ctx: &egui::Context) -> WindowState {
    ctx.data(|d| d.get_temp(state_id())).unwrap_or_default()
}

/// The window's title.
pub const TITLE: &str = "Sources";

/// Opens the Sources window, on entry `key` when given.
pub fn open_sources(ctx: &egui::Context, key: Option<&str>) {
    let highlight = key.and_then(|k| SOURCES.iter().position(|s| s.key == k));
    ctx.data_mut(|d| {
        d.insert_temp(
            state_id(),
            WindowState {
                open: true,
                highlight,
                scroll: true,
            },
        );
    });
}

/// Is the Sources window open?
pub fn is_open(ctx: &egui::Context) -> bool {
    state(ctx).open
}

/// The key of the highlighted entry, if any.
pub fn highlighted(ctx: &egui::Context) -> Option<&'static str> {
    state(ctx)
        .highlight
        .and_then(|i| SOURCES.get(i))
        .map(|s| s.key)
}

fn window_id() -> egui::Id {
    egui::Id::unique("slamlab_sources_window_area")
}

/// Where the Sources window was drawn last (none before it first opens).
pub fn window_rect(ctx: &egui::Context) -> Option<egui::Rect> {
    ctx.memory(|m| m.area_rect(window_id()))
}

/// A link-styled label that opens the Sources window on entry `key`.
pub fn source_link(
    ui: &mut egui::Ui,
    key: &str,
    text: impl Into<egui::WidgetText>,
) -> egui::Response {
    let response = ui.link(text);
    let response = match find(key) {
        Some(s) => response.on_hover_text(format!(
            "{}: \"{}\", {}. Click for the Sources panel.",
            s.short, s.title, s.author
        )),
        None => response,
    };
    if response.clicked() {
        open_sources(ui.ctx(), Some(key));
    }
    response
}

/// Draws the Sources window when it is open. Call once per frame.
pub fn sources_window(ctx: &egui::Context) {
    let mut st = state(ctx);
    if !st.open {
        return;
    }
    let screen = ctx.content_rect();
    let width = (screen.width() - 40.0).clamp(240.0, 620.0);
    let height = (screen.height() - 80.0).max(160.0);
    let mut open = true;
    let mut scroll = st.scroll;
    egui::Window::new(TITLE)
        .id(window_id())
        .open(&mut open)
        .constrain(true)
        .collapsible(false)
        .default_pos(screen.center_top() + egui::vec2(-width / 2.0, 40.0))
        .default_width(width)
        .default_height(height.min(620.0))
        .max_width(width)
        .max_height(height)
        .vscroll(true)
        .show(ctx, |ui| {
            ui.label(
                "What the lessons cite. A panel names the document and the section \
                 (\"Eq. 3.17-3.19 of Xiang's thesis\"); here is what each document is.",
            );
            for (i, source) in SOURCES.iter().enumerate() {
                ui.add_space(6.0);
                let highlighted = st.highlight == Some(i);
                let response = entry_ui(ui, source, highlighted);
                if highlighted && scroll {
                    response.scroll_to_me(Some(egui::Align::TOP));
                    scroll = false;
                }
            }
        });
    st.open = open;
    st.scroll = scroll;
    ctx.data_mut(|d| d.insert_temp(state_id(), st));
}

fn entry_ui(ui: &mut egui::Ui, source: &Source, highlighted: bool) -> egui::Response {
    let visuals = ui.visuals();
    let (fill, stroke) = if highlighted {
        (
            visuals.selection.bg_fill.gamma_multiply(0.25),
            egui::Stroke::new(2.0, visuals.selection.stroke.color),
        )
    } else {
        (
            egui::Color32::TRANSPARENT,
            visuals.widgets.noninteractive.bg_stroke,
        )
    };
    egui::Frame::group(ui.style())
        .fill(fill)
        .stroke(stroke)
        .show(ui, |ui| {
            ui.set_width(ui.available_width());
            ui.label(egui::RichText::new(source.short).heading());
            ui.label(egui::RichText::new(source.title).strong().italics());
            ui.label(format!("By {}", source.author));
            ui.label(source.publisher);
            ui.label(format!("Year: {}", source.year));
            ui.label(format!("What SLAM Lab takes from it: {}", source.covers));
            if !source.sections.is_empty() {
                ui.label(egui::RichText::new("Cited in the lessons").strong());
                for (section, what) in source.sections {
                    ui.horizontal_wrapped(|ui| {
                        ui.label(egui::RichText::new(*section).strong());
                        ui.label(*what);
                    });
                }
            }
        })
        .response
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_unique_and_found() {
        for (i, a) in SOURCES.iter().enumerate() {
            assert!(find(a.key).is_some());
            for b in &SOURCES[i + 1..] {
                assert_ne!(a.key, b.key);
                assert_ne!(a.short, b.short);
            }
        }
        assert!(find("nothing").is_none());
    }
}
