//! The Common Data Representation (CDR) that ROS 2 serializes its messages in,
//! read and written by hand: it is small, and it is what a student sees in a
//! bag's bytes.
//!
//! A serialized message starts with a 4-byte encapsulation header: two bytes of
//! representation identifier (big-endian) and two bytes of options (ignored).
//! `00 00` is CDR big-endian, `00 01` CDR little-endian (OMG DDS-XTypes 1.3,
//! Sec. 7.6.3.1.2, "PLAIN_CDR"; what rmw_fastrtps and rmw_cyclonedds write).
//! After it, every primitive is aligned to its own size (1, 2, 4 or 8 bytes),
//! counted from the first byte after the header (XCDR1). A string is a `u32`
//! length that counts its terminating NUL, then the bytes and the NUL; a
//! sequence is a `u32` element count, then the elements; a fixed array has no
//! count (CORBA 3.0 Sec. 15.3, "CDR Transfer Syntax").
//!
//! Every length read is checked against the bytes that remain before anything
//! is allocated, so no length field can make the reader allocate more than the
//! message itself holds.

/// Why a message cannot be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field} at byte {offset}: {message}")]
pub struct CdrError {
    /// The field being read.
    pub field: &'static str,
    /// Where in the message (bytes from its start, header included).
    pub offset: usize,
    /// What is wrong.
    pub message: String,
}

/// The encapsulation header's length, bytes.
const HEADER: usize = 4;

/// Reads one CDR-encoded message.
#[derive(Debug)]
pub struct CdrReader<'a> {
    bytes: &'a [u8],
    /// Offset of the next byte to read, from the start of `bytes`.
    pos: usize,
    little_endian: bool,
}

impl<'a> CdrReader<'a> {
    /// Starts reading a message: checks its encapsulation header.
    pub fn new(bytes: &'a [u8]) -> Result<Self, CdrError> {
        let error = |message: String| CdrError {
            field: "encapsulation header",
            offset: 0,
            message,
        };
        let Some(header) = bytes.get(..HEADER) else {
            return Err(error(format!(
                "the message is {} bytes, shorter than its 4-byte header",
                bytes.len()
            )));
        };
        let little_endian = match (header[0], header[1]) {
            (0, 0) => false,
            (0, 1) => true,
            (0, 6) | (0, 7) => {
                return Err(error(
                    "XCDR2 (CDR2) encoding; SLAM Lab reads ROS 2's default plain CDR".to_owned(),
                ));
            }
            (a, b) => {
                return Err(error(format!(
                    "representation {a:02x} {b:02x} is not plain CDR (00 00 or 00 01)"
                )));
            }
        };
        Ok(Self {
            bytes,
            pos: HEADER,
            little_endian,
        })
    }

    /// Whether the message is little-endian.
    pub fn is_little_endian(&self) -> bool {
        self.little_endian
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    fn error(&self, field: &'static str, message: impl Into<String>) -> CdrError {
        CdrError {
            field,
            offset: self.pos,
            message: message.into(),
        }
    }

    /// Skips the padding before a primitive of `size` bytes.
    fn align(&mut self, size: usize) {
        let from_start = self.pos - HEADER;
        self.pos += (size - from_start % size) % size;
    }

    fn take<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], CdrError> {
        self.align(N);
        let end = self.pos + N;
        let Some(slice) = self.bytes.get(self.pos..end) else {
            return Err(self.error(
                field,
                format!("the message ends ({} bytes) before it", self.bytes.len()),
            ));
        };
        let mut out = [0u8; N];
        out.copy_from_slice(slice);
        self.pos = end;
        Ok(out)
    }

    /// A `uint32`.
    pub fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        let b = self.take::<4>(field)?;
        Ok(if self.little_endian {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// An `int32`.
    pub fn i32(&mut self, field: &'static str) -> Result<i32, CdrError> {
        // The same four bytes in the same order, read as two's complement.
        Ok(i32::from_ne_bytes(self.u32(field)?.to_ne_bytes()))
    }

    /// A `float32`.
    pub fn f32(&mut self, field: &'static str) -> Result<f32, CdrError> {
        Ok(f32::from_bits(self.u32(field)?))
    }

    /// A `float64`.
    pub fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        let b = self.take::<8>(field)?;
        Ok(f64::from_bits(if self.little_endian {
            u64::from_le_bytes(b)
        } else {
            u64::from_be_bytes(b)
        }))
    }

    /// `N` `float64`s (a fixed-size array: no count).
    pub fn f64_array<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], CdrError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(field)?;
        }
        Ok(out)
    }

    /// A `string` of at most `cap` bytes (its NUL not counted). Bytes that are
    /// not UTF-8 are replaced (frame ids are ASCII in practice).
    pub fn string(&mut self, field: &'static str, cap: usize) -> Result<String, CdrError> {
        let len = self.u32(field)? as usize;
        if len == 0 {
            // Some writers send an empty string as a bare zero length.
            return Ok(String::new());
        }
        if len > self.remaining() {
            return Err(self.error(
                field,
                format!(
                    "a string of {len} bytes, but only {} remain",
                    self.remaining()
                ),
            ));
        }
        if len - 1 > cap {
            return Err(self.error(
                field,
                format!("a string of {} bytes, over the cap of {cap}", len - 1),
            ));
        }
        let bytes = &self.bytes[self.pos..self.pos + len];
        self.pos += len;
        // The last byte is the terminating NUL.
        let text = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        Ok(String::from_utf8_lossy(text).into_owned())
    }

    /// A sequence's element count, checked: `count` elements of at least
    /// `min_element_bytes` each must fit in what remains, and `count <= cap`.
    pub fn sequence_len(
        &mut self,
        field: &'static str,
        min_element_bytes: usize,
        cap: usize,
    ) -> Result<usize, CdrError> {
        let count = self.u32(field)? as usize;
        if count > cap {
            return Err(self.error(
                field,
                format!("a sequence of {count} elements, over the cap of {cap}"),
            ));
        }
        let needed = count.saturating_mul(min_element_bytes.max(1));
        if needed > self.remaining() {
            return Err(self.error(
                field,
                format!(
                    "a sequence of {count} elements needs at least {needed} bytes, but only {} remain",
                    self.remaining()
                ),
            ));
        }
        Ok(count)
    }

    /// A `float32[]` of at most `cap` elements.
    pub fn f32_sequence(&mut self, field: &'static str, cap: usize) -> Result<Vec<f32>, CdrError> {
        let count = self.sequence_len(field, 4, cap)?;
        let mut out = Vec::with_capacity(count);
        for _ in 0..count {
            out.push(self.f32(field)?);
        }
        Ok(out)
    }

    /// Skips a `float32[]` of at most `cap` elements without keeping it.
    pub fn skip_f32_sequence(&mut self, field: &'static str, cap: usize) -> Result<(), CdrError> {
        let count = self.sequence_len(field, 4, cap)?;
        if count > 0 {
            self.align(4);
            self.pos += 4 * count;
            if self.pos > self.bytes.len() {
                return Err(self.error(field, "the sequence runs past the message's end"));
            }
        }
        Ok(())
    }
}

/// Writes one CDR-encoded message, little-endian (as ROS 2 on x86 and ARM).
#[derive(Debug, Clone)]
pub struct CdrWriter {
    bytes: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// A message with its little-endian encapsulation header (`00 01 00 00`).
    pub fn new() -> Self {
        Self {
            bytes: vec![0, 1, 0, 0],
        }
    }

    fn align(&mut self, size: usize) {
        let from_start = self.bytes.len() - HEADER;
        let pad = (size - from_start % size) % size;
        self.bytes.extend(std::iter::repeat_n(0u8, pad));
    }

    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32`.
    pub fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_bits().to_le_bytes());
    }

    /// A `string`: its length with the NUL, the bytes, the NUL.
    pub fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.bytes.extend_from_slice(s.as_bytes());
        self.bytes.push(0);
    }

    /// A sequence's element count.
    pub fn sequence_len(&mut self, count: usize) {
        self.u32(count as u32);
    }

    /// A `float32[]`.
    pub fn f32_sequence(&mut self, values: &[f32]) {
        self.sequence_len(values.len());
        for &v in values {
            self.f32(v);
        }
    }

    /// The message's bytes.
    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }
}
