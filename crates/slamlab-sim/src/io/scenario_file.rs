//! A lesson's setup as a JSON file: what the app exports ("Scenario as JSON"), opens
//! again (file picker or drag-and-drop), and `slamlab run LESSON --scenario FILE` runs.
//!
//! ```json
//! {
//!   "format": "slamlab-scenario",
//!   "version": 1,
//!   "lesson": "landmark-slam",
//!   "params": { "seed": "7", "estimator": "ekf,ukf", "landmarks": "30" },
//!   "view": { "tick": "120", "legend": "1" }
//! }
//! ```
//!
//! `params` are the lesson's parameters with exactly the names and the text of the
//! URL and the CLI flags (`index.html?lesson=landmark-slam&seed=7&landmarks=30` is the
//! same setup), so one parameter table reads all three. `view` holds the figure keys
//! of the app (`tick`, `legend`, `zoom`, `follow`, `panels`), which the CLI ignores.
//! Numbers and booleans are accepted in place of strings, so a hand-written file can
//! say `"seed": 7`.

use serde_json::Value;

/// The `format` field every scenario file carries.
pub const FORMAT: &str = "slamlab-scenario";
/// The version this build writes and reads.
pub const VERSION: u64 = 1;

/// A lesson's setup: its id, its parameters and the app's figure keys, as `key=value`
/// text pairs.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ScenarioFile {
    /// The lesson id (`lesson=` in URLs).
    pub lesson: String,
    /// The lesson's parameters, in order.
    pub params: Vec<(String, String)>,
    /// The app's figure keys (`tick`, `legend`, ...), in order.
    pub view: Vec<(String, String)>,
}

impl ScenarioFile {
    /// The file's text: pretty JSON with the pairs in the order given.
    pub fn to_json(&self) -> String {
        let quote = |text: &str| serde_json::to_string(text).unwrap_or_else(|_| "\"\"".into());
        let object = |pairs: &[(String, String)]| {
            if pairs.is_empty() {
                return "{}".to_owned();
            }
            let body: Vec<String> = pairs
                .iter()
                .map(|(k, v)| format!("    {}: {}", quote(k), quote(v)))
                .collect();
            format!("{{\n{}\n  }}", body.join(",\n"))
        };
        let mut fields = vec![
            format!("  \"format\": {}", quote(FORMAT)),
            format!("  \"version\": {VERSION}"),
            format!("  \"lesson\": {}", quote(&self.lesson)),
            format!("  \"params\": {}", object(&self.params)),
        ];
        if !self.view.is_empty() {
            fields.push(format!("  \"view\": {}", object(&self.view)));
        }
        format!("{{\n{}\n}}\n", fields.join(",\n"))
    }

    /// Reads a scenario file, or says in one sentence what is wrong with it.
    pub fn parse(text: &str) -> Result<Self, String> {
        let value: Value = serde_json::from_str(text)
            .map_err(|e| format!("not a SLAM Lab scenario: the JSON does not parse ({e})"))?;
        let Value::Object(root) = value else {
            return Err("not a SLAM Lab scenario: the file is not a JSON object".into());
        };
        match root.get("format") {
            Some(Value::String(f)) if f == FORMAT => {}
            _ => {
                return Err(format!(
                    "not a SLAM Lab scenario: \"format\" must be \"{FORMAT}\""
                ));
            }
        }
        match root.get("version") {
            Some(v) if v.as_u64() == Some(VERSION) => {}
            Some(v) => {
                return Err(format!(
                    "scenario version {v} is not supported; this SLAM Lab reads version {VERSION}"
                ));
            }
            None => return Err("the scenario has no \"version\"".into()),
        }
        let lesson = match root.get("lesson") {
            Some(Value::String(id)) if !id.trim().is_empty() => id.trim().to_owned(),
            _ => return Err("the scenario names no \"lesson\"".into()),
        };
        for field in ["params", "view"] {
            if !matches!(root.get(field), None | Some(Value::Null | Value::Object(_))) {
                return Err(format!("\"{field}\" must be an object of key: value"));
            }
        }
        // The pairs in the file's order (read into a map they would be sorted).
        let ordered: OrderedFields = serde_json::from_str(text)
            .map_err(|e| format!("not a SLAM Lab scenario: the JSON does not parse ({e})"))?;
        let pairs =
            |field: &str, entries: Option<Entries>| -> Result<Vec<(String, String)>, String> {
                entries
                    .map(|e| e.0)
                    .unwrap_or_default()
                    .into_iter()
                    .map(|(k, v)| {
                        let text = match v {
                            Value::String(s) => s,
                            Value::Number(n) => n.to_string(),
                            Value::Bool(b) => if b { "1" } else { "0" }.to_owned(),
                            _ => {
                                return Err(format!(
                                    "\"{field}\".\"{k}\" must be a string, number or boolean"
                                ));
                            }
                        };
                        Ok((k, text))
                    })
                    .collect()
            };
        let params = pairs("params", ordered.params)?;
        let view = pairs("view", ordered.view)?;
        Ok(Self {
            lesson,
            params,
            view,
        })
    }

    /// The value of parameter `key`, if the file sets it.
    pub fn param(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// The file's `params` and `view` objects with their entries in file order (other
/// fields are checked on the parsed [`Value`]).
#[derive(serde::Deserialize)]
struct OrderedFields {
    #[serde(default)]
    params: Option<Entries>,
    #[serde(default)]
    view: Option<Entries>,
}

/// A JSON object's entries, in order.
struct Entries(Vec<(String, Value)>);

impl<'de> serde::Deserialize<'de> for Entries {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Entries;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("an object of key: value")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Entries, A::Error> {
                let mut entries = Vec::new();
                while let Some(entry) = map.next_entry::<String, Value>()? {
                    entries.push(entry);
                }
                Ok(Entries(entries))
            }
        }
        deserializer.deserialize_map(Visit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ScenarioFile {
        ScenarioFile {
            lesson: "landmark-slam".into(),
            params: vec![
                ("seed".into(), "7".into()),
                ("estimator".into(), "ekf,ukf".into()),
                ("range-std".into(), "0.1".into()),
            ],
            view: vec![("tick".into(), "120".into())],
        }
    }

    #[test]
    fn a_file_round_trips_and_keeps_the_order() {
        let file = sample();
        let text = file.to_json();
        assert!(text.contains("\"format\": \"slamlab-scenario\""), "{text}");
        let back = ScenarioFile::parse(&text).unwrap();
        assert_eq!(back, file);
        assert_eq!(back.param("estimator"), Some("ekf,ukf"));
        assert_eq!(back.param("nope"), None);
    }

    #[test]
    fn hand_written_numbers_and_booleans_are_read_as_text() {
        let text = r#"{"format":"slamlab-scenario","version":1,"lesson":"kidnap",
                       "params":{"seed":7,"particles":500,"range-std":0.25,"x":true}}"#;
        let file = ScenarioFile::parse(text).unwrap();
        assert_eq!(file.lesson, "kidnap");
        assert_eq!(
            file.params,
            vec![
                ("seed".into(), "7".into()),
                ("particles".into(), "500".into()),
                ("range-std".into(), "0.25".into()),
                ("x".into(), "1".into()),
            ]
        );
        assert!(file.view.is_empty());
    }

    #[test]
    fn bad_files_say_what_is_wrong() {
        let cases = [
            ("", "does not parse"),
            ("[1, 2]", "not a JSON object"),
            (r#"{"version":1,"lesson":"x"}"#, "\"format\" must be"),
            (
                r#"{"format":"slamlab-scenario","version":2,"lesson":"x"}"#,
                "version 2 is not supported",
            ),
            (
                r#"{"format":"slamlab-scenario","lesson":"x"}"#,
                "no \"version\"",
            ),
            (
                r#"{"format":"slamlab-scenario","version":1,"lesson":""}"#,
                "names no \"lesson\"",
            ),
            (
                r#"{"format":"slamlab-scenario","version":1,"lesson":"x","params":[1]}"#,
                "\"params\" must be an object",
            ),
            (
                r#"{"format":"slamlab-scenario","version":1,"lesson":"x","params":{"a":[1]}}"#,
                "\"params\".\"a\" must be",
            ),
        ];
        for (text, expected) in cases {
            match ScenarioFile::parse(text) {
                Ok(file) => panic!("{text:?} parsed: {file:?}"),
                Err(message) => assert!(message.contains(expected), "{text:?}: {message}"),
            }
        }
    }
}
