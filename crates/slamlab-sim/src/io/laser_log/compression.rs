//! Unpacking a log: plain text, gzip or bzip2, told apart by the first bytes
//! (magic numbers), never by the file name, with a cap on the unpacked size
//! checked while decompressing (a small file that unpacks to gigabytes stops
//! at the cap).

use super::LogError;
use std::borrow::Cow;
use std::io::Read;

/// How a log's bytes are packed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// Plain text.
    Plain,
    /// gzip (RFC 1952; magic `1f 8b`), possibly several members.
    Gzip,
    /// bzip2 (magic `BZh1`..`BZh9`), possibly several streams (as `pbzip2` writes).
    Bzip2,
}

impl Compression {
    /// The name used in messages and `slamlab log info`.
    pub fn name(self) -> &'static str {
        match self {
            Compression::Plain => "plain",
            Compression::Gzip => "gzip",
            Compression::Bzip2 => "bzip2",
        }
    }

    /// Recognizes the packing from the first bytes. Formats SLAM Lab does not
    /// unpack (zip, xz, zstd) are named in the error rather than read as text.
    pub fn detect(bytes: &[u8]) -> Result<Self, LogError> {
        match bytes {
            [0x1f, 0x8b, ..] => Ok(Compression::Gzip),
            [b'B', b'Z', b'h', b'1'..=b'9', ..] => Ok(Compression::Bzip2),
            [b'P', b'K', 3, 4, ..] => Err(LogError::UnsupportedCompression("zip")),
            [0xfd, b'7', b'z', b'X', b'Z', 0, ..] => Err(LogError::UnsupportedCompression("xz")),
            [0x28, 0xb5, 0x2f, 0xfd, ..] => Err(LogError::UnsupportedCompression("zstd")),
            _ => Ok(Compression::Plain),
        }
    }
}

/// Unpacks `bytes` (packing detected by [`Compression::detect`]), refusing to
/// produce more than `max_unpacked` bytes.
pub fn unpack(bytes: &[u8], max_unpacked: u64) -> Result<(Compression, Cow<'_, [u8]>), LogError> {
    let compression = Compression::detect(bytes)?;
    match compression {
        Compression::Plain => {
            if bytes.len() as u64 > max_unpacked {
                return Err(LogError::TooLarge {
                    what: "the log",
                    bytes: bytes.len() as u64,
                    cap: max_unpacked,
                });
            }
            Ok((compression, Cow::Borrowed(bytes)))
        }
        Compression::Gzip => {
            let decoder = flate2::read::MultiGzDecoder::new(bytes);
            read_capped(decoder, compression, max_unpacked).map(|v| (compression, Cow::Owned(v)))
        }
        Compression::Bzip2 => {
            let decoder = bzip2::read::MultiBzDecoder::new(bytes);
            read_capped(decoder, compression, max_unpacked).map(|v| (compression, Cow::Owned(v)))
        }
    }
}

/// Reads a decoder to its end, stopping with [`LogError::TooLarge`] as soon as
/// it yields more than `cap` bytes.
fn read_capped<R: Read>(
    decoder: R,
    compression: Compression,
    cap: u64,
) -> Result<Vec<u8>, LogError> {
    let mut out = Vec::new();
    let mut limited = decoder.take(cap.saturating_add(1));
    limited
        .read_to_end(&mut out)
        .map_err(|e| LogError::Corrupt {
            compression: compression.name(),
            message: e.to_string(),
            unpacked: out.len() as u64,
        })?;
    if out.len() as u64 > cap {
        return Err(LogError::TooLarge {
            what: "the unpacked log",
            bytes: out.len() as u64,
            cap,
        });
    }
    Ok(out)
}
