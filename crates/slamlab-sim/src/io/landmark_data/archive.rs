//! Zip archives: the UTIAS MRCLAM data set as UTIAS distributes it (one folder of
//! `.dat` files, deflated), or any data set zipped by hand.

use super::{DataError, DataFile, MAX_FILE_BYTES, MAX_FILES, MAX_ZIP_BYTES};
use std::io::{Cursor, Read};

/// True when `bytes` start like a zip archive (a local file header, or the end of
/// an empty archive).
pub(super) fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06")
}

/// The files in a zip archive (folders skipped), each named by its path inside
/// the archive and held to [`MAX_FILE_BYTES`] while it unpacks.
pub fn unzip(zip: &DataFile) -> Result<Vec<DataFile>, DataError> {
    if zip.bytes.len() > MAX_ZIP_BYTES {
        return Err(DataError::file(
            &zip.name,
            format!(
                "{} bytes, over the cap of {MAX_ZIP_BYTES} bytes for a zip archive",
                zip.bytes.len()
            ),
        ));
    }
    let mut archive = zip::ZipArchive::new(Cursor::new(zip.bytes.as_slice())).map_err(|e| {
        DataError::file(&zip.name, format!("not a zip archive SLAM Lab reads ({e})"))
    })?;
    if archive.len() > MAX_FILES {
        return Err(DataError::file(
            &zip.name,
            format!(
                "holds {} entries; a data set has at most {MAX_FILES} files",
                archive.len()
            ),
        ));
    }
    let mut files = Vec::new();
    for index in 0..archive.len() {
        let mut entry = archive.by_index(index).map_err(|e| {
            DataError::file(
                &zip.name,
                format!("entry {} cannot be read ({e})", index + 1),
            )
        })?;
        if entry.is_dir() {
            continue;
        }
        let name = entry
            .name()
            .map(|n| format!("{}/{n}", zip.name))
            .unwrap_or_else(|_| format!("{} entry {}", zip.name, index + 1));
        if entry.size() > MAX_FILE_BYTES as u64 {
            return Err(DataError::file(
                &name,
                format!(
                    "unpacks to {} bytes, over the cap of {MAX_FILE_BYTES} bytes for one data file",
                    entry.size()
                ),
            ));
        }
        let mut bytes = Vec::new();
        (&mut entry)
            .take(MAX_FILE_BYTES as u64 + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| DataError::file(&name, format!("does not unpack ({e})")))?;
        if bytes.len() > MAX_FILE_BYTES {
            return Err(DataError::file(
                &name,
                format!("unpacks to more than the cap of {MAX_FILE_BYTES} bytes for one data file"),
            ));
        }
        files.push(DataFile::new(name, bytes));
    }
    Ok(files)
}
