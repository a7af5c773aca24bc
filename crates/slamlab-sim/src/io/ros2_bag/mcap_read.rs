//! An MCAP file's records, read with the `mcap` crate's sans-I/O linear reader,
//! its chunks unpacked here by pure-Rust decoders (`ruzstd` for zstd,
//! `lz4_flex` for LZ4 frames), so the same code runs in the browser.
//!
//! MCAP (mcap.dev specification, "Records"): a magic, a Header record, a data
//! section of Schema, Channel and Message records (possibly inside Chunk
//! records, each compressed whole), a Data End record, an optional summary
//! section (repeated schemas and channels, statistics, indexes), a Footer and
//! the magic again. A linear read sees every record once, summary or not.

use super::{BagError, BagLimits};
use mcap::records::{ChunkHeader, Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Read as _;

/// A channel: a topic with its type and encoding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelInfo {
    /// The topic, e.g. `/scan`.
    pub topic: String,
    /// The schema's name: the ROS type, e.g. `sensor_msgs/msg/LaserScan`;
    /// empty when the channel has no schema.
    pub type_name: String,
    /// The schema's encoding (`ros2msg`, `ros2idl`, ...).
    pub schema_encoding: String,
    /// The messages' encoding (`cdr` for ROS 2).
    pub message_encoding: String,
}

/// What the file says about itself.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct McapHeader {
    /// The profile (`ros2` for a ROS 2 bag).
    pub profile: String,
    /// The library that wrote it.
    pub library: String,
    /// Chunks read, by compression (`""` for uncompressed).
    pub chunks: BTreeMap<String, usize>,
    /// Whether the file has a summary section (its footer points to one).
    pub has_summary: bool,
}

/// Reads every record of an MCAP file, calling `on_message` for each message
/// with its channel, log time (ns) and serialized bytes, in file order.
pub(crate) fn read_mcap(
    bytes: &[u8],
    limits: &BagLimits,
    mut on_message: impl FnMut(&ChannelInfo, u64, &[u8]) -> Result<(), BagError>,
) -> Result<McapHeader, BagError> {
    let mut state = State {
        limits: *limits,
        header: McapHeader::default(),
        schemas: BTreeMap::new(),
        channels: BTreeMap::new(),
        unpacked: 0,
        records: 0,
    };
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_emit_chunks(true)
            .with_record_length_limit(bytes.len()),
    );
    let mut rest = bytes;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            Ok(LinearReadEvent::Record { data, opcode }) => {
                state.records += 1;
                state.record(opcode, data, &mut on_message)?;
            }
            Err(e) => return Err(mcap_error(&e, bytes.len(), state.records)),
        }
    }
    Ok(state.header)
}

/// A damaged file's message: where reading stopped and what the crate said.
fn mcap_error(e: &mcap::McapError, len: usize, records: usize) -> BagError {
    match e {
        // The reader's record limit is the file's length: a record longer than
        // that runs past the end of the file.
        mcap::McapError::UnexpectedEof | mcap::McapError::RecordTooLarge { .. } => {
            BagError::Truncated {
                bytes: len as u64,
                records,
            }
        }
        mcap::McapError::BadMagic if records == 0 => BagError::NotMcap,
        other => BagError::Damaged {
            records,
            message: other.to_string(),
        },
    }
}

struct State {
    limits: BagLimits,
    header: McapHeader,
    /// Schema id -> (name, encoding).
    schemas: BTreeMap<u16, (String, String)>,
    channels: BTreeMap<u16, ChannelInfo>,
    /// Bytes unpacked from chunks so far.
    unpacked: u64,
    /// Records read so far (for messages).
    records: usize,
}

impl State {
    /// One record of the data or summary section, or of a chunk.
    fn record(
        &mut self,
        opcode: u8,
        body: &[u8],
        on_message: &mut impl FnMut(&ChannelInfo, u64, &[u8]) -> Result<(), BagError>,
    ) -> Result<(), BagError> {
        // Only the records read are parsed: an attachment, index or statistics
        // record is never looked into.
        if !matches!(
            opcode,
            op::HEADER | op::SCHEMA | op::CHANNEL | op::MESSAGE | op::CHUNK | op::FOOTER
        ) {
            return Ok(());
        }
        // The crate's parser sizes a string's buffer from its length field:
        // every length is checked against the record first.
        check_lengths(opcode, body).map_err(|message| BagError::Damaged {
            records: self.records,
            message: format!("record {} (opcode {opcode:#04x}): {message}", self.records),
        })?;
        let record = mcap::parse_record(opcode, body).map_err(|e| BagError::Damaged {
            records: self.records,
            message: format!("record {} (opcode {opcode:#04x}): {e}", self.records),
        })?;
        match record {
            Record::Header(h) => {
                self.header.profile = h.profile;
                self.header.library = h.library;
            }
            Record::Footer(f) => self.header.has_summary = f.summary_start != 0,
            Record::Schema { header, .. } => {
                self.schemas
                    .insert(header.id, (header.name, header.encoding));
            }
            Record::Channel(c) => {
                let (type_name, schema_encoding) =
                    self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                self.channels.insert(
                    c.id,
                    ChannelInfo {
                        topic: c.topic,
                        type_name,
                        schema_encoding,
                        message_encoding: c.message_encoding,
                    },
                );
            }
            Record::Message { header, data } => {
                let Some(channel) = self.channels.get(&header.channel_id) else {
                    return Err(BagError::Damaged {
                        records: self.records,
                        message: format!(
                            "a message on channel {} before that channel's record",
                            header.channel_id
                        ),
                    });
                };
                on_message(channel, header.log_time, &data)?;
            }
            Record::Chunk { header, data } => {
                let compression = header.compression.clone();
                let unpacked = self.unpack(&header, &data)?;
                *self.header.chunks.entry(compression).or_insert(0) += 1;
                self.chunk_records(&unpacked, on_message)?;
            }
            _ => {}
        }
        Ok(())
    }

    /// The records of an unpacked chunk: opcode (1 byte), length (`u64`), body.
    fn chunk_records(
        &mut self,
        mut chunk: &[u8],
        on_message: &mut impl FnMut(&ChannelInfo, u64, &[u8]) -> Result<(), BagError>,
    ) -> Result<(), BagError> {
        while !chunk.is_empty() {
            let damaged = |message: String| BagError::Damaged {
                records: self.records,
                message,
            };
            let Some((&opcode, rest)) = chunk.split_first() else {
                break;
            };
            let Some((len, rest)) = rest.split_first_chunk::<8>() else {
                return Err(damaged(
                    "a chunk ends in the middle of a record's length".to_owned(),
                ));
            };
            let len = u64::from_le_bytes(*len);
            if len > rest.len() as u64 {
                return Err(damaged(format!(
                    "a record in a chunk claims {len} bytes, but only {} remain in the chunk",
                    rest.len()
                )));
            }
            let (body, rest) = rest.split_at(len as usize);
            self.records += 1;
            if matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
                self.record(opcode, body, on_message)?;
            }
            chunk = rest;
        }
        Ok(())
    }

    /// A chunk's records, unpacked and checked against its CRC.
    fn unpack<'a>(
        &mut self,
        header: &ChunkHeader,
        data: &'a [u8],
    ) -> Result<Cow<'a, [u8]>, BagError> {
        let size = header.uncompressed_size;
        if size > self.limits.max_chunk_bytes {
            return Err(BagError::TooLarge {
                what: "a chunk (unpacked)",
                bytes: size,
                cap: self.limits.max_chunk_bytes,
            });
        }
        self.unpacked = self.unpacked.saturating_add(size);
        if self.unpacked > self.limits.max_unpacked_bytes {
            return Err(BagError::TooLarge {
                what: "the bag's unpacked chunks",
                bytes: self.unpacked,
                cap: self.limits.max_unpacked_bytes,
            });
        }
        let corrupt = |message: String| BagError::CorruptChunk {
            compression: header.compression.clone(),
            message,
        };
        let out: Cow<'a, [u8]> = match header.compression.as_str() {
            "" => Cow::Borrowed(data),
            "zstd" => {
                // The whole chunk at once, frames and skippable frames included;
                // the output is the size the header states, checked against the cap.
                let mut out = vec![0u8; size as usize];
                let mut decoder = ruzstd::decoding::FrameDecoder::new();
                decoder.set_max_window_size(self.limits.max_chunk_bytes.max(1 << 20));
                let written = decoder
                    .decode_all(data, &mut out)
                    .map_err(|e| corrupt(e.to_string()))?;
                out.truncate(written);
                Cow::Owned(out)
            }
            "lz4" => {
                let mut out = Vec::new();
                lz4_flex::frame::FrameDecoder::new(data)
                    .take(size + 1)
                    .read_to_end(&mut out)
                    .map_err(|e| corrupt(e.to_string()))?;
                Cow::Owned(out)
            }
            other => return Err(BagError::UnsupportedCompression(other.to_owned())),
        };
        if out.len() as u64 != size {
            return Err(corrupt(format!(
                "it unpacks to {} bytes where its header says {size}",
                out.len()
            )));
        }
        if header.uncompressed_crc != 0 {
            let crc = crc32fast::hash(&out);
            if crc != header.uncompressed_crc {
                return Err(corrupt(format!(
                    "its CRC is {crc:08x} where its header says {:08x}",
                    header.uncompressed_crc
                )));
            }
        }
        Ok(out)
    }
}

/// Checks that every length-prefixed field of a Header, Schema, Channel or
/// Chunk record (strings, the channel's metadata map, the schema's data) lies
/// within the record, before the `mcap` crate's parser allocates a buffer of
/// that length (mcap.dev specification, "Records": a string is a `u32` byte
/// length and UTF-8 bytes; a map a `u32` byte length and key-value strings).
fn check_lengths(opcode: u8, body: &[u8]) -> Result<(), String> {
    let mut at = 0usize;
    let skip = |n: usize, what: &str, at: &mut usize| -> Result<(), String> {
        match at.checked_add(n) {
            Some(end) if end <= body.len() => {
                *at = end;
                Ok(())
            }
            _ => Err(format!(
                "its {what} runs past the record's end ({} bytes)",
                body.len()
            )),
        }
    };
    let length = |at: &mut usize, what: &str| -> Result<usize, String> {
        let bytes = body
            .get(*at..*at + 4)
            .ok_or_else(|| format!("it ends before its {what}"))?;
        *at += 4;
        Ok(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as usize)
    };
    let string = |at: &mut usize, what: &str| -> Result<(), String> {
        let n = length(at, what)?;
        skip(n, what, at)
    };
    match opcode {
        op::HEADER => {
            string(&mut at, "profile")?;
            string(&mut at, "library")?;
        }
        op::SCHEMA => {
            at = 2;
            string(&mut at, "name")?;
            string(&mut at, "encoding")?;
            string(&mut at, "data")?;
        }
        op::CHANNEL => {
            at = 4;
            string(&mut at, "topic")?;
            string(&mut at, "message encoding")?;
            let n = length(&mut at, "metadata")?;
            let end = at
                .checked_add(n)
                .filter(|&e| e <= body.len())
                .ok_or_else(|| "its metadata runs past the record's end".to_owned())?;
            while at < end {
                string(&mut at, "metadata key")?;
                string(&mut at, "metadata value")?;
            }
        }
        op::CHUNK => {
            at = 28;
            string(&mut at, "compression")?;
        }
        _ => {}
    }
    Ok(())
}
