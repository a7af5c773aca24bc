//! Landmark data sets read from their files: the UTIAS Multi-Robot Cooperative
//! Localization and Mapping data set ([`mrclam`]), the Freiburg Robot Mapping
//! course's `world.dat`/`sensor_data.dat` ([`freiburg`]) and Victoria Park
//! ([`victoria_park`]). `../shared/data/landmarks/README.md` describes each
//! format, its units and its quirks; every quirk has a hand-made test file below.
//!
//! The readers take files as bytes with their names ([`DataFile`]), so the
//! browser can hand over dropped files and the contents of a zip, and the command
//! line reads them from disk ([`read_path`]). [`read_landmark_data`] tells the
//! three data sets apart by their file names and unpacks zip archives first.
//! What a reader returns is the files' content as plain tables, checked (times in
//! order, ranges not negative, one subject per barcode); turning it into a run is
//! the landmark world's work (`crate::world::recorded`).
//!
//! Every refusal is a [`DataError`] naming the file and, where it lies in one, the
//! line. Caps: [`MAX_FILE_BYTES`] per file (checked before a byte is parsed, and
//! while a zip entry unpacks), [`MAX_ZIP_BYTES`] per archive, [`MAX_FILES`] entries.

mod archive;
pub mod freiburg;
pub mod mrclam;
mod table;
pub mod victoria_park;

pub use archive::unzip;
pub use freiburg::FreiburgData;
pub use mrclam::MrclamData;
pub use victoria_park::VictoriaParkData;

use std::fmt;
use std::path::Path;

/// The largest data file accepted, bytes: 64 MiB (the largest file of the three
/// data sets, `Robot4_Groundtruth.dat`, has 3.4 MB).
pub const MAX_FILE_BYTES: usize = 64 * 1024 * 1024;
/// The largest zip archive accepted, bytes: 64 MiB (MRCLAM's Dataset 6 is 5.1 MB).
pub const MAX_ZIP_BYTES: usize = 64 * 1024 * 1024;
/// The most files one data set may be given as (in a zip or dropped together).
pub const MAX_FILES: usize = 256;

/// A file as given: its name (as dropped, or its path inside a zip) and its bytes.
#[derive(Clone, PartialEq, Eq)]
pub struct DataFile {
    /// The file's name; only the part after the last `/` or `\` identifies it.
    pub name: String,
    /// Its contents.
    pub bytes: Vec<u8>,
}

impl fmt::Debug for DataFile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "DataFile({}, {} bytes)", self.name, self.bytes.len())
    }
}

impl DataFile {
    /// A file from its name and bytes.
    pub fn new(name: impl Into<String>, bytes: Vec<u8>) -> Self {
        Self {
            name: name.into(),
            bytes,
        }
    }

    /// The name without any folder (`MRCLAM_Dataset6/Barcodes.dat` is `Barcodes.dat`).
    pub fn base_name(&self) -> &str {
        base_name(&self.name)
    }
}

/// The part of `name` after its last `/` or `\`.
pub fn base_name(name: &str) -> &str {
    name.rsplit(['/', '\\']).next().unwrap_or(name)
}

/// Why a data set could not be read: the file, the line when the problem lies in
/// one (1-based), and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct DataError {
    /// The file's name (empty when the problem is the set of files as a whole).
    pub file: String,
    /// The 1-based line, when the problem is on one.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.file.is_empty(), self.line) {
            (true, _) => write!(f, "{}", self.message),
            (false, Some(line)) => write!(f, "{}, line {line}: {}", self.file, self.message),
            (false, None) => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl DataError {
    /// A problem on `line` of `file`.
    pub fn line(file: &str, line: usize, message: impl Into<String>) -> Self {
        Self {
            file: file.to_owned(),
            line: Some(line),
            message: message.into(),
        }
    }

    /// A problem with `file` as a whole.
    pub fn file(file: &str, message: impl Into<String>) -> Self {
        Self {
            file: file.to_owned(),
            line: None,
            message: message.into(),
        }
    }

    /// A problem with the set of files as a whole (a missing file, files of two
    /// data sets).
    pub fn set(message: impl Into<String>) -> Self {
        Self {
            file: String::new(),
            line: None,
            message: message.into(),
        }
    }
}

/// Which data set a set of files is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataSetKind {
    /// UTIAS MRCLAM (`Barcodes.dat`, `RobotN_*.dat`, ...).
    Mrclam,
    /// The Freiburg course files (`sensor_data.dat`, `world.dat`).
    Freiburg,
    /// Victoria Park (`inputs.dat`, `measurements.dat`, `gps.dat`).
    VictoriaPark,
}

impl DataSetKind {
    /// Which data set a file of this (base) name belongs to, if any.
    pub fn of_file(base_name: &str) -> Option<Self> {
        if mrclam::is_mrclam_file(base_name) {
            Some(DataSetKind::Mrclam)
        } else if freiburg::FILES.contains(&base_name) {
            Some(DataSetKind::Freiburg)
        } else if victoria_park::FILES.contains(&base_name) {
            Some(DataSetKind::VictoriaPark)
        } else {
            None
        }
    }

    /// The data set's short name.
    pub fn name(self) -> &'static str {
        match self {
            DataSetKind::Mrclam => "UTIAS MRCLAM",
            DataSetKind::Freiburg => "Freiburg Robot Mapping course",
            DataSetKind::VictoriaPark => "Victoria Park",
        }
    }
}

/// A landmark data set as read from its files.
#[derive(Clone, Debug, PartialEq)]
pub enum LandmarkData {
    /// UTIAS MRCLAM: robots, barcoded landmarks, Vicon truth.
    Mrclam(MrclamData),
    /// The Freiburg course's odometry and sensor steps with the true landmarks.
    Freiburg(FreiburgData),
    /// Victoria Park: a car's speed and steering, tree detections, GPS.
    VictoriaPark(VictoriaParkData),
}

impl LandmarkData {
    /// Which data set this is.
    pub fn kind(&self) -> DataSetKind {
        match self {
            LandmarkData::Mrclam(_) => DataSetKind::Mrclam,
            LandmarkData::Freiburg(_) => DataSetKind::Freiburg,
            LandmarkData::VictoriaPark(_) => DataSetKind::VictoriaPark,
        }
    }
}

/// Reads a data set from its files: a zip is unpacked first (MRCLAM as UTIAS
/// distributes it), then the files are told apart by name. Files of no data set
/// (a `README`, say) are ignored; files of two data sets are refused.
pub fn read_landmark_data(files: Vec<DataFile>) -> Result<LandmarkData, DataError> {
    if files.len() > MAX_FILES {
        return Err(DataError::set(format!(
            "{} files given; a data set has at most {MAX_FILES}",
            files.len()
        )));
    }
    let mut unpacked = Vec::new();
    for file in files {
        if archive::is_zip(&file.bytes) {
            unpacked.extend(unzip(&file)?);
        } else {
            unpacked.push(file);
        }
        if unpacked.len() > MAX_FILES {
            return Err(DataError::set(format!(
                "more than {MAX_FILES} files given; a data set has at most {MAX_FILES}"
            )));
        }
    }
    let kinds: Vec<(DataSetKind, &str)> = unpacked
        .iter()
        .filter_map(|f| DataSetKind::of_file(f.base_name()).map(|k| (k, f.name.as_str())))
        .collect();
    let Some(&(kind, first)) = kinds.first() else {
        let names: Vec<&str> = unpacked.iter().map(|f| f.name.as_str()).take(5).collect();
        return Err(DataError::set(format!(
            "no file of a landmark data set SLAM Lab reads among {}: expected the UTIAS MRCLAM \
             zip or its Barcodes.dat, Landmark_Groundtruth.dat and RobotN_Odometry.dat, \
             RobotN_Measurement.dat, RobotN_Groundtruth.dat; or the Freiburg course's \
             sensor_data.dat and world.dat; or Victoria Park's inputs.dat, measurements.dat \
             and gps.dat",
            if names.is_empty() {
                "no files".to_owned()
            } else {
                names.join(", ")
            }
        )));
    };
    if let Some((other, name)) = kinds.iter().find(|(k, _)| *k != kind) {
        return Err(DataError::set(format!(
            "{first} is a {} file but {name} a {} file: give one data set at a time",
            kind.name(),
            other.name()
        )));
    }
    match kind {
        DataSetKind::Mrclam => mrclam::read(&unpacked).map(LandmarkData::Mrclam),
        DataSetKind::Freiburg => freiburg::read(&unpacked).map(LandmarkData::Freiburg),
        DataSetKind::VictoriaPark => victoria_park::read(&unpacked).map(LandmarkData::VictoriaPark),
    }
}

/// Reads the files a command-line `--data PATH` names: a zip, a folder (every
/// file in it of the data set's names), or one file of a data set (it and the
/// other files of its set beside it). Files are checked against
/// [`MAX_FILE_BYTES`] (or [`MAX_ZIP_BYTES`]) before they are read.
pub fn read_path(path: &Path) -> Result<LandmarkData, DataError> {
    let shown = path.display().to_string();
    let meta = std::fs::metadata(path)
        .map_err(|e| DataError::file(&shown, format!("cannot be read: {e}")))?;
    let files = if meta.is_dir() {
        read_folder(path, None)?
    } else {
        let name = base_name(&shown).to_owned();
        match DataSetKind::of_file(&name) {
            // One file of a set: read its companions beside it.
            Some(kind) => read_folder(path.parent().unwrap_or(Path::new(".")), Some(kind))?,
            None => vec![read_file(path, &shown)?],
        }
    };
    read_landmark_data(files)
}

/// The files of `folder` whose names belong to a data set (to `only`, if given).
fn read_folder(folder: &Path, only: Option<DataSetKind>) -> Result<Vec<DataFile>, DataError> {
    let shown = folder.display().to_string();
    let entries = std::fs::read_dir(folder)
        .map_err(|e| DataError::file(&shown, format!("cannot be read: {e}")))?;
    let mut files = Vec::new();
    let mut paths: Vec<_> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
    paths.sort();
    for path in paths {
        let name = path.display().to_string();
        let kind = DataSetKind::of_file(base_name(&name));
        let zip = name.to_ascii_lowercase().ends_with(".zip");
        let wanted = match only {
            Some(only) => kind == Some(only),
            None => kind.is_some() || zip,
        };
        if wanted && path.is_file() {
            files.push(read_file(&path, &name)?);
        }
    }
    if files.is_empty() {
        return Err(DataError::file(
            &shown,
            "holds no file of a landmark data set (MRCLAM's zip or .dat files, the \
             Freiburg course's sensor_data.dat and world.dat, Victoria Park's inputs.dat, \
             measurements.dat and gps.dat)",
        ));
    }
    Ok(files)
}

/// Reads one file after checking its size.
fn read_file(path: &Path, shown: &str) -> Result<DataFile, DataError> {
    let size = std::fs::metadata(path)
        .map_err(|e| DataError::file(shown, format!("cannot be read: {e}")))?
        .len();
    let cap = MAX_FILE_BYTES.max(MAX_ZIP_BYTES) as u64;
    if size > cap {
        return Err(DataError::file(
            shown,
            format!("{size} bytes, over the cap of {cap} bytes for one data file"),
        ));
    }
    let bytes =
        std::fs::read(path).map_err(|e| DataError::file(shown, format!("cannot be read: {e}")))?;
    Ok(DataFile::new(shown, bytes))
}

/// The file named `base` among `files`, if given.
fn find<'a>(files: &'a [DataFile], base: &str) -> Option<&'a DataFile> {
    files.iter().find(|f| f.base_name() == base)
}

#[cfg(test)]
mod tests;
