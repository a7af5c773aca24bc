//! ROS `map_server` map files, read from and written to bytes (so the browser
//! can pass what the user dropped): a YAML description and a PGM (P2 or P5, 8 or
//! 16 bit) or PNG (grey, grey + alpha, RGB(A) averaged as map_server does, or
//! palette) image.
//!
//! YAML keys (ROS `map_server`): `image`, `resolution`, `origin: [x, y, yaw]`,
//! `negate`, `occupied_thresh`, `free_thresh`, `mode` (`trinary` by default,
//! `scale`, `raw`). The YAML reader is a small one for exactly this flat format
//! (scalars, `[a, b, c]` and `- item` lists, comments), so every error can name
//! its line.
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
    /// The grid itself is refused (size, resolution, origin).
    #[error("{0}")]
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

/// Removes a `#` comment that is not inside quotes.
fn strip_comment(line: &str) -> &str {
    let mut quote: Option<char> = None;
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '#') => return &line[..i],
            _ => {}
        }
    }
    line
}

fn unquote(s: &str) -> &str {
    let s = s.trim();
    if s.len() >= 2
        && ((s.starts_with('"') && s.ends_with('"')) || (s.starts_with('\'') && s.ends_with('\'')))
    {
        &s[1..s.len() - 1]
    } else {
        s
    }
}

fn number(key: &str, line: usize, value: &str) -> Result<f64, MapError> {
    unquote(value)
        .parse::<f64>()
        .map_err(|_| MapError::BadValue {
            key: key.to_owned(),
            line,
            value: value.to_owned(),
            expected: "a number",
        })
}

/// Parses a ROS map YAML file. Unknown keys are ignored, as map_server does.
pub fn parse_map_yaml(text: &str) -> Result<MapYaml, MapError> {
    let mut yaml = MapYaml::default();
    let mut have_image = false;
    let mut have_resolution = false;
    // A key whose value is a block list (`origin:` then `- x` lines).
    let mut block: Option<(String, usize, Vec<String>)> = None;
    let mut origin_seen = false;
    let mut entries: Vec<(String, usize, Value)> = Vec::new();
    enum Value {
        Scalar(String),
        List(Vec<String>),
    }
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let content = strip_comment(raw).trim_end();
        if content.trim().is_empty() || content.trim() == "---" {
            continue;
        }
        let trimmed = content.trim_start();
        if let Some(item) =
            trimmed
                .strip_prefix("- ")
                .or(if trimmed == "-" { Some("") } else { None })
        {
            match &mut block {
                Some((_, _, items)) => {
                    items.push(item.trim().to_owned());
                    continue;
                }
                None => {
                    return Err(MapError::Yaml {
                        line,
                        message: format!("list item '{trimmed}' belongs to no key"),
                    });
                }
            }
        }
        if let Some((key, l, items)) = block.take() {
            entries.push((key, l, Value::List(items)));
        }
        let Some((key, value)) = trimmed.split_once(':') else {
            return Err(MapError::Yaml {
                line,
                message: format!("'{trimmed}' is not `key: value`"),
            });
        };
        let key = unquote(key).to_owned();
        if key.is_empty() {
            return Err(MapError::Yaml {
                line,
                message: "a value without a key".to_owned(),
            });
        }
        let value = value.trim();
        if value.is_empty() {
            block = Some((key, line, Vec::new()));
        } else if let Some(inner) = value.strip_prefix('[') {
            let Some(inner) = inner.strip_suffix(']') else {
                return Err(MapError::Yaml {
                    line,
                    message: format!("the list '{value}' has no closing ']'"),
                });
            };
            let items = if inner.trim().is_empty() {
                Vec::new()
            } else {
                inner.split(',').map(|s| s.trim().to_owned()).collect()
            };
            entries.push((key, line, Value::List(items)));
        } else {
            entries.push((key, line, Value::Scalar(value.to_owned())));
        }
    }
    if let Some((key, l, items)) = block.take() {
        entries.push((key, l, Value::List(items)));
    }
    for (key, line, value) in entries {
        let scalar = |expected: &'static str| match &value {
            Value::Scalar(s) => Ok(s.clone()),
            Value::List(items) => Err(MapError::BadValue {
                key: key.clone(),
                line,
                value: format!("[{}]", items.join(", ")),
                expected,
            }),
        };
        match key.as_str() {
            "image" => {
                let s = scalar("a file name")?;
                yaml.image = unquote(&s).to_owned();
                have_image = !yaml.image.is_empty();
            }
            "resolution" => {
                yaml.resolution = number(&key, line, &scalar("a number")?)?;
                have_resolution = true;
            }
            "origin" => {
                let items = match &value {
                    Value::List(items) => items,
                    Value::Scalar(s) => {
                        return Err(MapError::BadValue {
                            key: key.clone(),
                            line,
                            value: s.clone(),
                            expected: "a list [x, y, yaw]",
                        });
                    }
                };
                if items.len() != 3 {
                    return Err(MapError::BadValue {
                        key: key.clone(),
                        line,
                        value: format!("[{}]", items.join(", ")),
                        expected: "a list of three numbers [x, y, yaw]",
                    });
                }
                for (o, item) in yaml.origin.iter_mut().zip(items) {
                    *o = number("origin", line, item)?;
                }
                origin_seen = true;
            }
            "negate" => {
                let s = scalar("0 or 1")?;
                yaml.negate = match unquote(&s) {
                    "0" | "false" | "False" => false,
                    "1" | "true" | "True" => true,
                    _ => {
                        return Err(MapError::BadValue {
                            key: key.clone(),
                            line,
                            value: s,
                            expected: "0 or 1",
                        });
                    }
                };
            }
            "occupied_thresh" => yaml.occupied_thresh = number(&key, line, &scalar("a number")?)?,
            "free_thresh" => yaml.free_thresh = number(&key, line, &scalar("a number")?)?,
            "mode" => {
                let s = scalar("trinary, scale or raw")?;
                yaml.mode = match unquote(&s) {
                    "trinary" => MapMode::Trinary,
                    "scale" => MapMode::Scale,
                    "raw" => MapMode::Raw,
                    _ => {
                        return Err(MapError::BadValue {
                            key: key.clone(),
                            line,
                            value: s,
                            expected: "trinary, scale or raw",
                        });
                    }
                };
            }
            _ => {}
        }
    }
    if !have_image {
        return Err(MapError::MissingKey("image"));
    }
    if !have_resolution {
        return Err(MapError::MissingKey("resolution"));
    }
    if !origin_seen {
        return Err(MapError::MissingKey("origin"));
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

/// Decodes a PGM image: `P5` (binary, 1 byte per pixel if `maxval < 256`, else
/// 2 bytes big-endian) or `P2` (ASCII). The size is checked against
/// `slamlab_core::grid::MAX_CELLS` before anything is allocated.
pub fn decode_pgm(bytes: &[u8]) -> Result<GreyImage, MapError> {
    let binary = match bytes.get(..2) {
        Some(b"P5") => true,
        Some(b"P2") => false,
        _ => {
            return Err(MapError::Pgm(
                "the file does not start with P2 or P5".to_owned(),
            ));
        }
    };
    let mut pos = 2;
    let mut header = [0u64; 3];
    for (k, name) in ["width", "height", "maxval"].iter().enumerate() {
        header[k] = next_token(bytes, &mut pos)
            .ok_or_else(|| MapError::Pgm(format!("the header ends before its {name}")))?
            .parse::<u64>()
            .map_err(|_| MapError::Pgm(format!("the {name} is not a whole number")))?;
    }
    let [w, h, maxval] = header;
    if !(1..=65535).contains(&maxval) {
        return Err(MapError::Pgm(format!(
            "maxval {maxval} is outside 1..65535"
        )));
    }
    let width = usize::try_from(w).unwrap_or(usize::MAX);
    let height = usize::try_from(h).unwrap_or(usize::MAX);
    check_size(width, height)?;
    let n = width * height;
    let maxval = maxval as u16;
    let pixels = if binary {
        // Exactly one whitespace byte after maxval.
        pos += 1;
        let data = bytes.get(pos..).unwrap_or(&[]);
        let per = if maxval < 256 { 1 } else { 2 };
        let got = data.len() / per;
        if got < n {
            return Err(MapError::Truncated { expected: n, got });
        }
        if per == 1 {
            data[..n].iter().map(|&b| u16::from(b)).collect()
        } else {
            data[..2 * n]
                .chunks_exact(2)
                .map(|c| u16::from_be_bytes([c[0], c[1]]))
                .collect()
        }
    } else {
        let mut pixels = Vec::with_capacity(n);
        while pixels.len() < n {
            let Some(tok) = next_token(bytes, &mut pos) else {
                return Err(MapError::Truncated {
                    expected: n,
                    got: pixels.len(),
                });
            };
            let v: u32 = tok.parse().map_err(|_| {
                MapError::Pgm(format!("pixel {} '{tok}' is not a number", pixels.len()))
            })?;
            pixels.push(v.min(u32::from(maxval)) as u16);
        }
        pixels
    };
    if let Some(bad) = pixels.iter().position(|&v| v > maxval) {
        return Err(MapError::Pgm(format!(
            "pixel {bad} is {} above maxval {maxval}",
            pixels[bad]
        )));
    }
    Ok(GreyImage {
        width,
        height,
        maxval,
        pixels,
        alpha: None,
    })
}

/// The next whitespace-separated token of a PGM header, skipping `#` comments.
fn next_token<'a>(bytes: &'a [u8], pos: &mut usize) -> Option<&'a str> {
    loop {
        while *pos < bytes.len() && bytes[*pos].is_ascii_whitespace() {
            *pos += 1;
        }
        if *pos < bytes.len() && bytes[*pos] == b'#' {
            while *pos < bytes.len() && bytes[*pos] != b'\n' {
                *pos += 1;
            }
            continue;
        }
        break;
    }
    let start = *pos;
    while *pos < bytes.len() && !bytes[*pos].is_ascii_whitespace() && bytes[*pos] != b'#' {
        *pos += 1;
    }
    if start == *pos {
        None
    } else {
        std::str::from_utf8(&bytes[start..*pos]).ok()
    }
}

/// Decodes a PNG: grey, grey + alpha, RGB or RGBA (colour channels averaged, as
/// map_server does), palette images expanded; 1 to 16 bits. The size is checked
/// from the header before the pixels are decoded.
pub fn decode_png(bytes: &[u8]) -> Result<GreyImage, MapError> {
    // The IHDR chunk comes first: signature (8), length (4), "IHDR" (4), then
    // width and height. Check the size before the decoder allocates anything.
    if let (Some(b"IHDR"), Some(w), Some(h)) =
        (bytes.get(12..16), bytes.get(16..20), bytes.get(20..24))
    {
        let w = u32::from_be_bytes([w[0], w[1], w[2], w[3]]) as usize;
        let h = u32::from_be_bytes([h[0], h[1], h[2], h[3]]) as usize;
        check_size(w, h)?;
    }
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder
        .read_info()
        .map_err(|e| MapError::Png(e.to_string()))?;
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    check_size(w, h)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| MapError::Png("the image is too large to decode".to_owned()))?;
    let mut buf = vec![0u8; size];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| MapError::Png(e.to_string()))?;
    let (channels, has_alpha) = match frame.color_type {
        png::ColorType::Grayscale => (1, false),
        png::ColorType::GrayscaleAlpha => (2, true),
        png::ColorType::Rgb => (3, false),
        png::ColorType::Rgba => (4, true),
        png::ColorType::Indexed => {
            return Err(MapError::Png("the palette was not expanded".to_owned()));
        }
    };
    let sixteen = frame.bit_depth == png::BitDepth::Sixteen;
    let maxval: u16 = if sixteen { 65535 } else { 255 };
    let bps = if sixteen { 2 } else { 1 };
    let sample = |row: &[u8], k: usize| -> u32 {
        if sixteen {
            u32::from(u16::from_be_bytes([row[2 * k], row[2 * k + 1]]))
        } else {
            u32::from(row[k])
        }
    };
    let colour = if has_alpha { channels - 1 } else { channels };
    let mut pixels = Vec::with_capacity(w * h);
    let mut alpha = has_alpha.then(|| Vec::with_capacity(w * h));
    for r in 0..h {
        let start = r * frame.line_size;
        let row = buf
            .get(start..start + w * channels * bps)
            .ok_or_else(|| MapError::Png("the image data is shorter than its header".to_owned()))?;
        for x in 0..w {
            let base = x * channels;
            let sum: u32 = (0..colour).map(|c| sample(row, base + c)).sum();
            pixels.push((sum / colour as u32) as u16);
            if let Some(a) = &mut alpha {
                a.push(sample(row, base + channels - 1) as u16);
            }
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
                    MapError::Grid(GridError::BadResolution(_)) | MapError::BadValue { .. }
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
        assert!(matches!(
            decode_image(b"P2 3 1 255 0 1"),
            Err(MapError::Truncated {
                expected: 3,
                got: 2
            })
        ));
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
