//! The page's query string: `?lesson=landmark-slam&seed=7&embed=1&landmarks=30`.
//!
//! The app reads `lesson`, `embed`, `many-runs`, the figure keys (`tick`, `run`,
//! `legend`, `panels`, `zoom`, `follow`: how a lecture figure opens), a student's
//! `estimate=` files and homework (`assignment=`, `student=`) itself; every
//! other pair belongs to the lesson,
//! whose parameters use the same names as the command line. Nothing here panics:
//! malformed text becomes a notice and the default is used.

/// The query string split into the app's own keys and the lesson's pairs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Query {
    /// The `lesson=` value, if given.
    pub lesson: Option<String>,
    /// `embed=1` (or `true`, `yes`, empty): the compact layout for lecture pages.
    pub embed: bool,
    /// `many-runs=50`: open the "Many runs" window and start that many runs.
    pub many_runs: Option<usize>,
    /// How the figure opens: `tick=`, `run=`, `legend=`, `panels=`, `zoom=`, `follow=`.
    pub figure: FigureOptions,
    /// Every other `key=value` pair, decoded, in order.
    pub pairs: Vec<(String, String)>,
    /// Problems with the app's own keys (`embed=maybe`), worded for the user.
    pub issues: Vec<String>,
}

/// The most estimates a lesson holds at once (`estimate=` keys and files dropped).
pub const MAX_ESTIMATES: usize = 8;

/// The keys the app reads itself; lessons never see them.
pub const APP_KEYS: [&str; 13] = [
    "lesson",
    "estimate",
    "assignment",
    "student",
    "embed",
    "many-runs",
    "tick",
    "run",
    "speed",
    "legend",
    "panels",
    "zoom",
    "follow",
];

/// The most ticks `tick=` runs before the first frame (more would keep the page
/// blank for seconds).
pub const TICK_LIMIT: u64 = 2000;

/// The range of `zoom=`, a factor on the fitted view.
pub const ZOOM_RANGE: std::ops::RangeInclusive<f32> = 0.1..=20.0;

/// The panel names of `panels=`.
pub const PANEL_NAMES: [&str; 3] = ["parameters", "explanation", "plots"];

/// How a figure opens, from the URL; `None` leaves the lesson's own default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FigureOptions {
    /// `tick=N`: run N whole ticks before the first frame (at most [`TICK_LIMIT`]).
    pub tick: Option<u64>,
    /// `run=1`: start running.
    pub run: bool,
    /// `legend=0|1`: the map's legend.
    pub legend: Option<bool>,
    /// `panels=parameters,explanation,plots`: exactly these panels open.
    pub panels: Option<crate::panels::PanelVisibility>,
    /// `zoom=2`: the map this many times closer than the fitted view.
    pub zoom: Option<f32>,
    /// `follow=1`: the map follows the robot.
    pub follow: Option<bool>,
    /// `speed=max` or `speed=N`: the clock's speed while running, as the time
    /// bar's speed field and max box set it.
    pub speed: Option<Speed>,
    /// `estimate=FILE` (repeatable): a student's estimate beside the page, scored
    /// in the lesson.
    pub estimates: Vec<String>,
    /// `assignment=ekf-slam` (a built-in assignment) or `assignment=hw3.json` (an
    /// assignment file beside the page): homework, opened in its lesson.
    pub assignment: Option<String>,
    /// `student=ada@uni.edu`: whose variant of the assignment (any text; it
    /// derives the seed).
    pub student: Option<String>,
}

/// The longest `student=` text read (an e-mail address or a name fits many times).
pub const MAX_STUDENT_CHARS: usize = 200;

/// The clock's speed a link asks for (`speed=`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    /// `speed=max`: as many ticks as fit in each frame's budget.
    Max,
    /// `speed=N`: N ticks (scans, steps) per second, within
    /// [`crate::time_control::SPEED_RANGE`].
    TicksPerSecond(f64),
}

impl Speed {
    /// The value in a link.
    pub fn value(self) -> String {
        match self {
            Speed::Max => "max".to_owned(),
            Speed::TicksPerSecond(v) => format!("{v}"),
        }
    }
}

impl FigureOptions {
    /// The options as `key=value` pairs for a link (`tick` given separately).
    pub fn pairs(&self, tick: u64) -> Vec<(String, String)> {
        let mut pairs = Vec::new();
        if tick > 0 {
            pairs.push(("tick".to_owned(), tick.min(TICK_LIMIT).to_string()));
        }
        if self.run {
            pairs.push(("run".to_owned(), "1".to_owned()));
        }
        if let Some(on) = self.legend {
            pairs.push(("legend".to_owned(), u8::from(on).to_string()));
        }
        if let Some(p) = self.panels {
            let names: Vec<&str> = [p.parameters, p.explanation, p.plots]
                .iter()
                .zip(PANEL_NAMES)
                .filter_map(|(on, name)| on.then_some(name))
                .collect();
            pairs.push(("panels".to_owned(), names.join(",")));
        }
        if let Some(z) = self.zoom {
            pairs.push(("zoom".to_owned(), format!("{z}")));
        }
        if let Some(on) = self.follow {
            pairs.push(("follow".to_owned(), u8::from(on).to_string()));
        }
        if let Some(speed) = self.speed {
            pairs.push(("speed".to_owned(), speed.value()));
        }
        for location in &self.estimates {
            pairs.push(("estimate".to_owned(), location.clone()));
        }
        if let Some(assignment) = &self.assignment {
            pairs.push(("assignment".to_owned(), assignment.clone()));
        }
        if let Some(student) = &self.student {
            pairs.push(("student".to_owned(), student.clone()));
        }
        pairs
    }
}

/// Reads an on/off value (`1`, `true`, `yes`, `on`, empty; `0`, `false`, `no`, `off`).
fn parse_switch(value: &str) -> Option<bool> {
    match value.to_ascii_lowercase().as_str() {
        "" | "1" | "true" | "yes" | "on" => Some(true),
        "0" | "false" | "no" | "off" => Some(false),
        _ => None,
    }
}

/// The range of `many-runs=`.
pub const MANY_RUNS_RANGE: std::ops::RangeInclusive<usize> = 5..=500;

impl Query {
    /// Parses a query string, with or without the leading `?`.
    pub fn parse(query: &str) -> Self {
        let mut parsed = Query::default();
        let query = query.trim().trim_start_matches('?');
        for (key, value) in decode_pairs(query) {
            match key.as_str() {
                "lesson" => parsed.lesson = Some(value),
                "embed" => match value.as_str() {
                    "" | "1" | "true" | "yes" | "on" => parsed.embed = true,
                    "0" | "false" | "no" | "off" => parsed.embed = false,
                    other => parsed.issues.push(format!(
                        "embed = '{other}' is not 1 or 0; the full layout is used"
                    )),
                },
                "many-runs" => match value.parse::<usize>() {
                    Ok(n) if MANY_RUNS_RANGE.contains(&n) => parsed.many_runs = Some(n),
                    Ok(n) => {
                        let clamped = n.clamp(*MANY_RUNS_RANGE.start(), *MANY_RUNS_RANGE.end());
                        parsed.issues.push(format!(
                            "many-runs = {n} is outside {}..{}; {clamped} runs are used",
                            MANY_RUNS_RANGE.start(),
                            MANY_RUNS_RANGE.end()
                        ));
                        parsed.many_runs = Some(clamped);
                    }
                    Err(_) => parsed.issues.push(format!(
                        "many-runs = '{value}' is not a whole number of runs ({}..{}); the window stays closed",
                        MANY_RUNS_RANGE.start(),
                        MANY_RUNS_RANGE.end()
                    )),
                },
                "tick" | "run" | "legend" | "panels" | "zoom" | "follow" | "estimate" | "speed"
                | "assignment" | "student" => {
                    parsed.parse_figure_key(&key, &value);
                }
                _ => parsed.pairs.push((key, value)),
            }
        }
        parsed
    }

    /// Reads one of the figure keys; bad values become an issue and the default.
    fn parse_figure_key(&mut self, key: &str, value: &str) {
        let figure = &mut self.figure;
        match key {
            "assignment" => {
                // A built-in name, or an assignment file beside the page.
                let source = value.trim();
                if source.is_empty()
                    || source.len() > 1024
                    || source.contains("://")
                    || source.chars().any(char::is_control)
                {
                    self.issues.push(format!(
                        "assignment = '{}' is neither a built-in assignment (such as ekf-slam) nor an assignment file beside the page (such as hw3.json); the lesson opens without homework",
                        short(source)
                    ));
                } else {
                    figure.assignment = Some(source.to_owned());
                }
            }
            "student" => {
                let student = value.trim();
                if student.is_empty()
                    || student.chars().count() > MAX_STUDENT_CHARS
                    || student.chars().any(char::is_control)
                {
                    self.issues.push(format!(
                        "student = '{}' is not a student's id (1 to {MAX_STUDENT_CHARS} characters, such as an e-mail address); type yours in the Assignment window",
                        short(student)
                    ));
                } else {
                    figure.student = Some(student.to_owned());
                }
            }
            "estimate" => {
                // A file beside the page (or a path on the desktop), as map= names one.
                let location = value.trim();
                if location.is_empty() || location.len() > 1024 || location.contains("://") {
                    self.issues.push(format!(
                        "estimate = '{}' is not a file beside the page (a relative path such as estimates/mine.tum); it is ignored",
                        location.chars().take(80).collect::<String>()
                    ));
                } else if figure.estimates.len() >= MAX_ESTIMATES {
                    self.issues.push(format!(
                        "estimate = '{location}': at most {} estimates; it is ignored",
                        MAX_ESTIMATES
                    ));
                } else {
                    figure.estimates.push(location.to_owned());
                }
            }
            "speed" => {
                let range = crate::time_control::SPEED_RANGE;
                if value.eq_ignore_ascii_case("max") {
                    figure.speed = Some(Speed::Max);
                } else {
                    match value.parse::<f64>() {
                        Ok(v) if v.is_finite() && range.contains(&v) => {
                            figure.speed = Some(Speed::TicksPerSecond(v));
                        }
                        Ok(v) if v.is_finite() && v > 0.0 => {
                            let clamped = v.clamp(*range.start(), *range.end());
                            self.issues.push(format!(
                                "speed = {v} is outside {}..{} per second; {clamped} is used",
                                range.start(),
                                range.end()
                            ));
                            figure.speed = Some(Speed::TicksPerSecond(clamped));
                        }
                        _ => self.issues.push(format!(
                            "speed = '{value}' is not a number of ticks per second ({}..{}) or max; the lesson's speed is used",
                            range.start(),
                            range.end()
                        )),
                    }
                }
            }
            "tick" => match value.parse::<u64>() {
                Ok(n) if n <= TICK_LIMIT => figure.tick = Some(n),
                Ok(n) => {
                    self.issues.push(format!(
                        "tick = {n} is beyond {TICK_LIMIT}; the figure opens at tick {TICK_LIMIT}"
                    ));
                    figure.tick = Some(TICK_LIMIT);
                }
                Err(_) => self.issues.push(format!(
                    "tick = '{value}' is not a whole number of ticks (0..{TICK_LIMIT}); the figure opens at tick 0"
                )),
            },
            "run" | "legend" | "follow" => match parse_switch(value) {
                Some(on) => match key {
                    "run" => figure.run = on,
                    "legend" => figure.legend = Some(on),
                    _ => figure.follow = Some(on),
                },
                None => self.issues.push(format!(
                    "{key} = '{value}' is not 1 or 0; the lesson's default is used"
                )),
            },
            "panels" => {
                let mut panels = crate::panels::PanelVisibility {
                    parameters: false,
                    explanation: false,
                    plots: false,
                };
                for name in value.split(',').map(str::trim).filter(|n| !n.is_empty()) {
                    match name.to_ascii_lowercase().as_str() {
                        "parameters" | "params" => panels.parameters = true,
                        "explanation" | "explain" => panels.explanation = true,
                        "plots" => panels.plots = true,
                        "none" => {}
                        other => self.issues.push(format!(
                            "panels: there is no panel '{other}' (only {}); it is left out",
                            PANEL_NAMES.join(", ")
                        )),
                    }
                }
                figure.panels = Some(panels);
            }
            _ => match value.parse::<f32>() {
                Ok(z) if z.is_finite() && ZOOM_RANGE.contains(&z) => figure.zoom = Some(z),
                Ok(z) if z.is_finite() && z > 0.0 => {
                    let clamped = z.clamp(*ZOOM_RANGE.start(), *ZOOM_RANGE.end());
                    self.issues.push(format!(
                        "zoom = {z} is outside {}..{}; zoom {clamped} is used",
                        ZOOM_RANGE.start(),
                        ZOOM_RANGE.end()
                    ));
                    figure.zoom = Some(clamped);
                }
                _ => self.issues.push(format!(
                    "zoom = '{value}' is not a positive factor ({}..{}); the map shows the whole world",
                    ZOOM_RANGE.start(),
                    ZOOM_RANGE.end()
                )),
            },
        }
    }
}

/// At most 80 characters of `text`, for a notice that quotes it.
fn short(text: &str) -> String {
    let mut out: String = text.chars().filter(|c| !c.is_control()).take(80).collect();
    if text.chars().count() > 80 {
        out.push('…');
    }
    out
}

/// The `key=value` pairs of a query string (`application/x-www-form-urlencoded`,
/// decoded by `form_urlencoded`: `+` is a space, `%XX` a byte, an invalid escape
/// stays as written, invalid UTF-8 becomes U+FFFD), trimmed, in order. Parts that
/// are blank are skipped.
pub fn decode_pairs(query: &str) -> Vec<(String, String)> {
    form_urlencoded::parse(query.as_bytes())
        .map(|(k, v)| (k.trim().to_owned(), v.trim().to_owned()))
        .filter(|(k, v)| !(k.is_empty() && v.is_empty()))
        .collect()
}

/// Encodes a key or value for a query string with `form_urlencoded` (letters, digits
/// and `*-._` stay, a space becomes `+`, the rest `%XX`); commas stay as they are, so
/// lists read as lists in a link (`estimator=ekf,ukf`).
pub fn percent_encode(text: &str) -> String {
    text.split(',')
        .map(|piece| form_urlencoded::byte_serialize(piece.as_bytes()).collect::<String>())
        .collect::<Vec<_>>()
        .join(",")
}

/// Builds `lesson=...&key=value&...&embed=1` (without the leading `?`).
pub fn build(lesson: &str, pairs: &[(String, String)], embed: bool) -> String {
    let mut parts = vec![format!("lesson={}", percent_encode(lesson))];
    parts.extend(
        pairs
            .iter()
            .map(|(k, v)| format!("{}={}", percent_encode(k), percent_encode(v))),
    );
    if embed {
        parts.push("embed=1".to_owned());
    }
    parts.join("&")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_app_keys_from_lesson_pairs() {
        let q = Query::parse("?lesson=landmark-slam&seed=7&embed=1&fov-deg=90");
        assert_eq!(q.lesson.as_deref(), Some("landmark-slam"));
        assert!(q.embed);
        assert_eq!(
            q.pairs,
            vec![
                ("seed".to_owned(), "7".to_owned()),
                ("fov-deg".to_owned(), "90".to_owned())
            ]
        );
        assert!(q.issues.is_empty());
    }

    #[test]
    fn tolerates_junk() {
        let q = Query::parse("&&=&embed=maybe&%zz=%4&a+b=c%20d&%E2%82%AC");
        assert!(!q.embed);
        assert_eq!(q.issues.len(), 1);
        assert!(q.pairs.contains(&("%zz".to_owned(), "%4".to_owned())));
        assert!(q.pairs.contains(&("a b".to_owned(), "c d".to_owned())));
        assert!(q.pairs.contains(&("€".to_owned(), String::new())));
        assert_eq!(Query::parse(""), Query::default());
        let pairs = |q: &str| Query::parse(q).pairs;
        let one = |v: &str| vec![("k".to_owned(), v.to_owned())];
        assert_eq!(pairs("k=%"), one("%"));
        assert_eq!(pairs("k=%4"), one("%4"));
        assert_eq!(pairs("k=%41"), one("A"));
        assert_eq!(pairs("k=%FF"), one("\u{FFFD}"));
        assert_eq!(pairs("k=a=b"), one("a=b"));
        assert_eq!(pairs("k=%2C%20x+y"), one(", x y"));
    }

    #[test]
    fn many_runs_is_read_clamped_or_refused() {
        assert_eq!(Query::parse("many-runs=50").many_runs, Some(50));
        let q = Query::parse("many-runs=1");
        assert_eq!(q.many_runs, Some(5));
        assert!(q.issues[0].contains("5 runs are used"), "{:?}", q.issues);
        assert_eq!(Query::parse("many-runs=99999").many_runs, Some(500));
        for bad in [
            "many-runs=abc",
            "many-runs=-3",
            "many-runs=",
            "many-runs=NaN",
        ] {
            let q = Query::parse(bad);
            assert_eq!(q.many_runs, None, "{bad}");
            assert_eq!(q.issues.len(), 1, "{bad}");
            assert!(q.pairs.is_empty(), "{bad}: not a lesson parameter");
        }
    }

    #[test]
    fn figure_keys_are_read_and_kept_from_the_lesson() {
        let q = Query::parse(
            "lesson=kidnap&tick=120&run=1&legend=0&panels=plots,explanation&zoom=2.5&follow=yes&seed=3",
        );
        assert!(q.issues.is_empty(), "{:?}", q.issues);
        assert_eq!(q.pairs, vec![("seed".to_owned(), "3".to_owned())]);
        let f = &q.figure;
        assert_eq!(f.tick, Some(120));
        assert!(f.run);
        assert_eq!(f.legend, Some(false));
        assert_eq!(f.zoom, Some(2.5));
        assert_eq!(f.follow, Some(true));
        assert_eq!(
            f.panels,
            Some(crate::panels::PanelVisibility {
                parameters: false,
                explanation: true,
                plots: true
            })
        );
        // The link the shell writes reads back the same.
        let again = Query::parse(&build("kidnap", &f.pairs(120), false));
        assert_eq!(&again.figure, f);
        assert_eq!(Query::parse("").figure, FigureOptions::default());
    }

    #[test]
    fn bad_figure_keys_give_a_notice_and_the_default() {
        let q = Query::parse("tick=999999");
        assert_eq!(q.figure.tick, Some(TICK_LIMIT));
        assert!(q.issues[0].contains("opens at tick 2000"), "{:?}", q.issues);
        for bad in ["tick=-1", "tick=abc", "tick=1e3"] {
            let q = Query::parse(bad);
            assert_eq!(q.figure.tick, None, "{bad}");
            assert_eq!(q.issues.len(), 1, "{bad}");
        }
        for bad in [
            "zoom=0", "zoom=NaN", "zoom=-2", "zoom=inf", "zoom=", "zoom=big",
        ] {
            let q = Query::parse(bad);
            assert_eq!(q.figure.zoom, None, "{bad}");
            assert_eq!(q.issues.len(), 1, "{bad}");
            assert!(q.pairs.is_empty(), "{bad}");
        }
        let q = Query::parse("zoom=1000");
        assert_eq!(q.figure.zoom, Some(20.0));
        assert_eq!(q.issues.len(), 1);
        let q = Query::parse("panels=plots,maps,parameters");
        assert_eq!(q.issues.len(), 1);
        assert!(q.issues[0].contains("'maps'"), "{:?}", q.issues);
        assert_eq!(
            q.figure.panels,
            Some(crate::panels::PanelVisibility {
                parameters: true,
                explanation: false,
                plots: true
            })
        );
        let q = Query::parse("legend=maybe&run=2&follow=x");
        assert_eq!(q.issues.len(), 3);
        assert_eq!(
            (q.figure.legend, q.figure.run, q.figure.follow),
            (None, false, None)
        );
    }

    #[test]
    fn homework_keys_are_read_and_bad_ones_refused_by_name() {
        let q = Query::parse("assignment=ekf-slam&student=Ada%40Uni.edu&seed=3");
        assert!(q.issues.is_empty(), "{:?}", q.issues);
        assert_eq!(q.figure.assignment.as_deref(), Some("ekf-slam"));
        assert_eq!(q.figure.student.as_deref(), Some("Ada@Uni.edu"));
        assert_eq!(q.pairs, vec![("seed".to_owned(), "3".to_owned())]);
        let again = Query::parse(&build("landmark-slam", &q.figure.pairs(0), false));
        assert_eq!(again.figure, q.figure);
        let q = Query::parse("assignment=homework%2Fhw3.json");
        assert_eq!(q.figure.assignment.as_deref(), Some("homework/hw3.json"));
        let long = "x".repeat(MAX_STUDENT_CHARS + 1);
        for (bad, starts) in [
            ("assignment=", "assignment = ''"),
            (
                "assignment=https://elsewhere.example/hw.json",
                "assignment = 'https://elsewhere.example/hw.json'",
            ),
            ("student=", "student = ''"),
            ("student=a%0Ab", "student = 'ab'"),
            (&format!("student={long}"), "student = 'xxxxxxxx"),
        ] {
            let q = Query::parse(bad);
            assert_eq!(q.issues.len(), 1, "{bad}");
            assert!(q.issues[0].starts_with(starts), "{bad}: {:?}", q.issues);
            assert_eq!(q.figure, FigureOptions::default(), "{bad}");
            assert!(q.pairs.is_empty(), "{bad}");
        }
    }

    #[test]
    fn speed_is_read_clamped_or_refused() {
        assert_eq!(Query::parse("speed=max").figure.speed, Some(Speed::Max));
        assert_eq!(Query::parse("speed=MAX").figure.speed, Some(Speed::Max));
        let q = Query::parse("lesson=mapping&speed=50");
        assert_eq!(q.figure.speed, Some(Speed::TicksPerSecond(50.0)));
        assert!(q.issues.is_empty() && q.pairs.is_empty(), "{q:?}");
        // The link the shell writes reads back the same.
        for speed in [Speed::Max, Speed::TicksPerSecond(2.5)] {
            let figure = FigureOptions {
                speed: Some(speed),
                ..FigureOptions::default()
            };
            let again = Query::parse(&build("mapping", &figure.pairs(0), false));
            assert_eq!(again.figure, figure);
        }
        let q = Query::parse("speed=100000");
        assert_eq!(q.figure.speed, Some(Speed::TicksPerSecond(200.0)));
        assert!(q.issues[0].contains("200 is used"), "{:?}", q.issues);
        let q = Query::parse("speed=0.01");
        assert_eq!(q.figure.speed, Some(Speed::TicksPerSecond(1.0)));
        for bad in [
            "speed=0",
            "speed=-3",
            "speed=NaN",
            "speed=inf",
            "speed=",
            "speed=fast",
        ] {
            let q = Query::parse(bad);
            assert_eq!(q.figure.speed, None, "{bad}");
            assert_eq!(q.issues.len(), 1, "{bad}");
            assert!(q.pairs.is_empty(), "{bad}: not a lesson parameter");
        }
    }

    #[test]
    fn build_round_trips() {
        let pairs = vec![
            ("seed".to_owned(), "7".to_owned()),
            ("estimator".to_owned(), "ekf,ukf".to_owned()),
            ("odd key".to_owned(), "a&b=c".to_owned()),
        ];
        let text = build("landmark-slam", &pairs, true);
        assert_eq!(
            text,
            "lesson=landmark-slam&seed=7&estimator=ekf,ukf&odd+key=a%26b%3Dc&embed=1"
        );
        let q = Query::parse(&text);
        assert_eq!(q.pairs, pairs);
        assert!(q.embed);
    }

    /// The pairs applied to a lesson's scenario, as `apply_pairs` does when a lesson
    /// opens; an issue that does not name its parameter is an error of its own.
    fn apply<S: slamlab_sim::params::Scenario>(pairs: &[(String, String)]) -> Vec<String> {
        use slamlab_sim::params::{self, ParamIssue};
        let mut scenario = S::default();
        let issues = params::apply_pairs(
            &mut scenario,
            pairs.iter().map(|(k, v)| (k.as_str(), v.as_str())),
            &APP_KEYS,
        );
        issues
            .iter()
            .map(|issue| {
                let (ParamIssue::Unknown { name }
                | ParamIssue::Unreadable { name, .. }
                | ParamIssue::Ignored { name, .. }
                | ParamIssue::Clamped { name, .. }) = issue;
                let text = issue.to_string();
                if text.contains(name.as_str()) {
                    text
                } else {
                    format!("{MUTE}'{text}' does not name the parameter '{name}'")
                }
            })
            .collect()
    }

    /// What marks a problem of the reader (not a refusal of a bad link) in the
    /// fuzz test's messages.
    const MUTE: &str = "issue without its key: ";
    const ROUND_TRIP: &str = "round trip: ";

    /// Every lesson's parameters as a share link writes them, and hand-written links
    /// with the figure keys and odd encodings: the URL fuzz test's seeds.
    fn query_seeds() -> Vec<Vec<u8>> {
        use slamlab_sim::params::{Scenario, to_pairs};
        fn link<S: Scenario>(lesson: &str) -> String {
            let pairs: Vec<(String, String)> = to_pairs(&S::default())
                .into_iter()
                .map(|(k, v)| (k.to_owned(), v))
                .collect();
            build(lesson, &pairs, false)
        }
        let mut seeds = vec![
            link::<slamlab_sim::LandmarkScenario>("landmark-slam"),
            link::<slamlab_sim::kidnap::MclScenario>("kidnap"),
            link::<slamlab_sim::pose_graph::session::PoseGraphScenario>("pose-graph"),
            link::<slamlab_sim::resampling::session::LabScenario>("resampling"),
            link::<slamlab_sim::fusion::params::FusionLessonScenario>("fusion"),
            link::<slamlab_sim::mapping::MappingScenario>("mapping"),
        ];
        seeds.extend(
            [
                "?lesson=landmark-slam&seed=7&embed=1&fov-deg=90&landmarks=30",
                "?lesson=kidnap&estimator=amcl,acmcl&init=tracking&particles=500&kidnap-at=30&seed=4",
                "lesson=kidnap&map=maps%2Foffice.yaml&particles=300&seed=2&tick=120&run=1&legend=0",
                "lesson=pose-graph&noise=0.2&kernel=huber&panels=plots,explanation&zoom=2.5&follow=1",
                "lesson=resampling&many-runs=50&embed=yes",
                "lesson=fusion&slam-mode=differential&seed=3&odd+key=a%26b%3Dc&%E2%82%AC=%FF",
                "lesson=mapping&source=icp&seed=5&embed=1&panels=none",
            ]
            .map(str::to_owned),
        );
        seeds.into_iter().map(String::into_bytes).collect()
    }

    /// The URL reader under [`slamlab_fuzz::inputs_per_reader`] mutated query strings
    /// (10,000 in `./test.sh`): no panic, at most 16 MiB held at once, every issue a
    /// sentence that names its key (the app's own and every lesson's parameters);
    /// and `parse(build(pairs))` gives the pairs back.
    #[test]
    fn query_strings_survive_mutations() {
        use slamlab_sim::{fusion, kidnap, mapping, pose_graph, resampling};
        let report = slamlab_fuzz::Target::new("URL query string", query_seeds(), 16 << 20)
            .run_checked(
                |bytes| {
                    let text = String::from_utf8_lossy(bytes);
                    let q = Query::parse(&text);
                    let link = build(q.lesson.as_deref().unwrap_or(""), &q.pairs, q.embed);
                    let again = Query::parse(&link);
                    if again.pairs != q.pairs || again.embed != q.embed {
                        return Err(format!(
                            "{ROUND_TRIP}{:?} (embed {}) came back from '{link}' as {:?} (embed {})",
                            q.pairs, q.embed, again.pairs, again.embed
                        ));
                    }
                    let mut issues = q.issues.clone();
                    issues.extend(apply::<slamlab_sim::LandmarkScenario>(&q.pairs));
                    issues.extend(apply::<kidnap::MclScenario>(&q.pairs));
                    issues.extend(apply::<pose_graph::PoseGraphScenario>(&q.pairs));
                    issues.extend(apply::<resampling::LabScenario>(&q.pairs));
                    issues.extend(apply::<fusion::params::FusionLessonScenario>(&q.pairs));
                    issues.extend(apply::<mapping::MappingScenario>(&q.pairs));
                    if let Some(short) = issues
                        .iter()
                        .find(|i| i.trim().chars().count() < slamlab_fuzz::MIN_MESSAGE_CHARS)
                    {
                        return Err(format!("{MUTE}'{short}' says too little"));
                    }
                    match issues.iter().find(|i| i.starts_with(MUTE)) {
                        Some(mute) => Err(mute.clone()),
                        None if issues.is_empty() => Ok(()),
                        None => Err(issues.join("\n")),
                    }
                },
                |message| {
                    if message.starts_with(ROUND_TRIP) || message.starts_with(MUTE) {
                        Err(message.to_owned())
                    } else {
                        Ok(())
                    }
                },
            );
        report.assert_clean();
    }
}
