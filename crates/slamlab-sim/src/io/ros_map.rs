//! ROS `map_server` map files, read from and written to bytes (so the browser
//! can pass what the user dropped): a YAML description and a PGM (P2 or P5, 8 or
//! 16 bit) or PNG (grey, grey + alpha, RGB(A) averaged as map_server does, or
//! palette) image.
//!
//! YAML keys (ROS `map_server`): `image`, `resolution`, `origin: [x, y, yaw]`,
//! `negate`, `occupied_thresh`, `free_thresh`, `mode` (`trinary` by default,
//! `scale`, `raw`). The YAML is read by serde-saphyr under a budget (size, events,
//! depth, aliases), so a hostile file is refused quickly; every error names its
//! line. The images are decoded by the `image` crate (its `pnm` and `png` decoders
//! only), after the size in the header has been checked.
//!
//! Pixel to cell (map_server, `trinary`): with `v` the grey value scaled to
//! `0..255` (`255 − v` if `negate`), `p = (255 − v) / 255`; occupied if
//! `p > occupied_thresh`, free if `p < free_thresh`, otherwise unknown. `scale`
//! mode gives the same three states here (SLAM Lab's grid has no intermediate
//! probabilities; they show as unknown). `raw`: `v = 0` free, `v ≥ 100 x
//! occupied_thresh` (up to 100) occupied, anything else unknown. The image's
//! first row is the map's top row: cell row `j` is image row `height − 1 − j`.

use slamlab_core::Pose2;
use slamlab_core::grid::{Cell, GridError, OccupancyGrid, check_size};
use thiserror::Error;

/// Why a map file cannot be read.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum MapError {
    /// A YAML line that is not `key: value`, a list item or a comment.
    #[error("map YAML line {line}: {message}")]
    Yaml {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A required key is absent.
    #[error("map YAML has no `{0}`")]
    MissingKey(&'static str),
    /// A value of the wrong kind.
    #[error("map YAML line {line}: `{key}: {value}` is not {expected}")]
    BadValue {
        /// The key.
        key: String,
        /// 1-based line number.
        line: usize,
        /// The value as written.
        value: String,
        /// What was expected.
        expected: &'static str,
    },
    /// The thresholds are not `0 ≤ free_thresh < occupied_thresh ≤ 1`.
    #[error(
        "free_thresh {free} and occupied_thresh {occupied} must satisfy 0 <= free_thresh < occupied_thresh <= 1"
    )]
    BadThresholds {
        /// free_thresh.
        free: f64,
        /// occupied_thresh.
        occupied: f64,
    },
    /// The image named in the YAML could not be found or read.
    #[error("image '{name}' cannot be read: {reason}")]
    ImageUnreadable {
        /// The image file name.
        name: String,
        /// Why.
        reason: String,
    },
    /// Neither a PGM nor a PNG.
    #[error("the image is neither a PGM (P2/P5) nor a PNG (it starts with {0:?})")]
    UnknownImageFormat(String),
    /// A PGM header or body that cannot be read.
    #[error("PGM: {0}")]
    Pgm(String),
    /// A PGM whose pixel data stops early.
    #[error("PGM is truncated: {expected} pixels announced, {got} present")]
    Truncated {
        /// Pixels the header announces.
        expected: usize,
        /// Pixels present.
        got: usize,
    },
    /// A PNG that cannot be decoded.
    #[error("PNG: {0}")]
    Png(String),
    /// The grid itself is refused (size, resolution, origin). Transparent: the
    /// grid's message is the whole message (a `{0}` wrapper with `#[from]` made
    /// error chains print it twice).
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Every cell is occupied or unknown.
    #[error("the map has no free cell: there is nowhere for the robot to be")]
    NoFreeCell,
}

/// How grey values become cells (`mode` in the YAML).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MapMode {
    /// Free, occupied or unknown by the two thresholds (the default).
    #[default]
    Trinary,
    /// Thresholds as trinary; intermediate values unknown here.
    Scale,
    /// Grey values are occupancy percentages.
    Raw,
}

impl MapMode {
    /// The YAML name.
    pub fn name(self) -> &'static str {
        match self {
            MapMode::Trinary => "trinary",
            MapMode::Scale => "scale",
            MapMode::Raw => "raw",
        }
    }
}

/// The contents of a map YAML file.
#[derive(Clone, Debug, PartialEq)]
pub struct MapYaml {
    /// The image file, relative to the YAML file.
    pub image: String,
    /// Metres per cell.
    pub resolution: f64,
    /// The lower-left corner of the map in the world: `[x, y, yaw]`.
    pub origin: [f64; 3],
    /// Whether white means occupied.
    pub negate: bool,
    /// Occupancy probability above which a cell is occupied.
    pub occupied_thresh: f64,
    /// Occupancy probability below which a cell is free.
    pub free_thresh: f64,
    /// How grey values become cells.
    pub mode: MapMode,
}

impl Default for MapYaml {
    fn default() -> Self {
        Self {
            image: String::new(),
            resolution: 0.05,
            origin: [0.0; 3],
            negate: false,
            occupied_thresh: 0.65,
            free_thresh: 0.196,
            mode: MapMode::Trinary,
        }
    }
}

/// The most bytes of map YAML read (a map_server file is a few hundred).
pub const MAX_YAML_BYTES: usize = 64 * 1024;

/// serde-saphyr's budget for a map YAML: a flat mapping of a dozen keys needs a few
/// dozen parser events; these limits refuse a hostile file (deep nesting, alias
/// bombs, huge scalars) before it costs memory or time.
fn yaml_options() -> serde_saphyr::Options {
    let mut budget = serde_saphyr::Budget::default();
    budget.max_reader_input_bytes = Some(MAX_YAML_BYTES);
    budget.max_events = 4_096;
    budget.max_nodes = 2_048;
    budget.max_depth = 16;
    budget.max_aliases = 16;
    budget.max_anchors = 16;
    budget.max_documents = 1;
    budget.max_total_scalar_bytes = MAX_YAML_BYTES;
    budget.max_merge_keys = 0;
    let mut options = serde_saphyr::Options::default();
    options.budget = Some(budget);
    options
}

/// One value of the YAML with the line it is on.
type Spanned = serde_saphyr::Spanned<serde_json::Value>;

/// A value as the user wrote it, for messages.
fn shown(value: &serde_json::Value) -> String {
    match value {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => "(nothing, or a number that is not finite)".to_owned(),
        serde_json::Value::Array(items) => {
            format!(
                "[{}]",
                items.iter().map(shown).collect::<Vec<_>>().join(", ")
            )
        }
        other => other.to_string(),
    }
}

fn line_of(value: &Spanned) -> usize {
    usize::try_from(value.referenced.line()).unwrap_or(usize::MAX)
}

fn bad_value(key: &str, value: &Spanned, expected: &'static str) -> MapError {
    MapError::BadValue {
        key: key.to_owned(),
        line: line_of(value),
        value: shown(&value.value),
        expected,
    }
}

/// A number: a YAML number or a quoted one.
fn number(key: &str, value: &Spanned) -> Result<f64, MapError> {
    match &value.value {
        serde_json::Value::Number(n) => n.as_f64(),
        serde_json::Value::String(s) => s.trim().parse::<f64>().ok(),
        _ => None,
    }
    .ok_or_else(|| bad_value(key, value, "a number"))
}

/// The line of a serde-saphyr error (1 when it gives none), and its message.
fn yaml_error(error: &serde_saphyr::Error) -> MapError {
    let line = error.location().map_or(1, |l| {
        usize::try_from(l.line()).unwrap_or(usize::MAX).max(1)
    });
    // The error's Display draws a source snippet; the first line says what is wrong.
    let text = error.to_string();
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("the YAML does not parse");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    // "line 2 column 13: what" -> "column 13: what" (the line is said once).
    let message = match first
        .strip_prefix("line ")
        .and_then(|rest| rest.split_once(' '))
    {
        Some((_, rest)) if rest.starts_with("column ") => rest.to_owned(),
        _ => first.to_owned(),
    };
    MapError::Yaml { line, message }
}

/// Parses a ROS map YAML file with serde-saphyr (budget-limited; see
/// [`MAX_YAML_BYTES`]). Unknown keys are ignored, as map_server does. Every error
/// names its line.
pub fn parse_map_yaml(text: &str) -> Result<MapYaml, MapError> {
    if text.len() > MAX_YAML_BYTES {
        return Err(MapError::Yaml {
            line: 1,
            message: format!(
                "the file has {} bytes, more than the {MAX_YAML_BYTES} bytes a map YAML may have",
                text.len()
            ),
        });
    }
    // An empty file (or one of comments only) is a document with no keys.
    let entries: std::collections::BTreeMap<String, Spanned> = if text
        .lines()
        .all(|l| l.trim().is_empty() || l.trim_start().starts_with('#'))
    {
        std::collections::BTreeMap::new()
    } else {
        serde_saphyr::from_str_with_options::<Option<_>>(text, yaml_options())
            .map_err(|e| yaml_error(&e))?
            .unwrap_or_default()
    };
    let mut yaml = MapYaml::default();
    let Some(image) = entries.get("image") else {
        return Err(MapError::MissingKey("image"));
    };
    yaml.image = match &image.value {
        serde_json::Value::String(s) if !s.trim().is_empty() => s.trim().to_owned(),
        serde_json::Value::Number(n) => n.to_string(),
        _ => return Err(bad_value("image", image, "a file name")),
    };
    let Some(resolution) = entries.get("resolution") else {
        return Err(MapError::MissingKey("resolution"));
    };
    yaml.resolution = number("resolution", resolution)?;
    let Some(origin) = entries.get("origin") else {
        return Err(MapError::MissingKey("origin"));
    };
    match &origin.value {
        serde_json::Value::Array(items) if items.len() == 3 => {
            for (o, item) in yaml.origin.iter_mut().zip(items) {
                let item = Spanned::new(item.clone(), origin.referenced, origin.defined);
                *o = number("origin", &item)?;
            }
        }
        serde_json::Value::Array(_) => {
            return Err(bad_value(
                "origin",
                origin,
                "a list of three numbers [x, y, yaw]",
            ));
        }
        _ => return Err(bad_value("origin", origin, "a list [x, y, yaw]")),
    }
    if let Some(negate) = entries.get("negate") {
        yaml.negate = match &negate.value {
            serde_json::Value::Bool(b) => *b,
            serde_json::Value::Number(n) if n.as_f64() == Some(0.0) => false,
            serde_json::Value::Number(n) if n.as_f64() == Some(1.0) => true,
            serde_json::Value::String(s) => match s.trim() {
                "0" | "false" | "False" => false,
                "1" | "true" | "True" => true,
                _ => return Err(bad_value("negate", negate, "0 or 1")),
            },
            _ => return Err(bad_value("negate", negate, "0 or 1")),
        };
    }
    if let Some(v) = entries.get("occupied_thresh") {
        yaml.occupied_thresh = number("occupied_thresh", v)?;
    }
    if let Some(v) = entries.get("free_thresh") {
        yaml.free_thresh = number("free_thresh", v)?;
    }
    if let Some(mode) = entries.get("mode") {
        yaml.mode = match &mode.value {
            serde_json::Value::String(s) => match s.trim() {
                "trinary" => MapMode::Trinary,
                "scale" => MapMode::Scale,
                "raw" => MapMode::Raw,
                _ => return Err(bad_value("mode", mode, "trinary, scale or raw")),
            },
            _ => return Err(bad_value("mode", mode, "trinary, scale or raw")),
        };
    }
    check_yaml(&yaml)?;
    Ok(yaml)
}

fn check_yaml(yaml: &MapYaml) -> Result<(), MapError> {
    if !(yaml.resolution > 0.0) || !yaml.resolution.is_finite() {
        return Err(GridError::BadResolution(yaml.resolution).into());
    }
    if yaml.origin.iter().any(|v| !v.is_finite()) {
        return Err(GridError::BadOrigin {
            x: yaml.origin[0],
            y: yaml.origin[1],
            yaw: yaml.origin[2],
        }
        .into());
    }
    let (f, o) = (yaml.free_thresh, yaml.occupied_thresh);
    if !(f >= 0.0 && f < o && o <= 1.0) {
        return Err(MapError::BadThresholds {
            free: f,
            occupied: o,
        });
    }
    Ok(())
}

/// Writes a map YAML file.
pub fn write_map_yaml(yaml: &MapYaml) -> String {
    format!(
        "image: {}\nresolution: {}\norigin: [{}, {}, {}]\nnegate: {}\noccupied_thresh: {}\nfree_thresh: {}\nmode: {}\n",
        yaml.image,
        yaml.resolution,
        yaml.origin[0],
        yaml.origin[1],
        yaml.origin[2],
        u8::from(yaml.negate),
        yaml.occupied_thresh,
        yaml.free_thresh,
        yaml.mode.name(),
    )
}

/// A decoded grey image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct GreyImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The largest grey value (255 for 8 bit, up to 65535).
    pub maxval: u16,
    /// Grey values, row-major from the top row.
    pub pixels: Vec<u16>,
    /// Alpha per pixel (0 transparent .. maxval opaque), if the image has one.
    pub alpha: Option<Vec<u16>>,
}

/// Decodes a PGM (P2 or P5) or PNG image, told apart by their first bytes.
pub fn decode_image(bytes: &[u8]) -> Result<GreyImage, MapError> {
    if bytes.starts_with(b"\x89PNG") {
        decode_png(bytes)
    } else if bytes.starts_with(b"P5") || bytes.starts_with(b"P2") {
        decode_pgm(bytes)
    } else {
        let head: String = bytes
            .iter()
            .take(8)
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '.' })
            .collect();
        Err(MapError::UnknownImageFormat(head))
    }
}

/// The most bytes the image decoders may allocate for one image (the largest map
/// SLAM Lab accepts, `MAX_CELLS` 16-bit RGBA pixels, is far less).
const MAX_DECODE_BYTES: u64 = 512 * 1024 * 1024;

/// A short description of an `image` error, without the crate's type names.
fn image_error_text(error: &image::ImageError) -> String {
    match error {
        image::ImageError::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the data ends early".to_owned()
        }
        other => other.to_string(),
    }
}

/// Whether an `image` error says the pixel data stops early.
fn is_truncation(error: &image::ImageError) -> bool {
    match error {
        image::ImageError::IoError(e) => e.kind() == std::io::ErrorKind::UnexpectedEof,
        other => other.to_string().contains("Not enough data"),
    }
}

/// Decodes a PGM image with the `image` crate's PNM decoder: `P5` (binary, 1 byte
/// per pixel if `maxval < 256`, else 2 bytes big-endian) or `P2` (ASCII). Grey values
/// come scaled to 8 or 16 bits (`maxval` 255 or 65535). The size in the header is
/// checked against `slamlab_core::grid::MAX_CELLS` before the pixels are allocated.
pub fn decode_pgm(bytes: &[u8]) -> Result<GreyImage, MapError> {
    use image::ImageDecoder;
    use image::codecs::pnm::{PnmDecoder, PnmSubtype, SampleEncoding};
    if !matches!(bytes.get(..2), Some(b"P5" | b"P2")) {
        return Err(MapError::Pgm(
            "the file does not start with P2 or P5".to_owned(),
        ));
    }
    let decoder = PnmDecoder::new(std::io::Cursor::new(bytes)).map_err(|e| {
        MapError::Pgm(format!(
            "the header cannot be read: {}",
            image_error_text(&e)
        ))
    })?;
    let (w, h) = decoder.dimensions();
    let (width, height) = (w as usize, h as usize);
    check_size(width, height)?;
    let n = width * height;
    let sixteen = match decoder.color_type() {
        image::ColorType::L8 => false,
        image::ColorType::L16 => true,
        other => {
            return Err(MapError::Pgm(format!(
                "a grey image was expected, the header describes {other:?}"
            )));
        }
    };
    // How many pixels the data can hold, checked before the pixels are allocated: a
    // binary PGM has 1 or 2 bytes per pixel, an ASCII one at least 2 (a digit and a
    // separator, the last one without).
    let header_len = PnmDecoder::new(std::io::Cursor::new(bytes))
        .ok()
        .map_or(bytes.len(), |d| {
            usize::try_from(d.into_inner().0.position()).unwrap_or(bytes.len())
        });
    let data_len = bytes.len().saturating_sub(header_len);
    match decoder.subtype() {
        PnmSubtype::Graymap(SampleEncoding::Binary) => {
            let got = data_len / if sixteen { 2 } else { 1 };
            if got < n {
                return Err(MapError::Truncated { expected: n, got });
            }
        }
        _ => {
            if data_len + 1 < 2 * n {
                return Err(MapError::Pgm(format!(
                    "the pixel data ends before its {n} pixels ({data_len} bytes of text)"
                )));
            }
        }
    }
    let total = usize::try_from(decoder.total_bytes()).unwrap_or(usize::MAX);
    let mut buf = vec![0u8; total];
    decoder.read_image(&mut buf).map_err(|e| {
        if is_truncation(&e) {
            MapError::Pgm(format!("the pixel data ends before its {n} pixels"))
        } else {
            MapError::Pgm(format!(
                "the pixel data cannot be read: {}",
                image_error_text(&e)
            ))
        }
    })?;
    let pixels = if sixteen {
        buf.chunks_exact(2)
            .map(|c| u16::from_ne_bytes([c[0], c[1]]))
            .collect()
    } else {
        buf.iter().map(|&b| u16::from(b)).collect()
    };
    Ok(GreyImage {
        width,
        height,
        maxval: if sixteen { 65535 } else { 255 },
        pixels,
        alpha: None,
    })
}

/// Decodes a PNG with the `image` crate's PNG decoder: grey, grey + alpha, RGB or
/// RGBA (colour channels averaged, as map_server does), palette images expanded; 1
/// to 16 bits. The size is checked from the header before the pixels are decoded.
pub fn decode_png(bytes: &[u8]) -> Result<GreyImage, MapError> {
    use image::ImageDecoder;
    // The IHDR chunk comes first: signature (8), length (4), "IHDR" (4), then
    // width and height. Check the size before the decoder allocates anything.
    if let (Some(b"IHDR"), Some(w), Some(h)) =
        (bytes.get(12..16), bytes.get(16..20), bytes.get(20..24))
    {
        let w = u32::from_be_bytes([w[0], w[1], w[2], w[3]]) as usize;
        let h = u32::from_be_bytes([h[0], h[1], h[2], h[3]]) as usize;
        check_size(w, h)?;
    }
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_DECODE_BYTES);
    let decoder = image::codecs::png::PngDecoder::with_limits(std::io::Cursor::new(bytes), limits)
        .map_err(|e| MapError::Png(image_error_text(&e)))?;
    let (w, h) = decoder.dimensions();
    let (w, h) = (w as usize, h as usize);
    check_size(w, h)?;
    let color = decoder.color_type();
    let channels = usize::from(color.channel_count());
    let has_alpha = color.has_alpha();
    let sixteen = color.bytes_per_pixel() / color.channel_count() == 2;
    let total = usize::try_from(decoder.total_bytes()).unwrap_or(usize::MAX);
    let mut buf = vec![0u8; total];
    decoder
        .read_image(&mut buf)
        .map_err(|e| MapError::Png(image_error_text(&e)))?;
    let maxval: u16 = if sixteen { 65535 } else { 255 };
    // `image` gives 16-bit samples in native byte order.
    let sample = |k: usize| -> u32 {
        if sixteen {
            u32::from(u16::from_ne_bytes([buf[2 * k], buf[2 * k + 1]]))
        } else {
            u32::from(buf[k])
        }
    };
    let colour = if has_alpha { channels - 1 } else { channels }.max(1);
    if buf.len() < w * h * channels * if sixteen { 2 } else { 1 } {
        return Err(MapError::Png(
            "the image data is shorter than its header".to_owned(),
        ));
    }
    let mut pixels = Vec::with_capacity(w * h);
    let mut alpha = has_alpha.then(|| Vec::with_capacity(w * h));
    for p in 0..w * h {
        let base = p * channels;
        let sum: u32 = (0..colour).map(|c| sample(base + c)).sum();
        pixels.push((sum / colour as u32) as u16);
        if let Some(a) = &mut alpha {
            a.push(sample(base + channels - 1) as u16);
        }
    }
    Ok(GreyImage {
        width: w,
        height: h,
        maxval,
        pixels,
        alpha,
    })
}

/// Turns a decoded image into a grid with the YAML's rules (see the module
/// documentation).
pub fn grid_from_image(image: &GreyImage, yaml: &MapYaml) -> Result<OccupancyGrid, MapError> {
    check_yaml(yaml)?;
    check_size(image.width, image.height)?;
    let (w, h) = (image.width, image.height);
    if image.pixels.len() != w * h {
        return Err(MapError::Truncated {
            expected: w * h,
            got: image.pixels.len(),
        });
    }
    let max = f64::from(image.maxval.max(1));
    let mut cells = vec![Cell::Unknown; w * h];
    for j in 0..h {
        let row = h - 1 - j;
        for i in 0..w {
            let raw = f64::from(image.pixels[row * w + i]) * 255.0 / max;
            cells[j * w + i] = match yaml.mode {
                MapMode::Raw => {
                    if raw == 0.0 {
                        Cell::Free
                    } else if raw <= 100.0 && raw >= 100.0 * yaml.occupied_thresh {
                        Cell::Occupied
                    } else {
                        Cell::Unknown
                    }
                }
                MapMode::Trinary | MapMode::Scale => {
                    let v = if yaml.negate { 255.0 - raw } else { raw };
                    let p = (255.0 - v) / 255.0;
                    if p > yaml.occupied_thresh {
                        Cell::Occupied
                    } else if p < yaml.free_thresh {
                        Cell::Free
                    } else {
                        Cell::Unknown
                    }
                }
            };
        }
    }
    let origin = Pose2::new(yaml.origin[0], yaml.origin[1], yaml.origin[2]);
    Ok(OccupancyGrid::new(w, h, yaml.resolution, origin, cells)?)
}

/// Reads a map from its YAML text and the bytes of the image it names. Refuses
/// a map with no free cell.
pub fn load_map(yaml_text: &str, image_bytes: &[u8]) -> Result<(OccupancyGrid, MapYaml), MapError> {
    let yaml = parse_map_yaml(yaml_text)?;
    let image = decode_image(image_bytes)?;
    let grid = grid_from_image(&image, &yaml)?;
    if grid.counts().0 == 0 {
        return Err(MapError::NoFreeCell);
    }
    Ok((grid, yaml))
}

/// Reads a lone image (no YAML) with the given resolution, origin `(0, 0, 0)`
/// and map_server's default thresholds (old `map_server IMAGE RESOLUTION`).
pub fn load_lone_image(image_bytes: &[u8], resolution: f64) -> Result<OccupancyGrid, MapError> {
    let yaml = MapYaml {
        resolution,
        ..MapYaml::default()
    };
    check_yaml(&yaml)?;
    let image = decode_image(image_bytes)?;
    let grid = grid_from_image(&image, &yaml)?;
    if grid.counts().0 == 0 {
        return Err(MapError::NoFreeCell);
    }
    Ok(grid)
}

/// Image formats for export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit grey PNG.
    Png,
    /// Binary 8-bit PGM (P5).
    Pgm,
}

impl ImageFormat {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            ImageFormat::Png => "png",
            ImageFormat::Pgm => "pgm",
        }
    }
}

/// Grey values map_saver writes: occupied 0, free 254, unknown 205.
fn grey(cell: Cell) -> u8 {
    match cell {
        Cell::Occupied => 0,
        Cell::Free => 254,
        Cell::Unknown => 205,
    }
}

/// The grid's image rows, top row first.
fn image_rows(grid: &OccupancyGrid) -> Vec<u8> {
    let (w, h) = (grid.width(), grid.height());
    let mut out = Vec::with_capacity(w * h);
    for row in 0..h {
        let j = h - 1 - row;
        out.extend(grid.cells()[j * w..(j + 1) * w].iter().map(|&c| grey(c)));
    }
    out
}

/// Encodes the grid as an 8-bit image (map_saver's grey values).
pub fn encode_image(grid: &OccupancyGrid, format: ImageFormat) -> Result<Vec<u8>, MapError> {
    let pixels = image_rows(grid);
    match format {
        ImageFormat::Pgm => {
            let mut out = format!(
                "P5\n# SLAM Lab map\n{} {}\n255\n",
                grid.width(),
                grid.height()
            )
            .into_bytes();
            out.extend_from_slice(&pixels);
            Ok(out)
        }
        ImageFormat::Png => {
            let mut out = Vec::new();
            {
                let mut enc =
                    png::Encoder::new(&mut out, grid.width() as u32, grid.height() as u32);
                enc.set_color(png::ColorType::Grayscale);
                enc.set_depth(png::BitDepth::Eight);
                let mut writer = enc
                    .write_header()
                    .map_err(|e| MapError::Png(e.to_string()))?;
                writer
                    .write_image_data(&pixels)
                    .map_err(|e| MapError::Png(e.to_string()))?;
                writer.finish().map_err(|e| MapError::Png(e.to_string()))?;
            }
            Ok(out)
        }
    }
}

/// Exports a grid as a YAML text naming `image_name` and the image's bytes.
pub fn export_map(
    grid: &OccupancyGrid,
    image_name: &str,
    format: ImageFormat,
) -> Result<(String, Vec<u8>), MapError> {
    let o = grid.origin();
    let yaml = MapYaml {
        image: image_name.to_owned(),
        resolution: grid.resolution(),
        origin: [o.x, o.y, o.theta],
        ..MapYaml::default()
    };
    Ok((write_map_yaml(&yaml), encode_image(grid, format)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_grid(seed: u64) -> OccupancyGrid {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (w, h) = (37, 23);
        let cells = (0..w * h)
            .map(|_| match rng.random_range(0..3) {
                0 => Cell::Free,
                1 => Cell::Occupied,
                _ => Cell::Unknown,
            })
            .collect();
        OccupancyGrid::new(w, h, 0.05, Pose2::new(-3.5, 1.25, 0.0), cells).unwrap()
    }

    #[test]
    fn round_trips_through_png_and_pgm() {
        let grid = random_grid(1);
        for format in [ImageFormat::Png, ImageFormat::Pgm] {
            let (yaml, image) = export_map(&grid, "m.img", format).unwrap();
            let (back, meta) = load_map(&yaml, &image).unwrap();
            assert_eq!(back, grid, "{format:?}");
            assert_eq!(meta.image, "m.img");
            assert_eq!(meta.origin, [-3.5, 1.25, 0.0]);
        }
    }

    #[test]
    fn one_occupied_cell_lands_at_its_world_position() {
        // A 4 x 3 image, all white except the pixel in column 1 of the TOP row.
        // With origin (10, 20) and 0.5 m cells, that pixel is cell (1, 2), whose
        // centre is at (10.75, 21.25).
        let mut pgm = b"P2\n# one wall\n4 3\n255\n".to_vec();
        let rows = ["255 0 255 255", "255 255 255 255", "255 255 255 255"];
        for r in rows {
            pgm.extend_from_slice(r.as_bytes());
            pgm.push(b'\n');
        }
        let yaml = "image: x.pgm\nresolution: 0.5\norigin: [10.0, 20.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        let (g, _) = load_map(yaml, &pgm).unwrap();
        assert_eq!(g.get(1, 2), Some(Cell::Occupied));
        assert_eq!(g.counts(), (11, 1, 0));
        assert_eq!(g.cell_at(10.75, 21.25), Some(Cell::Occupied));
        assert_eq!(g.cell_at(10.75, 20.25), Some(Cell::Free));
        // The same map as a 16-bit P5.
        let mut p5 = b"P5 4 3 65535\n".to_vec();
        for r in rows {
            for v in r.split(' ') {
                let v: u16 = if v == "0" { 0 } else { 65535 };
                p5.extend_from_slice(&v.to_be_bytes());
            }
        }
        assert_eq!(load_map(yaml, &p5).unwrap().0, g);
    }

    #[test]
    fn negate_and_thresholds_are_honoured() {
        // Grey values 0, 60, 128, 200, 255: p = 1, 0.765, 0.498, 0.216, 0.
        let pgm = b"P2 5 1 255 0 60 128 200 255".to_vec();
        let cells = |yaml: &str| load_map(yaml, &pgm).map(|(g, _)| g.cells().to_vec());
        let base = "image: a.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n";
        use Cell::*;
        assert_eq!(
            cells(&format!(
                "{base}negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196"
            ))
            .unwrap(),
            vec![Occupied, Occupied, Unknown, Unknown, Free]
        );
        assert_eq!(
            cells(&format!(
                "{base}negate: 0\noccupied_thresh: 0.4\nfree_thresh: 0.25"
            ))
            .unwrap(),
            vec![Occupied, Occupied, Occupied, Free, Free]
        );
        assert_eq!(
            cells(&format!(
                "{base}negate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.196"
            ))
            .unwrap(),
            vec![Free, Unknown, Unknown, Occupied, Occupied]
        );
    }

    #[test]
    fn png_with_alpha_and_rgb_are_read() {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, 2, 1);
            enc.set_color(png::ColorType::GrayscaleAlpha);
            enc.set_depth(png::BitDepth::Eight);
            let mut wr = enc.write_header().unwrap();
            wr.write_image_data(&[0, 255, 254, 128]).unwrap();
            wr.finish().unwrap();
        }
        let img = decode_image(&out).unwrap();
        assert_eq!(img.pixels, vec![0, 254]);
        assert_eq!(img.alpha, Some(vec![255, 128]));
        let mut rgb = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut rgb, 1, 1);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut wr = enc.write_header().unwrap();
            wr.write_image_data(&[30, 60, 90]).unwrap();
            wr.finish().unwrap();
        }
        assert_eq!(decode_image(&rgb).unwrap().pixels, vec![60]);
    }

    #[test]
    fn bad_input_gets_a_message_naming_the_problem() {
        let ok_image = b"P2 2 1 255 255 0".to_vec();
        let e = parse_map_yaml("image: a.pgm\nresolution 0.05\n").unwrap_err();
        assert!(matches!(e, MapError::Yaml { line: 2, .. }), "{e}");
        assert!(e.to_string().contains("line 2"));
        assert_eq!(
            parse_map_yaml("resolution: 0.05\norigin: [0, 0, 0]").unwrap_err(),
            MapError::MissingKey("image")
        );
        let e = parse_map_yaml("image: a\nresolution: 0.05\norigin: [0, 0]").unwrap_err();
        assert!(matches!(e, MapError::BadValue { line: 3, .. }), "{e}");
        let e = parse_map_yaml("image: a\nresolution: 0.05\norigin: [0, 0, 0\n").unwrap_err();
        assert!(matches!(e, MapError::Yaml { line: 3, .. }), "{e}");
        for r in ["0", "-0.05", "nan", ".nan"] {
            let e = parse_map_yaml(&format!("image: a\nresolution: {r}\norigin: [0, 0, 0]"))
                .unwrap_err();
            assert!(
                matches!(
                    e,
                    MapError::Grid(GridError::BadResolution(_))
                        | MapError::BadValue { .. }
                        | MapError::Yaml { line: 2, .. }
                ),
                "{r}: {e}"
            );
        }
        let e = load_lone_image(&ok_image, 0.0).unwrap_err();
        assert!(e.to_string().contains("resolution 0"), "{e}");
        // A block list for origin is fine; comments are ignored.
        let y = parse_map_yaml(
            "# map\nimage: 'a b.png'  # quoted\nresolution: 0.1\norigin:\n  - 1\n  - 2\n  - 0\n",
        )
        .unwrap();
        assert_eq!(y.image, "a b.png");
        assert_eq!(y.origin, [1.0, 2.0, 0.0]);

        // Images.
        assert!(matches!(
            decode_image(b"GIF89a"),
            Err(MapError::UnknownImageFormat(_))
        ));
        assert_eq!(
            decode_image(b"P5 4 4 255\n0123456").unwrap_err(),
            MapError::Truncated {
                expected: 16,
                got: 7
            }
        );
        let e = decode_image(b"P2 3 1 255 0 1").unwrap_err();
        assert!(e.to_string().contains("ends before its 3 pixels"), "{e}");
        assert!(matches!(decode_image(b"P5 4"), Err(MapError::Pgm(_))));
        assert!(matches!(
            decode_image(b"P5 4 4 70000\n"),
            Err(MapError::Pgm(_))
        ));
        // A header claiming 100000 x 100000 is refused before any allocation.
        assert!(matches!(
            decode_image(b"P5 100000 100000 255\n\0\0\0"),
            Err(MapError::Grid(GridError::TooLarge { .. }))
        ));
        let mut huge_png = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut huge_png, 100_000, 100_000);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            let wr = enc.write_header().unwrap();
            drop(wr);
        }
        assert!(matches!(
            decode_image(&huge_png),
            Err(MapError::Grid(GridError::TooLarge { .. }))
        ));
        assert!(matches!(
            decode_image(b"\x89PNG\r\n\x1a\nxx"),
            Err(MapError::Png(_))
        ));
        // No free cell.
        let yaml = "image: a\nresolution: 0.1\norigin: [0, 0, 0]";
        assert_eq!(
            load_map(yaml, b"P2 2 1 255 0 0").unwrap_err(),
            MapError::NoFreeCell
        );
        assert!(load_map(yaml, &ok_image).is_ok());
        let e = parse_map_yaml("image: a\nresolution: 0.1\norigin: [0, 0, 0]\nfree_thresh: 0.9")
            .unwrap_err();
        assert!(matches!(e, MapError::BadThresholds { .. }), "{e}");
    }
}
