//! A ROS map handed in as one file: a zip holding map_server's YAML and the
//! image (PGM or PNG) it names, as a student's program writes them beside each
//! other. The grader and a page's drop read it here; the command line zips a
//! YAML and its image when it is given the YAML.

use super::archive::write_zip;
use super::ros_map::{ImageFormat, MAX_YAML_BYTES, MapYaml, export_map, load_map, parse_map_yaml};
use slamlab_core::grid::OccupancyGrid;
use std::io::{Cursor, Read};

/// The largest zip read, bytes (a 4000 x 4000 map's PGM is 16 MB).
pub const MAX_MAP_ZIP_BYTES: usize = 64 * 1024 * 1024;

/// The largest image inside, bytes once unpacked.
pub const MAX_IMAGE_BYTES: usize = 64 * 1024 * 1024;

/// The most entries a map's zip may hold.
pub const MAX_ENTRIES: usize = 16;

/// True when `bytes` start like a zip archive.
pub fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06")
}

/// The last part of a path inside an archive or a YAML's `image:`.
fn base_name(path: &str) -> &str {
    path.rsplit(['/', '\\']).next().unwrap_or(path)
}

/// A map zipped as a student's program hands it in: `{stem}.yaml` and the
/// image it names, `{stem}.pgm` or `{stem}.png` (what [`read_map_zip`] reads
/// back cell for cell).
pub fn write_map_zip(
    grid: &OccupancyGrid,
    stem: &str,
    format: ImageFormat,
) -> Result<Vec<u8>, String> {
    let image = format!("{stem}.{}", format.extension());
    let (yaml, bytes) = export_map(grid, &image, format).map_err(|e| e.to_string())?;
    write_zip(
        "hand-in",
        &[(format!("{stem}.yaml"), yaml.into_bytes()), (image, bytes)],
    )
    .map_err(|e| e.to_string())
}

/// Reads the map in a zip named `name`: its one `.yaml` (or `.yml`) and the
/// image that YAML names (matched by file name, in any folder of the zip).
/// Every refusal names the file and what is wrong.
pub fn read_map_zip(name: &str, bytes: &[u8]) -> Result<(OccupancyGrid, MapYaml), String> {
    if bytes.len() > MAX_MAP_ZIP_BYTES {
        return Err(format!(
            "{name}: {} bytes, over the cap of {MAX_MAP_ZIP_BYTES} bytes for a map's zip",
            bytes.len()
        ));
    }
    if !is_zip(bytes) {
        return Err(format!(
            "{name}: not a zip archive; hand in the map's YAML and its image together in one zip"
        ));
    }
    let mut archive = zip::ZipArchive::new(Cursor::new(bytes))
        .map_err(|e| format!("{name}: not a zip archive SLAM Lab reads ({e})"))?;
    if archive.len() > MAX_ENTRIES {
        return Err(format!(
            "{name}: {} entries; a map's zip holds its YAML and its image",
            archive.len()
        ));
    }
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    for index in 0..archive.len() {
        let mut entry = archive
            .by_index(index)
            .map_err(|e| format!("{name}: entry {} cannot be read ({e})", index + 1))?;
        if entry.is_dir() {
            continue;
        }
        let path = entry
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| format!("entry {}", index + 1));
        let mut data = Vec::new();
        (&mut entry)
            .take(MAX_IMAGE_BYTES as u64 + 1)
            .read_to_end(&mut data)
            .map_err(|e| format!("{name}/{path}: does not unpack ({e})"))?;
        if data.len() > MAX_IMAGE_BYTES {
            return Err(format!(
                "{name}/{path}: unpacks to more than {MAX_IMAGE_BYTES} bytes"
            ));
        }
        files.push((path, data));
    }
    let yamls: Vec<&(String, Vec<u8>)> = files
        .iter()
        .filter(|(p, _)| {
            let lower = p.to_ascii_lowercase();
            (lower.ends_with(".yaml") || lower.ends_with(".yml"))
                && !base_name(&lower).starts_with("._")
        })
        .collect();
    let [(yaml_path, yaml_bytes)] = yamls.as_slice() else {
        return Err(format!(
            "{name}: holds {} YAML files; a map's zip holds exactly one (map.yaml) and its image",
            yamls.len()
        ));
    };
    if yaml_bytes.len() > MAX_YAML_BYTES {
        return Err(format!(
            "{name}/{yaml_path}: {} bytes, over the {MAX_YAML_BYTES} a map's YAML may have",
            yaml_bytes.len()
        ));
    }
    let yaml_text = std::str::from_utf8(yaml_bytes)
        .map_err(|_| format!("{name}/{yaml_path}: not UTF-8 text"))?;
    let yaml = parse_map_yaml(yaml_text).map_err(|e| format!("{name}/{yaml_path}: {e}"))?;
    let wanted = base_name(&yaml.image);
    let Some((image_path, image)) = files.iter().find(|(p, _)| base_name(p) == wanted) else {
        return Err(format!(
            "{name}/{yaml_path} names the image {:?}, which the zip does not hold",
            yaml.image
        ));
    };
    load_map(yaml_text, image).map_err(|e| format!("{name}/{image_path}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_core::Pose2;
    use slamlab_core::grid::Cell;

    fn grid() -> OccupancyGrid {
        let cells = (0..40 * 30)
            .map(|k| match k % 7 {
                0 => Cell::Occupied,
                1 | 2 => Cell::Unknown,
                _ => Cell::Free,
            })
            .collect();
        OccupancyGrid::new(40, 30, 0.05, Pose2::new(-1.0, 2.0, 0.0), cells).unwrap()
    }

    #[test]
    fn a_zipped_map_reads_back_cell_for_cell() {
        for format in [ImageFormat::Pgm, ImageFormat::Png] {
            let zip = write_map_zip(&grid(), "m", format).unwrap();
            let (back, _) = read_map_zip("mine.zip", &zip).unwrap();
            assert_eq!(back, grid());
        }
    }

    #[test]
    fn a_zip_without_its_image_or_with_two_yamls_is_refused_by_name() {
        let (yaml, bytes) = export_map(&grid(), "m.pgm", ImageFormat::Pgm).unwrap();
        let only_yaml =
            write_zip("x", &[("m.yaml".to_owned(), yaml.clone().into_bytes())]).unwrap();
        let err = read_map_zip("mine.zip", &only_yaml).unwrap_err();
        assert!(err.contains("mine.zip") && err.contains("m.pgm"), "{err}");
        let two = write_zip(
            "x",
            &[
                ("a.yaml".to_owned(), yaml.clone().into_bytes()),
                ("b.yaml".to_owned(), yaml.into_bytes()),
                ("m.pgm".to_owned(), bytes),
            ],
        )
        .unwrap();
        let err = read_map_zip("mine.zip", &two).unwrap_err();
        assert!(err.contains("2 YAML files"), "{err}");
        let err = read_map_zip("map.yaml", b"image: m.pgm\n").unwrap_err();
        assert!(err.contains("not a zip"), "{err}");
    }
}
