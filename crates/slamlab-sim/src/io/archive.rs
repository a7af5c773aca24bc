//! Zip archives SLAM Lab writes: a lesson's exported trajectories in one file,
//! for the browser's single download.

use std::io::{Cursor, Write as _};
use thiserror::Error;
use zip::write::SimpleFileOptions;

/// Why an archive could not be written.
#[derive(Debug, Error)]
#[error("could not write the zip archive: {0}")]
pub struct ArchiveError(String);

/// The files, deflated, in a zip archive under `folder/` (a folder of the
/// archive's own name, so that unpacking does not scatter them).
pub fn write_zip(folder: &str, files: &[(String, Vec<u8>)]) -> Result<Vec<u8>, ArchiveError> {
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in files {
        zip.start_file(format!("{folder}/{name}"), options)
            .map_err(|e| ArchiveError(e.to_string()))?;
        zip.write_all(bytes)
            .map_err(|e| ArchiveError(e.to_string()))?;
    }
    let cursor = zip.finish().map_err(|e| ArchiveError(e.to_string()))?;
    Ok(cursor.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read as _;

    #[test]
    fn files_come_back_out_of_the_archive() {
        let files = vec![
            ("a.tum".to_owned(), b"0 1 2 0 0 0 0 1\n".to_vec()),
            ("README.txt".to_owned(), vec![b'x'; 10_000]),
        ];
        let bytes = write_zip("slamlab-kidnap", &files).unwrap();
        assert!(bytes.len() < 1_000, "deflated: {} bytes", bytes.len());
        let mut archive = zip::ZipArchive::new(Cursor::new(bytes)).unwrap();
        assert_eq!(archive.len(), 2);
        for (name, content) in &files {
            let mut entry = archive.by_name(&format!("slamlab-kidnap/{name}")).unwrap();
            let mut back = Vec::new();
            entry.read_to_end(&mut back).unwrap();
            assert_eq!(&back, content);
        }
    }
}
