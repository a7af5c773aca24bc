//! Seeded mutation fuzzing of SLAM Lab's readers, in process and deterministic.
//!
//! Every reader a user can feed (map YAML, PGM and PNG images, g2o/TORO/iSAM pose
//! graphs, scenario JSON, URL query strings) is run on many mutated copies of real
//! files. For each input the harness checks three things:
//!
//! 1. **no panic** (in the browser a panic kills the tab);
//! 2. **no allocation beyond a stated cap**: the peak of the bytes the reading thread
//!    holds while it reads one input, counted by a per-thread counting allocator
//!    ([`allocation_counter`]), stays under [`Target::max_bytes`];
//! 3. **an error that names the problem**: a refused input returns a message of at
//!    least [`MIN_MESSAGE_CHARS`] characters (the reader's own check may demand more,
//!    e.g. a line number).
//!
//! The run is reproducible: input `i` of reader `name` comes from a ChaCha8 stream
//! seeded by the reader's name and [`seed`], so a failure report (reader, seed, input
//! index) replays exactly, and the failing input is written to the temporary directory.
//!
//! # How many inputs
//!
//! [`inputs_per_reader`]: 10,000 by default (what `./test.sh` runs), or
//! `SLAMLAB_FUZZ_INPUTS` (`scripts/fuzz.sh` runs 1,000,000 per reader in the release
//! profile). `SLAMLAB_FUZZ_SEED` changes the stream.
//!
//! # Adding a reader
//!
//! 1. In the crate that owns the reader, add `slamlab-fuzz` to `[dev-dependencies]`
//!    (`slamlab-fuzz.workspace = true`); slamlab-sim and slamlab-app already have it.
//! 2. Beside the other fuzz tests (slamlab-sim: `src/fuzz_tests.rs`; slamlab-app: the
//!    `tests` module of `src/query.rs`), write one `#[test]`:
//!
//!    ```ignore
//!    #[test]
//!    fn carmen_logs_survive_mutations() {
//!        let seeds = slamlab_fuzz::shared_file_seeds("laser", &["clf"], 4096);
//!        let report = slamlab_fuzz::Target::new("CARMEN log", seeds, 64 << 20)
//!            .run(|bytes| {
//!                let text = String::from_utf8_lossy(bytes);
//!                crate::laser_log::read_carmen(&text).map(drop).map_err(|e| e.to_string())
//!            });
//!        report.assert_clean();
//!    }
//!    ```
//!
//!    Seeds are real files cut to a few kilobytes (a mutation loop spends its time on
//!    the headers and the first records, where the parser's branches are; whole files
//!    would make 10,000 inputs slow). Compressed logs: seed with the decompressed text
//!    and fuzz the decompressor separately, or both through the one entry point.
//! 3. Add the test's name to `scripts/fuzz.sh` (its `--` filter list) and to the table
//!    of readers in `docs/robustness.md`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

/// Inputs per reader when `SLAMLAB_FUZZ_INPUTS` is not set (what CI runs).
pub const DEFAULT_INPUTS: usize = 10_000;

/// The shortest error message accepted as naming a problem.
pub const MIN_MESSAGE_CHARS: usize = 12;

/// Inputs per reader: `SLAMLAB_FUZZ_INPUTS`, or [`DEFAULT_INPUTS`].
pub fn inputs_per_reader() -> usize {
    std::env::var("SLAMLAB_FUZZ_INPUTS")
        .ok()
        .and_then(|v| v.trim().replace('_', "").parse().ok())
        .unwrap_or(DEFAULT_INPUTS)
}

/// The base seed: `SLAMLAB_FUZZ_SEED`, or 2026.
pub fn seed() -> u64 {
    std::env::var("SLAMLAB_FUZZ_SEED")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(2026)
}

/// The workspace's root (two levels above this crate).
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `../shared/data` beside the repository (where CI clones it), or the folder
/// `SLAMLAB_SHARED_DATA` names, if it is there.
pub fn shared_data() -> Option<PathBuf> {
    let dir = std::env::var_os("SLAMLAB_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("../shared/data"));
    dir.is_dir().then_some(dir)
}

/// The first `max_bytes` of every file under `shared/data/<folder>` (recursively)
/// whose name ends in one of `extensions`, cut at a line end when the file is text.
/// Empty, with a message on stderr, when the shared data is absent.
pub fn shared_file_seeds(folder: &str, extensions: &[&str], max_bytes: usize) -> Vec<Vec<u8>> {
    let Some(root) = shared_data() else {
        eprintln!(
            "slamlab-fuzz: ../shared/data is absent (or set SLAMLAB_SHARED_DATA); fuzzing '{folder}' with the built-in seeds only"
        );
        return Vec::new();
    };
    let mut files = Vec::new();
    collect_files(&root.join(folder), extensions, &mut files);
    files.sort();
    files
        .iter()
        .filter_map(|path| std::fs::read(path).ok())
        .map(|bytes| head(&bytes, max_bytes))
        .collect()
}

fn collect_files(dir: &std::path::Path, extensions: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect_files(&path, extensions, out);
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)))
        {
            out.push(path);
        }
    }
}

/// The first `max_bytes` of `bytes`, ending at the last newline within them if any.
pub fn head(bytes: &[u8], max_bytes: usize) -> Vec<u8> {
    if bytes.len() <= max_bytes {
        return bytes.to_vec();
    }
    let cut = &bytes[..max_bytes];
    match cut.iter().rposition(|&b| b == b'\n') {
        Some(end) if end > 0 => cut[..=end].to_vec(),
        _ => cut.to_vec(),
    }
}

/// Tokens that parsers treat specially, spliced into inputs by the mutator.
const TOKENS: &[&[u8]] = &[
    b"0",
    b"-1",
    b"1e308",
    b"-1e308",
    b"1e-320",
    b"nan",
    b"NaN",
    b".nan",
    b"inf",
    b"-inf",
    b".inf",
    b"18446744073709551616",
    b"4294967296",
    b"2147483648",
    b"65535",
    b"65536",
    b"100000",
    b"999999999",
    b"\n",
    b"\r\n",
    b"\t",
    b" ",
    b"#",
    b":",
    b": ",
    b"- ",
    b"[",
    b"]",
    b"{",
    b"}",
    b",",
    b"\"",
    b"'",
    b"&",
    b"=",
    b"%",
    b"%zz",
    b"%00",
    b"%FF",
    b"%C3%28",
    b"+",
    b"&a",
    b"*a",
    b"!!binary",
    b"---",
    b"...",
    b"\xff\xfe",
    b"\xc3\x28",
    b"\0",
    b"P5",
    b"P2",
    b"IHDR",
    b"IDAT",
    b"IEND",
    b"VERTEX_SE2",
    b"EDGE_SE2",
    b"VERTEX2",
    b"EDGE2",
    b"ODOMETRY",
    b"LANDMARK",
    b"EDGE_SE2_XY",
    b"VERTEX_XY",
    b"FIX",
];

/// Values that sit on a boundary of a byte, a 16-bit and a 32-bit integer.
const INTERESTING_BYTES: &[u8] = &[0, 1, 0x7f, 0x80, 0xff, b'0', b'9', b' ', b'\n'];

/// One mutated input: a copy of a seed with 1 to 8 random edits.
pub fn mutate(seeds: &[Vec<u8>], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut data = if seeds.is_empty() {
        Vec::new()
    } else {
        seeds[rng.random_range(0..seeds.len())].clone()
    };
    let edits = rng.random_range(1..=8);
    for _ in 0..edits {
        edit(&mut data, seeds, rng);
    }
    data
}

fn edit(data: &mut Vec<u8>, seeds: &[Vec<u8>], rng: &mut ChaCha8Rng) {
    let len = data.len();
    let at = |rng: &mut ChaCha8Rng| {
        if len == 0 {
            0
        } else {
            rng.random_range(0..len)
        }
    };
    match rng.random_range(0..11) {
        // Flip one bit.
        0 if len > 0 => {
            let i = at(rng);
            data[i] ^= 1 << rng.random_range(0..8);
        }
        // Set a byte to a boundary value or a random one.
        1 if len > 0 => {
            let i = at(rng);
            data[i] = if rng.random_bool(0.5) {
                INTERESTING_BYTES[rng.random_range(0..INTERESTING_BYTES.len())]
            } else {
                rng.random()
            };
        }
        // Insert a token.
        2 | 3 => {
            let i = if len == 0 {
                0
            } else {
                rng.random_range(0..=len)
            };
            let token = TOKENS[rng.random_range(0..TOKENS.len())];
            data.splice(i..i, token.iter().copied());
        }
        // Replace a number-like run (digits, '.', '-', 'e') with a token.
        4 if len > 0 => {
            let i = at(rng);
            let start = (0..=i)
                .rev()
                .take_while(|&k| is_numeric(data[k]))
                .last()
                .unwrap_or(i);
            let end = (i..len)
                .take_while(|&k| is_numeric(data[k]))
                .last()
                .map_or(i, |k| k + 1);
            let token = TOKENS[rng.random_range(0..TOKENS.len())];
            data.splice(start..end.max(start), token.iter().copied());
        }
        // Delete a range.
        5 if len > 0 => {
            let i = at(rng);
            let n = rng.random_range(1..=(len - i).min(64));
            data.drain(i..i + n);
        }
        // Duplicate a range (repeated lines, repeated chunks).
        6 if len > 0 => {
            let i = at(rng);
            let n = rng.random_range(1..=(len - i).min(256));
            let copy: Vec<u8> = data[i..i + n].to_vec();
            let j = rng.random_range(0..=len);
            data.splice(j..j, copy);
        }
        // Truncate.
        7 if len > 0 => {
            data.truncate(at(rng));
        }
        // Splice in a piece of another seed.
        8 if !seeds.is_empty() => {
            let other = &seeds[rng.random_range(0..seeds.len())];
            if !other.is_empty() {
                let i = rng.random_range(0..other.len());
                let n = rng.random_range(1..=(other.len() - i).min(512));
                let j = if len == 0 {
                    0
                } else {
                    rng.random_range(0..=len)
                };
                data.splice(j..j, other[i..i + n].iter().copied());
            }
        }
        // Random bytes.
        9 => {
            let n = rng.random_range(1..=16);
            let j = if len == 0 {
                0
            } else {
                rng.random_range(0..=len)
            };
            let bytes: Vec<u8> = (0..n).map(|_| rng.random()).collect();
            data.splice(j..j, bytes);
        }
        // Swap two bytes.
        _ if len > 1 => {
            let (i, j) = (at(rng), at(rng));
            data.swap(i, j);
        }
        _ => {}
    }
}

fn is_numeric(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E')
}

/// A reader to fuzz: its name, the real inputs the mutations start from, and the most
/// bytes it may hold while reading one input.
#[derive(Debug)]
pub struct Target {
    /// What is read, e.g. "map YAML" (names the failure reports).
    pub name: String,
    /// Real files (or pieces of them) the mutations start from.
    pub seeds: Vec<Vec<u8>>,
    /// The cap on the peak of bytes allocated by the reading thread for one input.
    pub max_bytes: u64,
    /// Inputs to try ([`inputs_per_reader`] unless changed).
    pub inputs: usize,
}

/// What a run found.
#[derive(Debug, Default)]
pub struct Report {
    /// The reader's name.
    pub name: String,
    /// Inputs tried.
    pub inputs: usize,
    /// Inputs the reader accepted.
    pub accepted: usize,
    /// Inputs refused with a message.
    pub refused: usize,
    /// The largest peak of allocated bytes over all inputs.
    pub peak_bytes: u64,
    /// Problems: panics, allocations over the cap, messages that say nothing.
    pub failures: Vec<String>,
    /// Seconds the run took.
    pub seconds: f64,
}

impl Report {
    /// Fails the test with every problem found, or prints the counts.
    #[allow(clippy::panic)] // a test's failure
    pub fn assert_clean(&self) {
        println!(
            "fuzz {}: {} inputs ({} accepted, {} refused) in {:.1} s; peak allocation {} bytes",
            self.name, self.inputs, self.accepted, self.refused, self.seconds, self.peak_bytes
        );
        if !self.failures.is_empty() {
            panic!(
                "fuzz {}: {} of {} inputs failed:\n{}",
                self.name,
                self.failures.len(),
                self.inputs,
                self.failures
                    .iter()
                    .take(10)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join("\n")
            );
        }
    }
}

impl Target {
    /// A target with [`inputs_per_reader`] inputs.
    pub fn new(name: &str, seeds: Vec<Vec<u8>>, max_bytes: u64) -> Self {
        Self {
            name: name.to_owned(),
            seeds,
            max_bytes,
            inputs: inputs_per_reader(),
        }
    }

    /// Runs the reader on the seeds themselves, then on [`Target::inputs`] mutated
    /// inputs. `read` returns `Err(message)` for a refused input; `check` may demand
    /// more of a message (`Err(why)` when it says too little).
    pub fn run_checked(
        &self,
        read: impl Fn(&[u8]) -> Result<(), String>,
        check: impl Fn(&str) -> Result<(), String>,
    ) -> Report {
        let started = std::time::Instant::now();
        let mut report = Report {
            name: self.name.clone(),
            ..Report::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed() ^ fnv1a(self.name.as_bytes()));
        let total = self.seeds.len() + self.inputs;
        for index in 0..total {
            let input = match self.seeds.get(index) {
                Some(seed) => seed.clone(),
                None => mutate(&self.seeds, &mut rng),
            };
            let mut outcome = None;
            let info = allocation_counter::measure(|| {
                outcome = Some(catch_unwind(AssertUnwindSafe(|| read(&input))));
            });
            report.inputs += 1;
            report.peak_bytes = report.peak_bytes.max(info.bytes_max);
            let problem = match outcome {
                Some(Ok(Ok(()))) => {
                    report.accepted += 1;
                    None
                }
                Some(Ok(Err(message))) => {
                    report.refused += 1;
                    if message.trim().chars().count() < MIN_MESSAGE_CHARS {
                        Some(format!("the error '{message}' does not name a problem"))
                    } else {
                        check(&message).err()
                    }
                }
                Some(Err(panic)) => Some(format!("panicked: {}", panic_text(&*panic))),
                None => Some("the reader did not run".to_owned()),
            };
            let problem = problem.or_else(|| {
                (info.bytes_max > self.max_bytes).then(|| {
                    format!(
                        "allocated {} bytes at once, more than the cap of {}",
                        info.bytes_max, self.max_bytes
                    )
                })
            });
            if let Some(problem) = problem {
                let file = self.save(index, &input);
                report.failures.push(format!(
                    "input {index} (seed {}, {} bytes, saved to {file}): {problem}",
                    seed(),
                    input.len()
                ));
            }
        }
        report.seconds = started.elapsed().as_secs_f64();
        report
    }

    /// [`Target::run_checked`] with no check beyond a message's length.
    pub fn run(&self, read: impl Fn(&[u8]) -> Result<(), String>) -> Report {
        self.run_checked(read, |_| Ok(()))
    }

    fn save(&self, index: usize, input: &[u8]) -> String {
        let slug: String = self
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect();
        let path = std::env::temp_dir().join(format!("slamlab-fuzz-{slug}-{index}.bin"));
        match std::fs::write(&path, input) {
            Ok(()) => path.display().to_string(),
            Err(e) => format!("(not saved: {e})"),
        }
    }
}

fn panic_text(panic: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".to_owned()
    }
}

/// FNV-1a, to turn a reader's name into a seed.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_inputs_and_edits_change_them() {
        let seeds = vec![b"image: a.pgm\nresolution: 0.05\n".to_vec()];
        let mut a = ChaCha8Rng::seed_from_u64(7);
        let mut b = ChaCha8Rng::seed_from_u64(7);
        let xs: Vec<Vec<u8>> = (0..200).map(|_| mutate(&seeds, &mut a)).collect();
        let ys: Vec<Vec<u8>> = (0..200).map(|_| mutate(&seeds, &mut b)).collect();
        assert_eq!(xs, ys);
        let changed = xs.iter().filter(|x| **x != seeds[0]).count();
        assert!(
            changed >= 190,
            "{changed} of 200 inputs differ from the seed"
        );
        let lengths: std::collections::BTreeSet<usize> = xs.iter().map(Vec::len).collect();
        assert!(
            lengths.len() > 20,
            "only {} distinct lengths",
            lengths.len()
        );
    }

    #[test]
    fn the_harness_catches_a_panic_a_large_allocation_and_a_mute_error() {
        let seeds = vec![b"12345".to_vec()];
        let target = Target {
            inputs: 300,
            ..Target::new("harness self-test", seeds, 1 << 20)
        };
        #[allow(clippy::panic)]
        let report = target.run(|bytes| match bytes.first() {
            Some(b'1') => Ok(()),
            Some(b'0') => panic!("a zero"),
            Some(b'9') => {
                let big = vec![0u8; 4 << 20];
                std::hint::black_box(&big);
                Ok(())
            }
            _ => Err("bad".to_owned()),
        });
        assert_eq!(report.inputs, 301);
        let has = |needle: &str| report.failures.iter().any(|f| f.contains(needle));
        assert!(has("panicked: a zero"), "{:?}", report.failures);
        assert!(has("more than the cap"), "{:?}", report.failures);
        assert!(has("does not name a problem"), "{:?}", report.failures);
        assert!(report.peak_bytes >= 4 << 20);
        assert!(report.accepted > 0);
    }
}
