//! Fuzz tests of every reader in this crate a user can feed: ROS map YAML, PGM and
//! PNG images, g2o/TORO/iSAM pose graphs, scenario JSON and CARMEN laser logs (plain,
//! gzip and bzip2) with their corrected versions (reference trajectories), ROS 2
//! bags (MCAP) and the ROS 2 messages in them (CDR), and maps handed in as a zip. Each runs
//! [`slamlab_fuzz::inputs_per_reader`] mutated inputs (10,000 in `./test.sh`,
//! 1,000,000 in `scripts/fuzz.sh`) from real files: the shared data sets
//! (`../shared/data`, when present) and the built-in maps. See the `slamlab-fuzz`
//! crate for what is checked and how to add a reader.

use crate::io;
use crate::io::graph::GraphFormat;
use crate::io::ros_map::ImageFormat;
use crate::io::scenario_file::ScenarioFile;
use slamlab_core::Pose2;
use slamlab_core::graph::PoseGraph;
use slamlab_core::grid::{Cell, OccupancyGrid};
use slamlab_fuzz::{Target, head, shared_file_seeds, workspace_root};

/// A reader's cap on the bytes it holds at once while reading one input. The map
/// readers may build a grid of up to `MAX_CELLS` cells, but the seeds are small and a
/// mutation can only claim a large size in a header, which is refused before any
/// allocation: 64 MiB is far above any honest input here.
const CAP: u64 = 64 << 20;

fn asset(name: &str) -> Vec<u8> {
    std::fs::read(workspace_root().join("assets/maps").join(name)).unwrap_or_default()
}

/// Real maps, cut to a 48 x 48 window (a mutation loop on a 300 kB image spends its
/// time copying pixels, not in the decoder's branches), in both image formats.
fn image_seeds() -> Vec<Vec<u8>> {
    let mut seeds = vec![asset("maze.png"), asset("office.png")];
    let mut grids = Vec::new();
    for bytes in shared_file_seeds("maps", &["pgm", "png"], usize::MAX) {
        if let Ok(image) = io::ros_map::decode_image(&bytes) {
            let yaml = io::ros_map::MapYaml {
                resolution: 0.05,
                ..io::ros_map::MapYaml::default()
            };
            if let Ok(grid) = io::ros_map::grid_from_image(&image, &yaml) {
                grids.push(crop(&grid, 48));
            }
        }
    }
    for grid in grids.iter().flatten() {
        for format in [ImageFormat::Pgm, ImageFormat::Png] {
            if let Ok(bytes) = io::ros_map::encode_image(grid, format) {
                seeds.push(bytes);
            }
        }
    }
    // An ASCII PGM and a 16-bit one (map_server reads both).
    seeds.push(
        b"P2\n# a small map\n4 3\n255\n255 0 255 255\n255 255 205 255\n254 254 254 0\n".to_vec(),
    );
    let mut p5 = b"P5 3 2 65535\n".to_vec();
    for v in [0u16, 65535, 52000, 65535, 0, 65535] {
        p5.extend_from_slice(&v.to_be_bytes());
    }
    seeds.push(p5);
    seeds.retain(|s| !s.is_empty());
    seeds
}

fn crop(grid: &OccupancyGrid, side: usize) -> Option<OccupancyGrid> {
    let (w, h) = (grid.width().min(side), grid.height().min(side));
    let (x0, y0) = ((grid.width() - w) / 2, (grid.height() - h) / 2);
    let cells: Vec<Cell> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            grid.get((x0 + i) as i64, (y0 + j) as i64)
                .unwrap_or(Cell::Unknown)
        })
        .collect();
    OccupancyGrid::new(w, h, grid.resolution(), Pose2::new(0.0, 0.0, 0.0), cells).ok()
}

#[test]
fn map_yaml_survives_mutations() {
    let mut seeds = vec![asset("maze.yaml"), asset("office.yaml")];
    seeds.extend(shared_file_seeds("maps", &["yaml"], 4096));
    seeds.push(
        b"# every key map_server reads\nimage: \"a b.pgm\"\nresolution: 0.05\norigin:\n  - -12.5\n  - 3\n  - 0.0\nnegate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: scale\n"
            .to_vec(),
    );
    seeds.retain(|s| !s.is_empty());
    let report = Target::new("map YAML", seeds, CAP).run_checked(
        |bytes| {
            io::ros_map::parse_map_yaml(&String::from_utf8_lossy(bytes))
                .map(drop)
                .map_err(|e| e.to_string())
        },
        // Syntax errors and bad values say which line.
        |message| {
            let names_line = message.contains("line ");
            let whole_file = message.contains("has no `")
                || message.contains("thresh")
                || message.contains("resolution")
                || message.contains("origin");
            if names_line || whole_file {
                Ok(())
            } else {
                Err(format!("'{message}' names neither a line nor a key"))
            }
        },
    );
    report.assert_clean();
}

#[test]
fn map_images_survive_mutations() {
    let seeds = image_seeds();
    assert!(seeds.len() >= 4, "only {} image seeds", seeds.len());
    let report = Target::new("map image (PGM/PNG)", seeds, CAP).run_checked(
        |bytes| {
            io::ros_map::decode_image(bytes)
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            if ["PGM", "PNG", "image", "map", "cells"]
                .iter()
                .any(|w| message.contains(w))
            {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' does not say which image or what is wrong"
                ))
            }
        },
    );
    report.assert_clean();
}

#[test]
fn map_files_survive_mutations_together() {
    // YAML and image through `load_map`, the app's and the CLI's entry point: the
    // thresholds and modes of the YAML meet every pixel value.
    let yaml = "image: m.png\nresolution: 0.1\norigin: [-2, -3, 0.5]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
    let mut seeds: Vec<Vec<u8>> = image_seeds()
        .into_iter()
        .map(|image| {
            let mut s = yaml.as_bytes().to_vec();
            s.extend_from_slice(b"\0");
            s.extend_from_slice(&image);
            s
        })
        .collect();
    seeds.truncate(6);
    let report = Target::new("map YAML + image", seeds, CAP).run(|bytes| {
        let split = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
        let (text, image) = bytes.split_at(split);
        let image = image.get(1..).unwrap_or(&[]);
        io::ros_map::load_map(&String::from_utf8_lossy(text), image)
            .map(drop)
            .map_err(|e| e.to_string())
    });
    report.assert_clean();
}

/// Pieces of the real files under `shared/data/posegraphs` with one of `extensions`:
/// the first 4 kB and, to reach the loop closures, 4 kB from the middle.
#[test]
fn zipped_maps_survive_mutations() {
    // A handed-in or dropped map: YAML and image in one zip
    // (`io::map_archive::read_map_zip`): the archive's headers, the YAML that
    // names the image, the image.
    let mut seeds = Vec::new();
    for (k, image) in image_seeds().into_iter().take(6).enumerate() {
        let name = if image.starts_with(b"\x89PNG") {
            "m.png"
        } else {
            "m.pgm"
        };
        let yaml = format!(
            "image: {name}\nresolution: 0.1\norigin: [-2, -3, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
        );
        let files = [
            (format!("map{k}.yaml"), yaml.into_bytes()),
            (name.to_owned(), image),
        ];
        if let Ok(zip) = io::archive::write_zip("hand-in", &files) {
            seeds.push(zip);
        }
    }
    assert!(seeds.len() >= 4, "only {} zip seeds", seeds.len());
    let report = Target::new("map zip (YAML + image)", seeds, CAP).run_checked(
        |bytes| io::map_archive::read_map_zip("map.zip", bytes).map(drop),
        |message| {
            if message.starts_with("map.zip") {
                Ok(())
            } else {
                Err(format!("'{message}' does not name the file"))
            }
        },
    );
    report.assert_clean();
}

fn graph_pieces(extensions: &[&str]) -> Vec<Vec<u8>> {
    let mut pieces = Vec::new();
    for bytes in shared_file_seeds("posegraphs", extensions, usize::MAX) {
        pieces.push(head(&bytes, 4096));
        let middle = bytes.len() / 2;
        let from = bytes[middle..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(middle, |k| middle + k + 1);
        pieces.push(head(&bytes[from..], 4096));
    }
    pieces
}

const SMALL_G2O: &[u8] = b"VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.1\nVERTEX_SE2 2 1 1 1.6\nVERTEX_XY 7 2 2\nEDGE_SE2 0 1 1 0 0.1 500 0 0 500 0 2000\nEDGE_SE2 1 2 0 1 1.5 500 0 0 500 0 2000\nEDGE_SE2 2 0 -1 1 -1.6 500 0 0 500 0 2000\nEDGE_SE2_XY 2 7 1 1 100 0 100\nFIX 0\n";

/// A g2o text as TORO: `VERTEX2`, and `EDGE2` with the information matrix's entries
/// in TORO's order (xx xy yy tt xt yt; g2o writes xx xy xt yy yt tt).
fn g2o_as_toro(text: &[u8]) -> Vec<u8> {
    let mut out = String::new();
    for line in String::from_utf8_lossy(text).lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["VERTEX_SE2", rest @ ..] => out.push_str(&format!("VERTEX2 {}\n", rest.join(" "))),
            ["EDGE_SE2", a, b, x, y, t, i11, i12, i13, i22, i23, i33] => out.push_str(&format!(
                "EDGE2 {a} {b} {x} {y} {t} {i11} {i12} {i22} {i33} {i13} {i23}\n"
            )),
            _ => {}
        }
    }
    out.into_bytes()
}

fn graph_seeds(format: GraphFormat) -> Vec<Vec<u8>> {
    let mut g2o = graph_pieces(&["g2o"]);
    g2o.push(SMALL_G2O.to_vec());
    match format {
        GraphFormat::G2o => g2o,
        GraphFormat::Toro => g2o.iter().map(|t| g2o_as_toro(t)).collect(),
        GraphFormat::Isam => {
            // victoria_park.txt is iSAM's format.
            let mut seeds = graph_pieces(&["txt"]);
            seeds.push(
                b"ODOMETRY 1 0 1 0 0.1 100 0 0 100 0 1000\nODOMETRY 2 1 1 0 0.1 100 0 0 100 0 1000\nLANDMARK 2 0 3 1 10 0 10\nLANDMARK 1 0 2 2 10 0 10\n"
                    .to_vec(),
            );
            seeds
        }
    }
}

fn fuzz_graph(
    name: &str,
    format: GraphFormat,
    read: fn(&str) -> Result<PoseGraph, io::graph::GraphFileError>,
) {
    let seeds = graph_seeds(format);
    assert!(!seeds.is_empty(), "no {name} seeds");
    let report = Target::new(name, seeds, CAP).run_checked(
        |bytes| {
            read(&String::from_utf8_lossy(bytes))
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            if message.contains("line ")
                || message.contains("pose-graph file")
                || message.contains("bytes")
                || message.contains("vert")
                || message.contains("edge")
            {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' names neither a line nor what is missing"
                ))
            }
        },
    );
    report.assert_clean();
}

#[test]
fn g2o_graphs_survive_mutations() {
    fuzz_graph("g2o graph", GraphFormat::G2o, io::graph::read_g2o);
}

#[test]
fn toro_graphs_survive_mutations() {
    fuzz_graph("TORO graph", GraphFormat::Toro, io::graph::read_toro);
}

#[test]
fn isam_graphs_survive_mutations() {
    fuzz_graph("iSAM graph", GraphFormat::Isam, io::graph::read_isam);
}

#[test]
fn any_graph_file_survives_mutations() {
    // `read_graph` tells the formats apart: a g2o line in a TORO file and so on.
    let mut seeds = graph_seeds(GraphFormat::G2o);
    seeds.truncate(4);
    seeds.extend(graph_seeds(GraphFormat::Toro).into_iter().take(3));
    seeds.extend(graph_seeds(GraphFormat::Isam).into_iter().take(3));
    fuzz_graph_any(seeds);
}

fn fuzz_graph_any(seeds: Vec<Vec<u8>>) {
    let report = Target::new("pose-graph file (any format)", seeds, CAP).run(|bytes| {
        io::graph::read_graph(&String::from_utf8_lossy(bytes))
            .map(drop)
            .map_err(|e| e.to_string())
    });
    report.assert_clean();
}

#[test]
fn scenario_files_survive_mutations() {
    let seeds: Vec<Vec<u8>> = [
        ScenarioFile {
            lesson: "kidnap".into(),
            params: vec![
                ("map".into(), "maze".into()),
                ("particles".into(), "1000".into()),
                ("estimator".into(), "amcl,acmcl".into()),
            ],
            view: vec![("tick".into(), "30".into()), ("legend".into(), "0".into())],
        },
        ScenarioFile {
            lesson: "landmark-slam".into(),
            params: vec![("seed".into(), "7".into()), ("fov-deg".into(), "90".into())],
            view: Vec::new(),
        },
    ]
    .iter()
    .map(|f| f.to_json().into_bytes())
    .chain([
        br#"{"format": "slamlab-scenario", "version": 1, "lesson": "pose-graph", "params": {"noise": 0.1, "closures": true, "kernel": null}}"#.to_vec(),
    ])
    .collect();
    let report = Target::new("scenario JSON", seeds, CAP).run_checked(
        |bytes| ScenarioFile::parse(&String::from_utf8_lossy(bytes)).map(drop),
        |message| {
            if message.contains("scenario") || message.contains('"') {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' does not say what is wrong with the scenario"
                ))
            }
        },
    );
    report.assert_clean();
}

/// CARMEN laser logs through the one entry point the app and the CLI use
/// ([`LaserLog::from_bytes_with_limits`]: size cap, compression detected from the
/// bytes, then the parser). Seeds: a hand-made file with every record type the reader
/// knows and some it skips, a simulated log written by [`write_carmen`], the head of
/// the Intel log (when `../shared` is present), and gzip and bzip2 copies of the small
/// ones, so mutations also hit the decompressors' headers and streams.
#[test]
fn carmen_logs_survive_mutations() {
    use crate::grid::{SimulatedLogConfig, simulate_log};
    use crate::io::laser_log::{LaserLog, LogLimits, write_carmen};
    use std::io::{Read as _, Write as _};
    let mut text_seeds: Vec<Vec<u8>> = vec![
        b"PARAM robot_frontlaser_offset 0.0 nohost 0
PARAM laser_front_laser_resolution 1.0 nohost 0
ODOM 0.0 0.0 -0.002 0.0 0.0 0.0 100.0 nohost 0.0
FLASER 4 1.07 2.5 81.83 0.50 0.1 0.2 0.3 0.1 0.2 0.3 100.1 nohost 0.1
RLASER 2 3.0 4.0 1.0 2.0 3.1 0.0 0.0 3.0 100.15 nohost 0.15
SYNC tag 100.2 nohost 0.2
ROBOTLASER1 0 -1.5 3.0 0.5 30.0 0.01 0 7 1 2 3 4 5 6 7 2 0.9 0.8 5.1 5.2 0.1 5.0 5.0 0.1 0.2 0.3 0.4 0.5 0 100.5 nohost 0.5
NMEA-GGA 1 2 3 100.7 nohost 0.7
"
        .to_vec(),
    ];
    if let Ok(map) = crate::grid::BuiltinMap::Maze.load() {
        let config = SimulatedLogConfig {
            lidar: crate::grid::lidar::Lidar {
                beams: 24,
                ..SimulatedLogConfig::default().lidar
            },
            ..SimulatedLogConfig::default()
        };
        if let Ok((log, _)) = simulate_log(&map, 6, 1, &config)
            && let Ok(text) = write_carmen(&log)
        {
            text_seeds.push(text.into_bytes());
        }
    }
    // The Intel log is bzip2-compressed: the head of its text is the seed.
    for bytes in shared_file_seeds("laser", &["bz2", "gz", "clf", "log"], usize::MAX) {
        let mut text = Vec::new();
        let unpacked = if bytes.starts_with(b"BZh") {
            bzip2::read::MultiBzDecoder::new(&bytes[..])
                .take(64 << 10)
                .read_to_end(&mut text)
        } else if bytes.starts_with(&[0x1f, 0x8b]) {
            flate2::read::MultiGzDecoder::new(&bytes[..])
                .take(64 << 10)
                .read_to_end(&mut text)
        } else {
            text.extend_from_slice(&bytes[..bytes.len().min(64 << 10)]);
            Ok(text.len())
        };
        if unpacked.is_ok() {
            text_seeds.push(head(&text, 4096));
        }
    }
    let mut seeds = text_seeds.clone();
    for text in text_seeds.iter().take(2) {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        let mut bz = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
        if gz.write_all(text).is_ok()
            && bz.write_all(text).is_ok()
            && let (Ok(gz), Ok(bz)) = (gz.finish(), bz.finish())
        {
            seeds.push(gz);
            seeds.push(bz);
        }
    }
    // Caps far below the defaults: a mutated gzip header may claim anything, and the
    // unpacked-size cap must stop it before it allocates.
    let limits = LogLimits {
        max_input_bytes: 1 << 20,
        max_unpacked_bytes: 8 << 20,
    };
    let report = Target::new("CARMEN log", seeds, CAP).run_checked(
        |bytes| {
            LaserLog::from_bytes_with_limits(bytes, limits)
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            let names_place = message.contains("line")
                || message.contains("laser")
                || message.contains("compress")
                || message.contains("gzip")
                || message.contains("bzip2")
                || message.contains("beam")
                || message.contains("log");
            if names_place {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' does not say what is wrong with the log"
                ))
            }
        },
    );
    report.assert_clean();
}

/// Seeds for the bag reader: bags written by rosbags (little- and big-endian
/// CDR, zstd chunks; `tests/data/ros2_bags`), a simulated run written by
/// SLAM Lab (uncompressed chunks, a summary, the truth topic), and hand-made
/// files (chunks in zstd, lz4 and none, unchunked, without a summary, an
/// unknown type), each a few kilobytes.
fn bag_seeds() -> Vec<Vec<u8>> {
    use crate::io::ros2_bag::tests::{Layout, TestChannel, hand_made_mcap, rosbags_seed};
    use crate::io::ros2_bag::{BagWriteOptions, msgs, write_bag};
    let mut seeds = vec![
        rosbags_seed("rosbags-intel-3-scans.mcap"),
        rosbags_seed("rosbags-intel-3-scans-big-endian.mcap"),
    ];
    if let Ok(map) = crate::grid::BuiltinMap::Maze.load() {
        let config = crate::grid::SimulatedLogConfig {
            lidar: crate::grid::lidar::Lidar {
                beams: 24,
                ..crate::grid::SimulatedLogConfig::default().lidar
            },
            ..crate::grid::SimulatedLogConfig::default()
        };
        if let Ok((log, truth)) = crate::grid::simulate_log(&map, 4, 1, &config)
            && let Ok(bytes) = write_bag(&log, Some(&truth), &BagWriteOptions::default())
        {
            seeds.push(bytes);
        }
    }
    let scan = |t: i64| msgs::LaserScan {
        header: msgs::Header {
            stamp: msgs::Time::from_nanos(t),
            frame_id: "laser".to_owned(),
        },
        angle_min: -1.0,
        angle_max: 1.0,
        angle_increment: 0.5,
        range_min: 0.1,
        range_max: 8.0,
        ranges: vec![1.0, 2.0, f32::INFINITY, f32::NAN, 3.0],
        ..msgs::LaserScan::default()
    };
    let odom = |t: i64, x: f64| msgs::Odometry {
        header: msgs::Header {
            stamp: msgs::Time::from_nanos(t),
            frame_id: "odom".to_owned(),
        },
        child_frame_id: "base_link".to_owned(),
        pose: msgs::Transform3::from_pose2(Pose2::new(x, 0.0, 0.1)),
        ..msgs::Odometry::default()
    };
    let channels = vec![
        TestChannel::cdr(
            "/scan",
            msgs::LASER_SCAN,
            vec![(15, scan(15).encode()), (25, scan(25).encode())],
        ),
        TestChannel::cdr(
            "/odom",
            msgs::ODOMETRY,
            (1..4)
                .map(|k| (k * 10, odom(k as i64 * 10, k as f64).encode()))
                .collect(),
        ),
        TestChannel::cdr(
            "/image",
            "sensor_msgs/msg/Image",
            vec![(20, vec![0, 1, 0, 0, 7])],
        ),
    ];
    for (layout, summary) in [
        (Layout::Unchunked, false),
        (Layout::Chunked("zstd"), true),
        (Layout::Chunked("lz4"), false),
        (Layout::Chunked(""), true),
    ] {
        seeds.push(hand_made_mcap(&channels, layout, summary));
    }
    seeds
}

/// ROS 2 bags through the one entry point the app and the CLI use
/// ([`LaserFile::from_bytes_with_limits`](crate::grid::LaserFile): MCAP
/// records, chunks unpacked, messages decoded from CDR, topics chosen, scans
/// posed), with caps far below the defaults so that a chunk header claiming
/// gigabytes is refused before anything is allocated.
#[test]
fn ros2_bags_survive_mutations() {
    use crate::grid::LaserFile;
    use crate::io::ros2_bag::{BagLimits, TopicChoice};
    let limits = BagLimits {
        max_input_bytes: 1 << 20,
        max_chunk_bytes: 8 << 20,
        max_unpacked_bytes: 16 << 20,
    };
    let report = Target::new("ROS 2 bag (MCAP)", bag_seeds(), CAP).run_checked(
        |bytes| {
            LaserFile::from_bytes_with_limits("fuzz.mcap", bytes, &TopicChoice::default(), &limits)
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            let names_place = [
                "bag",
                "MCAP",
                "chunk",
                "message",
                "topic",
                "scan",
                "laser",
                "odometry",
                "line",
                "log",
                "compress",
                "transform",
            ]
            .iter()
            .any(|w| message.contains(w));
            if names_place {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' does not say what is wrong with the bag"
                ))
            }
        },
    );
    report.assert_clean();
}

/// The CDR decoder alone, on serialized LaserScan, Odometry, TFMessage and
/// PoseStamped messages in both byte orders: every length field is checked
/// against the bytes that remain before anything is allocated.
#[test]
fn ros2_messages_survive_mutations() {
    use crate::io::ros2_bag::msgs::{LaserScan, Odometry, PoseStamped, TfMessage};
    use crate::io::ros2_bag::{Ros2Bag, TopicChoice};
    let mut seeds = Vec::new();
    for bag in bag_seeds().iter().take(3) {
        let Ok(bag) = Ros2Bag::from_bytes(bag) else {
            continue;
        };
        let _ = bag.laser_log(&TopicChoice::default());
        // Each seed starts with a byte naming its type (0 LaserScan, 1 Odometry,
        // 2 TFMessage, 3 PoseStamped), so that one target decodes all four.
        for s in bag.scans.values().flatten().take(2) {
            let mut bytes = s.message.encode();
            bytes.insert(0, 0);
            seeds.push(bytes);
        }
        for o in bag.odometry.values().flatten().take(1) {
            let mut bytes = o.message.encode();
            bytes.insert(0, 1);
            seeds.push(bytes);
        }
        for p in bag.poses.values().flatten().take(1) {
            let mut bytes = p.message.encode();
            bytes.insert(0, 3);
            seeds.push(bytes);
        }
        let tf = TfMessage {
            transforms: bag
                .transforms
                .iter()
                .take(2)
                .map(|t| t.transform.clone())
                .collect(),
        };
        let mut bytes = tf.encode();
        bytes.insert(0, 2);
        seeds.push(bytes);
    }
    // Big-endian LaserScans, assembled by hand.
    for ranges in [&[1.0f32, 2.5][..], &[f32::INFINITY, 0.5, 3.0, 4.0]] {
        let mut bytes = crate::io::ros2_bag::tests::hand_laser_scan(true, "base_scan", ranges);
        bytes.insert(0, 0);
        seeds.push(bytes);
    }
    assert!(seeds.len() >= 8, "only {} message seeds", seeds.len());
    let report = Target::new("ROS 2 message (CDR)", seeds, CAP).run(|bytes| {
        let Some((&kind, body)) = bytes.split_first() else {
            return Err("an empty input: no message type".to_owned());
        };
        match kind % 4 {
            0 => LaserScan::decode(body).map(drop),
            1 => Odometry::decode(body).map(drop),
            2 => TfMessage::decode(body).map(drop),
            _ => PoseStamped::decode(body).map(drop),
        }
        .map_err(|e| e.to_string())
    });
    report.assert_clean();
}

/// Trajectory files (TUM and CSV, with and without covariances) and landmark CSVs,
/// through the readers a dropped estimate and `slamlab evaluate` use: every
/// refusal names a line or says what the file is instead.
#[test]
fn trajectory_files_survive_mutations() {
    use crate::io::trajectory::{
        LandmarkRow, read_landmarks, read_trajectory, write_csv, write_landmarks, write_tum,
    };
    use crate::metrics::Trajectory;
    use nalgebra::{Matrix2, Matrix3};
    let stamps: Vec<f64> = (0..12).map(|k| 0.1 * f64::from(k)).collect();
    let poses: Vec<Pose2> = (0..12)
        .map(|k| {
            let t = f64::from(k);
            Pose2::new(0.5 * t, 0.1 * t * t, 0.05 * t - 0.3)
        })
        .collect();
    let plain = Trajectory::new(stamps, poses);
    let with_cov = plain.clone().with_covariances(
        (0..12)
            .map(|k| {
                Matrix3::new(
                    0.01,
                    1e-4,
                    0.0,
                    1e-4,
                    0.02,
                    0.0,
                    0.0,
                    0.0,
                    1e-3 * f64::from(k + 1),
                )
            })
            .collect(),
    );
    let landmarks = write_landmarks(&[
        LandmarkRow {
            id: 1,
            x: 2.0,
            y: -1.5,
            covariance: Some(Matrix2::new(0.1, 0.0, 0.0, 0.2)),
        },
        LandmarkRow {
            id: 4,
            x: 0.25,
            y: 3.0,
            covariance: Some(Matrix2::new(0.3, 0.01, 0.01, 0.1)),
        },
    ]);
    let seeds: Vec<Vec<u8>> = vec![
        write_tum(&plain).into_bytes(),
        write_csv(&plain).into_bytes(),
        write_csv(&with_cov).into_bytes(),
        b"yaw,time,y,x\n0.5,0,2,1\n0.6,0.1,2.1,1.1\n".to_vec(),
        b"# t x y z qx qy qz qw\n1.0 2 3 0.5 0.1 0.2 0.3 0.9\n1.1 2 3 0.5 0.1 0.2 0.3 0.9\n"
            .to_vec(),
    ];
    let line_or_what = |message: &str| {
        if message.starts_with("line ") || message.contains("file") {
            Ok(())
        } else {
            Err(format!(
                "'{message}' names neither a line nor what the file is"
            ))
        }
    };
    let report = Target::new("trajectory file (TUM or CSV)", seeds, CAP).run_checked(
        |bytes| {
            read_trajectory("fuzz", bytes)
                .map(drop)
                .map_err(|e| e.to_string())
        },
        line_or_what,
    );
    report.assert_clean();
    let seeds = vec![
        landmarks.into_bytes(),
        b"1,2,3\n2,4,5\n".to_vec(),
        b"id,x,y\n7,1e3,-2\n".to_vec(),
    ];
    let report = Target::new("landmark CSV", seeds, CAP).run_checked(
        |bytes| read_landmarks(bytes).map(drop).map_err(|e| e.to_string()),
        line_or_what,
    );
    report.assert_clean();
    // A relative pose of two views: R and t, or t and a quaternion.
    let seeds = vec![
        crate::io::relative_pose::write_relative_pose(&slamlab_core::vision::RelativePose {
            rotation: nalgebra::Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner(),
            translation: nalgebra::Vector3::new(0.2, -0.1, 1.0),
        })
        .into_bytes(),
        b"0.1, 0, 1, 0, 0.0499792, 0, 0.99875\n".to_vec(),
    ];
    let report = Target::new("relative pose", seeds, CAP).run_checked(
        |bytes| {
            crate::io::relative_pose::read_relative_pose(bytes)
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            // A refusal names the line, the count, what is wrong with R, q or t, or
            // what the file is.
            if ["line ", "numbers", "R is", "quaternion", "t is", "file"]
                .iter()
                .any(|w| message.contains(w))
            {
                Ok(())
            } else {
                Err(format!("'{message}' says nothing of what is wrong"))
            }
        },
    );
    report.assert_clean();
}

/// Assignment JSON files through the reader the app and the command line use
/// ([`crate::assignments::read`]: size cap, serde, then the checks against the
/// lesson's task kind and parameter table). Seeds: the built-in assignments.
#[test]
fn assignment_files_survive_mutations() {
    let seeds: Vec<Vec<u8>> = crate::coursework::BUILTIN
        .iter()
        .map(|(_, text)| text.as_bytes().to_vec())
        .collect();
    let report = Target::new("assignment JSON", seeds, CAP).run_checked(
        |bytes| {
            crate::assignments::read("fuzz.json", bytes)
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            if message.starts_with("fuzz.json: ") {
                Ok(())
            } else {
                Err(format!("'{message}' does not name the assignment file"))
            }
        },
    );
    report.assert_clean();
}

/// Corrected CARMEN logs (the reference trajectories of laser logs) through
/// the path the lessons and `slamlab experiment laser-slam` take: read, then
/// matched to a raw log's scans by time and ranges
/// ([`crate::grid::MappingInput::reference_from`]). Seeds: a small
/// reference of a small raw log (its scans 1, 3 and 7, one of them matching),
/// the same gzip-compressed, and the head of the Intel log's corrected version.
#[test]
fn corrected_logs_survive_mutations() {
    use crate::grid::log_input;
    use crate::io::laser_log::LaserLog;
    use std::io::{Read as _, Write as _};
    let flaser = |ranges: &[f64], time: f64| -> String {
        let r: Vec<String> = ranges.iter().map(|v| v.to_string()).collect();
        format!(
            "FLASER {} {} 0.5 0.25 0.1 0.5 0.25 0.1 {time} pippo {time}\n",
            ranges.len(),
            r.join(" ")
        )
    };
    let mut raw = String::new();
    for k in 0..10 {
        let base = k as f64;
        raw += &flaser(&[base, base + 1.0, base + 2.0], 1000.0 + 0.2 * k as f64);
    }
    let input = LaserLog::from_bytes(raw.as_bytes())
        .map(|log| log_input(&log, "raw"))
        .unwrap_or_default();
    let mut reference = String::from("# corrected\nODOM 0 0 0 0 0 0 0.0 pippo 0.0\n");
    reference += &flaser(&[1.0, 2.0, 3.0], 0.203);
    reference += &flaser(&[3.0, 4.0, 5.0], 0.598);
    reference += &flaser(&[7.0, 8.0, 9.0], 1.404);
    reference += "NEFF 30 0.0 pippo 0.0\n";
    let mut seeds = vec![reference.clone().into_bytes()];
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    if gz.write_all(reference.as_bytes()).is_ok()
        && let Ok(bytes) = gz.finish()
    {
        seeds.push(bytes);
    }
    for bytes in shared_file_seeds("laser", &["gz"], usize::MAX) {
        let mut text = Vec::new();
        if flate2::read::MultiGzDecoder::new(&bytes[..])
            .take(64 << 10)
            .read_to_end(&mut text)
            .is_ok()
        {
            seeds.push(head(&text, 4096));
        }
    }
    let report = Target::new("corrected CARMEN log", seeds, CAP).run_checked(
        |bytes| {
            input
                .reference_from(bytes, "fuzz")
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            if message.contains("reference") || message.contains("log") {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' does not say what is wrong with the reference"
                ))
            }
        },
    );
    report.assert_clean();
}

/// The landmark data sets' files, cut to 4 kB: MRCLAM Dataset 6 unzipped (each
/// file by name), the Freiburg course's and Victoria Park's; empty without the
/// shared data.
fn landmark_files() -> Vec<io::landmark_data::DataFile> {
    use io::landmark_data::{DataFile, unzip};
    let Some(root) = slamlab_fuzz::shared_data() else {
        eprintln!(
            "slamlab-fuzz: ../shared/data is absent; fuzzing the landmark data sets with the built-in seeds only"
        );
        return Vec::new();
    };
    let dir = root.join("landmarks");
    let mut files = Vec::new();
    if let Ok(bytes) = std::fs::read(dir.join("mrclam/MRCLAM_Dataset6.zip"))
        && let Ok(unzipped) = unzip(&DataFile::new("MRCLAM_Dataset6.zip", bytes))
    {
        files.extend(
            unzipped
                .into_iter()
                .map(|f| DataFile::new(f.base_name().to_owned(), head(&f.bytes, 4096))),
        );
    }
    for name in [
        "freiburg/world.dat",
        "freiburg/sensor_data.dat",
        "victoria_park/inputs.dat",
        "victoria_park/measurements.dat",
        "victoria_park/gps.dat",
    ] {
        if let Ok(bytes) = std::fs::read(dir.join(name)) {
            let base = io::landmark_data::base_name(name).to_owned();
            files.push(DataFile::new(base, head(&bytes, 4096)));
        }
    }
    files
}
/// Fuzzes one data set: each input takes, in turn, the place of every file of
/// the small set (the others stay valid), goes through the reader, and when it
/// is accepted becomes a recorded world that a session runs 20 ticks of. An
/// input counts as accepted when some place took it; a refusal must name the
/// file (and the line, when it lies in one).
fn fuzz_landmark_set(name: &str, small: &[(&str, &str)]) {
    use crate::world::landmark_session::LandmarkSession;
    use crate::world::recorded::RecordedWorld;
    use io::landmark_data::{DataFile, read_landmark_data};
    let names: Vec<&str> = small.iter().map(|(n, _)| *n).collect();
    let mut seeds: Vec<Vec<u8>> = small.iter().map(|(_, t)| t.as_bytes().to_vec()).collect();
    seeds.extend(
        landmark_files()
            .into_iter()
            .filter(|f| names.contains(&f.name.as_str()))
            .map(|f| f.bytes),
    );
    let report = Target::new(name, seeds, CAP).run_checked(
        |bytes| {
            let mut refusals = Vec::new();
            for role in &names {
                let files: Vec<DataFile> = small
                    .iter()
                    .map(|(n, t)| {
                        let content = if n == role {
                            bytes.to_vec()
                        } else {
                            t.as_bytes().to_vec()
                        };
                        DataFile::new(*n, content)
                    })
                    .collect();
                match read_landmark_data(files) {
                    Ok(data) => {
                        if let Ok(world) = RecordedWorld::from_data(&data, 1) {
                            let scenario = crate::landmark_slam::presets::scenario(
                                crate::landmark_slam::presets::for_data(data.kind()),
                                1,
                            )
                            .unwrap_or_default();
                            let mut session = LandmarkSession::recorded(
                                crate::LandmarkScenario {
                                    estimators: vec![
                                        crate::EstimatorKind::Ekf,
                                        crate::EstimatorKind::FastSlam2,
                                    ],
                                    fastslam: crate::world::landmark_scenario::FastSlamSettings {
                                        particles: 5,
                                        ..scenario.fastslam
                                    },
                                    ..scenario
                                },
                                std::sync::Arc::new(world),
                            );
                            session.run_ticks(20);
                        }
                    }
                    Err(e) => refusals.push(e.to_string()),
                }
            }
            // Accepted in some place, or refused in every one (reported by the first).
            match refusals.first() {
                Some(first) if refusals.len() == names.len() => Err(first.clone()),
                _ => Ok(()),
            }
        },
        |message| {
            let names_file = names.iter().any(|n| message.contains(n));
            if names_file || message.contains("files") {
                Ok(())
            } else {
                Err(format!("'{message}' does not name the file"))
            }
        },
    );
    report.assert_clean();
}
#[test]
fn mrclam_files_survive_mutations() {
    fuzz_landmark_set("MRCLAM .dat files", &SMALL_MRCLAM);
}
#[test]
fn freiburg_files_survive_mutations() {
    fuzz_landmark_set("Freiburg course files", &SMALL_FREIBURG);
}
#[test]
fn victoria_park_files_survive_mutations() {
    fuzz_landmark_set("Victoria Park files", &SMALL_VICTORIA_PARK);
}
#[test]
fn mrclam_zips_survive_mutations() {
    use io::landmark_data::{DataFile, read_landmark_data};
    use std::io::Write;
    // Zips of the small set and of the real files' heads, deflated and stored.
    let zip = |files: &[(String, Vec<u8>)], method: zip::CompressionMethod| {
        let mut writer = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default().compression_method(method);
        for (name, bytes) in files {
            if writer
                .start_file(format!("MRCLAM_Dataset6/{name}"), options)
                .is_err()
                || writer.write_all(bytes).is_err()
            {
                return Vec::new();
            }
        }
        writer.finish().map(|c| c.into_inner()).unwrap_or_default()
    };
    let small: Vec<(String, Vec<u8>)> = SMALL_MRCLAM
        .iter()
        .map(|(n, t)| ((*n).to_owned(), t.as_bytes().to_vec()))
        .collect();
    let real: Vec<(String, Vec<u8>)> = landmark_files()
        .into_iter()
        .filter(|f| {
            io::landmark_data::DataSetKind::of_file(&f.name)
                == Some(io::landmark_data::DataSetKind::Mrclam)
        })
        .map(|f| (f.name, head(&f.bytes, 1024)))
        .collect();
    let mut seeds = vec![
        zip(&small, zip::CompressionMethod::Deflated),
        zip(&small, zip::CompressionMethod::Stored),
    ];
    if !real.is_empty() {
        seeds.push(zip(&real, zip::CompressionMethod::Deflated));
    }
    seeds.retain(|s| !s.is_empty());
    let report = Target::new("MRCLAM zip", seeds, CAP).run_checked(
        |bytes| {
            read_landmark_data(vec![DataFile::new("MRCLAM_Dataset6.zip", bytes.to_vec())])
                .map(drop)
                .map_err(|e| e.to_string())
        },
        |message| {
            if message.contains(".zip") || message.contains(".dat") || message.contains("files") {
                Ok(())
            } else {
                Err(format!(
                    "'{message}' does not name the zip or the file in it"
                ))
            }
        },
    );
    report.assert_clean();
}

/// A small data set of each kind, written by hand, as `(name, text)`.
const SMALL_MRCLAM: [(&str, &str); 5] = [
    (
        "Barcodes.dat",
        "# 4 comment lines\n#\n#\n#\n  1 \t  5 \n  6 \t 63 \n  7 \t 81 \n",
    ),
    (
        "Landmark_Groundtruth.dat",
        "  6 \t 1.0 \t 2.0 \t 0.0001 \t 0.0002 \n  7 \t -1.0 \t 3.0 \t 0.0001 \t 0.0001 \n",
    ),
    (
        "Robot1_Odometry.dat",
        "100.00 \t 0.1 \t 0.0 \n100.01 \t 0.1 \t 0.05 \n100.02 \t 0.0 \t 0.0 \n",
    ),
    (
        "Robot1_Measurement.dat",
        "100.005 \t 63 \t 2.2 \t 1.1 \n100.005 \t 81 \t 3.2 \t 1.9 \n100.015 \t 43 \t 1.0 \t 0.0 \n",
    ),
    (
        "Robot1_Groundtruth.dat",
        "99.99 \t 0.0 \t 0.0 \t 0.0 \n100.02 \t 0.002 \t 0.0 \t 0.001 \n",
    ),
];
const SMALL_FREIBURG: [(&str, &str); 2] = [
    ("world.dat", "1 2 1\n2 0 4\n"),
    (
        "sensor_data.dat",
        "ODOMETRY 0.1 0.1 0.0\nSENSOR 1 1.9 0.37\nSENSOR 2 -0.035 3.15\nODOMETRY 0.1 0.1 -0.0002\n",
    ),
];
const SMALL_VICTORIA_PARK: [(&str, &str); 3] = [
    (
        "inputs.dat",
        "     0.973      0.000    -0.0035\n     0.998      1.500    -0.0042\n",
    ),
    (
        "measurements.dat",
        "     0.852   20.46202    0.88575    0.35404\n     0.852   29.59859    1.02102    0.25717\n     1.052    9.5    3.1    0.2\n",
    ),
    ("gps.dat", "     0.000     -2.023     -1.923\n"),
];
