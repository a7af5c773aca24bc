//! The page's query string: `?lesson=landmark-slam&seed=7&embed=1&landmarks=30`.
//!
//! The app reads `lesson`, `embed`, `many-runs` and the figure keys (`tick`, `run`,
//! `legend`, `panels`, `zoom`, `follow`: how a lecture figure opens) itself; every
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

/// The keys the app reads itself; lessons never see them.
pub const APP_KEYS: [&str; 9] = [
    "lesson",
    "embed",
    "many-runs",
    "tick",
    "run",
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
        for part in query.split('&').filter(|p| !p.trim().is_empty()) {
            let (key, value) = part.split_once('=').unwrap_or((part, ""));
            let key = percent_decode(key).trim().to_owned();
            let value = percent_decode(value).trim().to_owned();
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
                "tick" | "run" | "legend" | "panels" | "zoom" | "follow" => {
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

/// Decodes `%XX` escapes and `+` (a space in form encoding). Invalid escapes are kept
/// as they are; invalid UTF-8 is replaced.
pub fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            b'%' if i + 2 < bytes.len() => {
                let hex = std::str::from_utf8(&bytes[i + 1..i + 3])
                    .ok()
                    .and_then(|h| u8::from_str_radix(h, 16).ok());
                match hex {
                    Some(b) => {
                        out.push(b);
                        i += 3;
                    }
                    None => {
                        out.push(b'%');
                        i += 1;
                    }
                }
            }
            b => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Encodes a value for a query string: letters, digits and `-_.~,` stay, the rest is `%XX`.
pub fn percent_encode(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.~,".contains(&b) {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
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
        assert_eq!(percent_decode("%"), "%");
        assert_eq!(percent_decode("%4"), "%4");
        assert_eq!(percent_decode("%41"), "A");
        assert_eq!(percent_decode("%FF"), "\u{FFFD}");
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
    fn build_round_trips() {
        let pairs = vec![
            ("seed".to_owned(), "7".to_owned()),
            ("estimator".to_owned(), "ekf,ukf".to_owned()),
            ("odd key".to_owned(), "a&b=c".to_owned()),
        ];
        let text = build("landmark-slam", &pairs, true);
        assert_eq!(
            text,
            "lesson=landmark-slam&seed=7&estimator=ekf,ukf&odd%20key=a%26b%3Dc&embed=1"
        );
        let q = Query::parse(&text);
        assert_eq!(q.pairs, pairs);
        assert!(q.embed);
    }
}
