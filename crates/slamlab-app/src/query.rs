//! The page's query string: `?lesson=landmark-slam&seed=7&embed=1&landmarks=30`.
//!
//! The app reads `lesson`, `embed` and `many-runs` itself; every other pair belongs to the lesson,
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
    /// Every other `key=value` pair, decoded, in order.
    pub pairs: Vec<(String, String)>,
    /// Problems with the app's own keys (`embed=maybe`), worded for the user.
    pub issues: Vec<String>,
}

/// The keys the app reads itself; lessons never see them.
pub const APP_KEYS: [&str; 3] = ["lesson", "embed", "many-runs"];

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
                _ => parsed.pairs.push((key, value)),
            }
        }
        parsed
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
