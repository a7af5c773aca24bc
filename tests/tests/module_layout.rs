//! The layout tells the architecture (docs/ARCHITECTURE.md), and this test keeps it so:
//!
//! - in every crate, the modules at the top level import each other without a circle,
//!   and so do the files of every folder;
//! - a lesson's folder (in the app and in the simulation crate, one per lesson, named
//!   as the app's) imports no other lesson's folder: what two lessons share lives in
//!   a shared module (`world/`, `grid/`, `io/`, `widgets/`, ...).
//!
//! It reads the sources as text: every path that starts with `crate::`, `super::` or
//! `self::` (in `use` lines and in code; comments and strings are skipped) is an
//! import of the module it names. A folder's `mod.rs` re-exporting its files
//! (`pub use child::Item`) is the folder's face, not an import.
#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module's path inside its crate, e.g. `["mapping", "run"]`.
type ModPath = Vec<String>;

/// One source file: its module path and the module paths it names.
#[derive(Debug)]
struct SourceFile {
    file: PathBuf,
    module: ModPath,
    /// Imports, each resolved to an absolute module path (as long as it names modules).
    imports: Vec<ModPath>,
    /// For a folder's face (`mod.rs`, `lib.rs`): the names it re-exports from its
    /// own files (`pub use run::{A, B}`), each with the file it comes from.
    reexports: BTreeMap<String, String>,
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `src/a/b.rs` is `a::b`, `src/a/mod.rs` is `a`, `src/lib.rs` the root.
fn module_of(src: &Path, file: &Path) -> ModPath {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_owned());
    }
    parts
}

/// The text with comments, string and character literals blanked (lines kept).
fn code_only(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < bytes.len() {
        let rest = &text[i..];
        if rest.starts_with("//") {
            let end = rest.find('\n').map_or(text.len(), |n| i + n);
            i = end;
        } else if rest.starts_with("/*") {
            let end = rest.find("*/").map_or(text.len(), |n| i + n + 2);
            out.extend(text[i..end].chars().filter(|&c| c == '\n'));
            i = end;
        } else if rest.starts_with("r#\"") || rest.starts_with("r\"") {
            let hashes = rest[1..].chars().take_while(|&c| c == '#').count();
            let close = format!("\"{}", "#".repeat(hashes));
            let body = 2 + hashes;
            let end = rest[body..]
                .find(&close)
                .map_or(text.len(), |n| i + body + n + close.len());
            out.extend(text[i..end].chars().filter(|&c| c == '\n'));
            i = end;
        } else if bytes[i] == b'"' {
            let mut j = i + 1;
            while j < bytes.len() && bytes[j] != b'"' {
                j += if bytes[j] == b'\\' { 2 } else { 1 };
            }
            out.extend(text[i..j.min(text.len())].chars().filter(|&c| c == '\n'));
            i = (j + 1).min(text.len());
        } else if bytes[i] == b'\''
            && (rest.get(2..3) == Some("'") || (rest.starts_with("'\\") && rest.len() > 3))
        {
            // A character literal ('a', '\n', '\u{..}'); lifetimes ('a) are left alone.
            let end = rest[1..].find('\'').map_or(text.len(), |n| i + n + 2);
            i = end;
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The paths that start at `start` in `code`: `a::b::c`, or every branch of
/// `{a::b, c}` (each branch's leading identifiers); none for a glob (`a::*`).
fn paths_at(code: &str, start: usize) -> Vec<Vec<String>> {
    let rest = &code[start..];
    let mut segments = Vec::new();
    let mut pos = 0;
    loop {
        let ident: String = rest[pos..].chars().take_while(|&c| is_ident(c)).collect();
        if ident.is_empty() {
            break;
        }
        pos += ident.len();
        segments.push(ident);
        if rest[pos..].starts_with("::") {
            pos += 2;
        } else {
            return vec![segments];
        }
    }
    if rest[pos..].starts_with('*') {
        // A glob (`use super::*`): what it takes is not known from the text.
        return Vec::new();
    }
    if rest[pos..].starts_with('{') {
        // Branches at depth one, split on commas.
        let mut depth = 0;
        let mut branch_starts = vec![pos + 1];
        for (k, c) in rest[pos..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                ',' if depth == 1 => branch_starts.push(pos + k + 1),
                _ => {}
            }
        }
        let offset = start;
        return branch_starts
            .into_iter()
            .flat_map(|b| {
                let skip = rest[b..].len() - rest[b..].trim_start().len();
                paths_at(code, offset + b + skip)
                    .into_iter()
                    .map(|tail| segments.iter().cloned().chain(tail).collect())
            })
            .collect();
    }
    if segments.is_empty() {
        // After a trailing comma in braces: no path.
        return Vec::new();
    }
    vec![segments]
}

/// Every `crate::`/`super::`/`self::` path of a file, resolved to absolute module paths.
fn imports_of(module: &ModPath, is_folder_face: bool, code: &str) -> Vec<ModPath> {
    let mut out = Vec::new();
    // Inline modules (`mod tests { ... }`): `super` inside them climbs from there.
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0_usize;
    let mut line_start = 0;
    let chars: Vec<(usize, char)> = code.char_indices().collect();
    let mut k = 0;
    while k < chars.len() {
        let (i, c) = chars[k];
        if c == '\n' {
            line_start = i + 1;
        }
        if c == '{' {
            depth += 1;
        } else if c == '}' {
            depth = depth.saturating_sub(1);
            while inline.last().is_some_and(|(_, d)| *d > depth) {
                inline.pop();
            }
        }
        let before_ok = i == 0 || {
            let prev = code[..i].chars().next_back().unwrap_or(' ');
            !is_ident(prev) && prev != ':'
        };
        if before_ok && code[i..].starts_with("mod ") {
            let name: String = code[i + 4..].chars().take_while(|&c| is_ident(c)).collect();
            let after = code[i + 4 + name.len()..].trim_start();
            if after.starts_with('{') {
                inline.push((name, depth + 1));
            }
        }
        let keyword = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|kw| before_ok && code[i..].starts_with(kw));
        if let Some(kw) = keyword {
            let line = &code[line_start..];
            let line = &line[..line.find('\n').unwrap_or(line.len())];
            let reexport = is_folder_face && line.trim_start().starts_with("pub use");
            // The module this code is in: the file's, then its inline modules.
            let mut here: ModPath = module.clone();
            here.extend(inline.iter().map(|(n, _)| n.clone()));
            for path in paths_at(code, i) {
                let mut segs = path.into_iter().peekable();
                let mut base = match segs.next().as_deref() {
                    Some("crate") => Vec::new(),
                    _ => here.clone(),
                };
                if kw == "super::" {
                    // The first `super` was consumed above.
                    base.pop();
                }
                let mut rest: Vec<String> = Vec::new();
                for s in segs {
                    if s == "super" && rest.is_empty() {
                        base.pop();
                    } else if s != "self" {
                        rest.push(s);
                    }
                }
                if !reexport {
                    out.push(base.into_iter().chain(rest).collect());
                }
            }
            k += kw.len();
            continue;
        }
        k += 1;
    }
    out
}

/// The names a folder's face re-exports from its own files: `pub use run::{A, B as C};`
/// gives `A -> run` and `C -> run`.
fn reexports_of(code: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut rest = code;
    while let Some(at) = rest.find("pub use ") {
        let statement = &rest[at + 8..];
        let end = statement.find(';').unwrap_or(statement.len());
        let statement: String = statement[..end]
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        rest = &rest[at + 8 + end.min(rest.len() - at - 8)..];
        let statement = statement.trim_start_matches("self::");
        if ["crate::", "super::"]
            .iter()
            .any(|p| statement.starts_with(p))
        {
            continue;
        }
        let Some((child, names)) = statement.split_once("::") else {
            continue;
        };
        let names = names.trim_start_matches('{').trim_end_matches('}');
        for name in names.split(',') {
            let name = name.trim();
            let leaf = name.rsplit(" as ").next().unwrap_or(name);
            let leaf = leaf.rsplit("::").next().unwrap_or(leaf).trim();
            if !leaf.is_empty() && leaf != "*" {
                out.insert(leaf.to_owned(), child.to_owned());
            }
        }
    }
    out
}

/// Every source file of a crate (its `src/` folder).
fn read_crate(name: &str) -> (PathBuf, Vec<SourceFile>) {
    let src = workspace().join("crates").join(name).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let sources = files
        .into_iter()
        .map(|file| {
            let text = std::fs::read_to_string(&file).unwrap();
            let module = module_of(&src, &file);
            let face = file.file_name().is_some_and(|n| n == "mod.rs");
            let code = code_only(&text);
            let imports = imports_of(&module, face, &code);
            let is_face = face
                || file
                    .file_name()
                    .is_some_and(|n| n == "lib.rs" || n == "main.rs");
            let reexports = if is_face {
                reexports_of(&code)
            } else {
                BTreeMap::new()
            };
            SourceFile {
                file,
                module,
                imports,
                reexports,
            }
        })
        .collect();
    (src, sources)
}

/// The node of `folder`'s graph that `target` lands on: the folder's file (or
/// subfolder) it names, the file an item re-exported by the folder's face comes
/// from, or the face itself for an item defined there. `None` outside the folder.
fn node_in(
    modules: &BTreeSet<ModPath>,
    faces: &BTreeMap<ModPath, &BTreeMap<String, String>>,
    folder: &[String],
    target: &ModPath,
) -> Option<ModPath> {
    if !target.starts_with(folder) {
        return None;
    }
    let Some(next) = target.get(folder.len()) else {
        return Some(folder.to_vec());
    };
    let mut child = folder.to_vec();
    child.push(next.clone());
    if modules.contains(&child) {
        return Some(child);
    }
    if let Some(from) = faces.get(folder).and_then(|r| r.get(next)) {
        let mut child = folder.to_vec();
        child.push(from.clone());
        if modules.contains(&child) {
            return Some(child);
        }
    }
    Some(folder.to_vec())
}

/// A circle in `edges`, as the modules along it, if there is one.
fn find_circle(edges: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Option<Vec<ModPath>> {
    fn visit(
        node: &ModPath,
        edges: &BTreeMap<ModPath, BTreeSet<ModPath>>,
        state: &mut BTreeMap<ModPath, u8>,
        stack: &mut Vec<ModPath>,
    ) -> Option<Vec<ModPath>> {
        state.insert(node.clone(), 1);
        stack.push(node.clone());
        for next in edges.get(node).into_iter().flatten() {
            match state.get(next) {
                Some(1) => {
                    let from = stack.iter().position(|n| n == next).unwrap_or(0);
                    let mut circle = stack[from..].to_vec();
                    circle.push(next.clone());
                    return Some(circle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(next, edges, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(node.clone(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in edges.keys() {
        if !state.contains_key(node)
            && let Some(c) = visit(node, edges, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

fn show(path: &[String]) -> String {
    if path.is_empty() {
        "crate".to_owned()
    } else {
        path.join("::")
    }
}

/// Circles among the modules of every folder of a crate (the top level included):
/// the nodes are the folder's files and subfolders and its face (`mod.rs`); an edge
/// runs from one to another when a file in the first names the second.
fn circles_in(files: &[SourceFile]) -> Vec<String> {
    let modules: BTreeSet<ModPath> = files.iter().map(|f| f.module.clone()).collect();
    let faces: BTreeMap<ModPath, &BTreeMap<String, String>> = files
        .iter()
        .filter(|f| !f.reexports.is_empty())
        .map(|f| (f.module.clone(), &f.reexports))
        .collect();
    let folders: BTreeSet<ModPath> = modules
        .iter()
        .filter_map(|m| m.split_last().map(|(_, parent)| parent.to_vec()))
        .collect();
    let mut problems = Vec::new();
    for folder in &folders {
        let mut edges: BTreeMap<ModPath, BTreeSet<ModPath>> = BTreeMap::new();
        for f in files {
            let Some(from) = node_in(&modules, &faces, folder, &f.module) else {
                continue;
            };
            for import in &f.imports {
                if let Some(to) = node_in(&modules, &faces, folder, import)
                    && to != from
                {
                    edges.entry(from.clone()).or_default().insert(to);
                }
            }
        }
        if let Some(circle) = find_circle(&edges) {
            let names: Vec<String> = circle.iter().map(|m| show(m)).collect();
            problems.push(format!("in {}: {}", show(folder), names.join(" -> ")));
        }
    }
    problems
}

/// The app's lesson folders: the top-level folders that declare a `LESSON_ID`.
fn app_lessons() -> BTreeSet<String> {
    let (src, files) = read_crate("slamlab-app");
    files
        .iter()
        .filter(|f| f.module.len() == 1 && f.file.ends_with("mod.rs"))
        .filter(|f| {
            std::fs::read_to_string(&f.file)
                .unwrap()
                .contains("pub const LESSON_ID: &str")
        })
        .map(|f| f.module[0].clone())
        .inspect(|m| assert!(src.join(m).is_dir()))
        .collect()
}

/// Files in one lesson's folder that name another lesson's folder.
fn lesson_crossings(files: &[SourceFile], lessons: &BTreeSet<String>) -> Vec<String> {
    let mut problems = Vec::new();
    for f in files {
        let Some(own) = f.module.first().filter(|m| lessons.contains(*m)) else {
            continue;
        };
        let others: BTreeSet<&String> = f
            .imports
            .iter()
            .filter_map(|i| i.first())
            .filter(|m| lessons.contains(*m) && *m != own)
            .collect();
        for other in others {
            problems.push(format!(
                "{} (lesson {own}) imports the lesson folder {other}",
                f.file
                    .strip_prefix(workspace())
                    .unwrap_or(&f.file)
                    .display()
            ));
        }
    }
    problems
}

#[test]
fn no_crate_has_an_import_circle() {
    let mut problems = Vec::new();
    for name in [
        "slamlab-core",
        "slamlab-sim",
        "slamlab-app",
        "slamlab-cli",
        "slamlab-fuzz",
    ] {
        let (_, files) = read_crate(name);
        assert!(!files.is_empty(), "{name}: no sources read");
        problems.extend(
            circles_in(&files)
                .into_iter()
                .map(|p| format!("{name} {p}")),
        );
    }
    assert!(
        problems.is_empty(),
        "import circles:\n{}",
        problems.join("\n")
    );
}

#[test]
fn every_lesson_has_one_folder_in_the_app_and_the_simulation() {
    let lessons = app_lessons();
    assert_eq!(lessons.len(), 9, "{lessons:?}");
    let sim = workspace().join("crates/slamlab-sim/src");
    for lesson in &lessons {
        assert!(
            sim.join(lesson).join("mod.rs").is_file(),
            "the lesson {lesson} has no folder crates/slamlab-sim/src/{lesson}/"
        );
    }
}

#[test]
fn no_lesson_folder_imports_another() {
    let lessons = app_lessons();
    let mut problems = Vec::new();
    for name in ["slamlab-app", "slamlab-sim"] {
        let (_, files) = read_crate(name);
        problems.extend(lesson_crossings(&files, &lessons));
    }
    assert!(
        problems.is_empty(),
        "lessons that import another lesson:\n{}",
        problems.join("\n")
    );
}

/// The checks themselves: a circle and a crossing written on purpose are found.
#[test]
fn the_checks_find_what_they_look_for() {
    let code = |text: &str| code_only(text);
    let a = SourceFile {
        file: PathBuf::from("a.rs"),
        module: vec!["mapping".into(), "run".into()],
        reexports: BTreeMap::new(),
        imports: imports_of(
            &vec!["mapping".into(), "run".into()],
            false,
            &code(
                "use super::{\n    scenario::S,\n    grid_fastslam,\n};\n// crate::kidnap::X\nfn f() { let s = \"crate::fusion\"; crate::world::f(); }\nmod tests { use super::super::tests::T; }",
            ),
        ),
    };
    assert_eq!(
        a.imports,
        vec![
            vec!["mapping".to_owned(), "scenario".into(), "S".into()],
            vec!["mapping".to_owned(), "grid_fastslam".into()],
            vec!["world".to_owned(), "f".into()],
            vec!["mapping".to_owned(), "tests".into(), "T".into()],
        ]
    );
    let b = SourceFile {
        file: PathBuf::from("b.rs"),
        module: vec!["mapping".into(), "scenario".into()],
        imports: vec![vec!["mapping".into(), "run".into(), "X".into()]],
        reexports: BTreeMap::new(),
    };
    let c = SourceFile {
        file: PathBuf::from("c.rs"),
        module: vec!["cartographer".into()],
        imports: vec![vec!["mapping".into(), "run".into()], vec!["grid".into()]],
        reexports: BTreeMap::new(),
    };
    // `run` and `scenario` import each other.
    let circles = circles_in(&[a, b, c]);
    assert_eq!(
        circles,
        vec!["in mapping: mapping::run -> mapping::scenario -> mapping::run"]
    );
    // The folder's face re-exports `V` from `run` and defines `Z` itself; it
    // imports `tests`, and `tests` imports the face's own `Z` (a circle) and `V`
    // (an import of `run`, not of the face).
    let face = SourceFile {
        file: PathBuf::from("mapping/mod.rs"),
        module: vec!["mapping".into()],
        imports: vec![vec!["mapping".into(), "tests".into(), "f".into()]],
        reexports: reexports_of("pub use run::{W, Y as V};\npub use crate::grid::Q;"),
    };
    assert_eq!(face.reexports.get("V").map(String::as_str), Some("run"));
    assert!(!face.reexports.contains_key("Q"));
    let tests_file = |imports| SourceFile {
        file: PathBuf::from("mapping/tests.rs"),
        module: vec!["mapping".into(), "tests".into()],
        imports,
        reexports: BTreeMap::new(),
    };
    let run = SourceFile {
        file: PathBuf::from("mapping/run.rs"),
        module: vec!["mapping".into(), "run".into()],
        imports: Vec::new(),
        reexports: BTreeMap::new(),
    };
    let only_v = tests_file(vec![vec!["mapping".into(), "V".into()]]);
    assert!(circles_in(&[face, only_v, run]).is_empty());
    let face = SourceFile {
        file: PathBuf::from("mapping/mod.rs"),
        module: vec!["mapping".into()],
        imports: vec![vec!["mapping".into(), "tests".into(), "f".into()]],
        reexports: reexports_of("pub use run::{W, Y as V};"),
    };
    let with_z = tests_file(vec![vec!["mapping".into(), "Z".into()]]);
    assert_eq!(
        circles_in(&[face, with_z]),
        vec!["in mapping: mapping -> mapping::tests -> mapping"]
    );
    let lessons: BTreeSet<String> = ["mapping", "cartographer"].map(String::from).into();
    let c = SourceFile {
        file: PathBuf::from("c.rs"),
        module: vec!["cartographer".into()],
        imports: vec![vec!["mapping".into(), "run".into()], vec!["grid".into()]],
        reexports: BTreeMap::new(),
    };
    assert_eq!(lesson_crossings(&[c], &lessons).len(), 1);
    // A folder's face re-exporting its files is not an import.
    let face = imports_of(
        &vec!["mapping".into()],
        true,
        "pub use run::X;\npub use crate::grid::Y;\nuse crate::io::Z;",
    );
    assert_eq!(face, vec![vec!["io".to_owned(), "Z".into()]]);
}
