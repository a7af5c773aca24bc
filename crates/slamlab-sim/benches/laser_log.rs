//! Laser log reading speed: `cargo bench -p slamlab-sim --bench laser_log`.
//!
//! The Intel Research Lab log (`../shared/data/laser/intel.clf.bz2` beside
//! the repository, or in `$SLAMLAB_SHARED`; 2.3 MB bzip2, 16.4 MB and 13,631 scans unpacked): the whole
//! read (bzip2 and parse), and parsing the unpacked text alone. Skipped with a
//! message when the file is absent.

#![allow(clippy::panic)] // a benchmark whose input does not read cannot run

mod common;

use slamlab_sim::io::laser_log::LaserLog;
use std::io::Read;

fn main() {
    divan::main();
}

fn intel_bytes() -> Option<Vec<u8>> {
    let path = common::intel_log_path();
    match std::fs::read(&path) {
        Ok(bytes) => Some(bytes),
        Err(e) => {
            eprintln!("skipped: the Intel log is not at {} ({e})", path.display());
            None
        }
    }
}

/// bzip2-decompressing and parsing the whole Intel log.
#[divan::bench(sample_count = 5)]
fn read_intel_log_bzip2(bencher: divan::Bencher) {
    let Some(bytes) = intel_bytes() else { return };
    bencher.bench_local(|| {
        let log = LaserLog::from_bytes(divan::black_box(&bytes)).unwrap_or_else(|e| panic!("{e}"));
        divan::black_box(log.scans.len())
    });
}

/// Parsing the unpacked Intel log (no decompression).
#[divan::bench(sample_count = 5)]
fn parse_intel_log_plain(bencher: divan::Bencher) {
    let Some(bytes) = intel_bytes() else { return };
    let mut plain = Vec::new();
    bzip2::read::MultiBzDecoder::new(bytes.as_slice())
        .read_to_end(&mut plain)
        .unwrap_or_else(|e| panic!("{e}"));
    bencher.bench_local(|| {
        let log = LaserLog::from_bytes(divan::black_box(&plain)).unwrap_or_else(|e| panic!("{e}"));
        divan::black_box(log.scans.len())
    });
}
