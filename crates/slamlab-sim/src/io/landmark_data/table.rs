//! The plain-text tables all three data sets use: one record a line, fields
//! separated by white space (MRCLAM pads tabs with spaces and ends lines with a
//! space), `#` comment lines, numbers in decimal or exponent form.

use super::{DataError, DataFile, MAX_FILE_BYTES};

/// A file's text, after its size is checked; invalid UTF-8 is refused with the
/// line it is on.
pub(super) fn text(file: &DataFile) -> Result<&str, DataError> {
    if file.bytes.len() > MAX_FILE_BYTES {
        return Err(DataError::file(
            &file.name,
            format!(
                "{} bytes, over the cap of {MAX_FILE_BYTES} bytes for one data file",
                file.bytes.len()
            ),
        ));
    }
    std::str::from_utf8(&file.bytes).map_err(|e| {
        let line = 1 + file.bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        DataError::line(&file.name, line, "not text (invalid UTF-8)")
    })
}

/// The lines that hold records: `(1-based line number, fields)`, comments
/// (`#`) and blank lines skipped.
pub(super) fn records(text: &str) -> impl Iterator<Item = (usize, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(i, line)| {
        let line = line.trim();
        (!line.is_empty() && !line.starts_with('#'))
            .then(|| (i + 1, line.split_whitespace().collect()))
    })
}

/// A table whose every record has the columns named in `columns`, all numbers:
/// `(line, values)`. A record with another number of fields, or a field that is
/// not a finite number, is refused with its line.
pub(super) fn numeric_rows<const N: usize>(
    file: &DataFile,
    columns: [&str; N],
) -> Result<Vec<(usize, [f64; N])>, DataError> {
    let text = text(file)?;
    let mut rows = Vec::new();
    for (line, fields) in records(text) {
        if fields.len() != N {
            return Err(DataError::line(
                &file.name,
                line,
                format!(
                    "{} field{}, expected {N}: {}",
                    fields.len(),
                    if fields.len() == 1 { "" } else { "s" },
                    columns.join(", ")
                ),
            ));
        }
        let mut values = [0.0; N];
        for (k, field) in fields.iter().enumerate() {
            values[k] = number(file, line, columns[k], field)?;
        }
        rows.push((line, values));
    }
    Ok(rows)
}

/// `field` as a finite number, or a refusal naming the line and the column.
pub(super) fn number(
    file: &DataFile,
    line: usize,
    column: &str,
    field: &str,
) -> Result<f64, DataError> {
    match field.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(DataError::line(
            &file.name,
            line,
            format!("{column} '{field}' is not a finite number"),
        )),
        Err(_) => Err(DataError::line(
            &file.name,
            line,
            format!("{column} '{}' is not a number", shorten(field)),
        )),
    }
}

/// `value` as a whole number in `0..=max`, or a refusal naming the line and the column.
pub(super) fn whole(
    file: &DataFile,
    line: usize,
    column: &str,
    value: f64,
    max: u32,
) -> Result<u32, DataError> {
    if value.fract() == 0.0 && (0.0..=f64::from(max)).contains(&value) {
        Ok(value as u32)
    } else {
        Err(DataError::line(
            &file.name,
            line,
            format!("{column} {value} is not a whole number from 0 to {max}"),
        ))
    }
}

/// Refuses a time earlier than the previous record's (equal times are one
/// camera image or laser scan, and are kept).
pub(super) fn check_time_order(
    file: &DataFile,
    rows: impl Iterator<Item = (usize, f64)>,
) -> Result<(), DataError> {
    let mut previous: Option<(usize, f64)> = None;
    for (line, time) in rows {
        if let Some((previous_line, previous_time)) = previous
            && time < previous_time
        {
            return Err(DataError::line(
                &file.name,
                line,
                format!(
                    "time {time} s goes back from {previous_time} s (line {previous_line}): \
                     the records must be in time order"
                ),
            ));
        }
        previous = Some((line, time));
    }
    Ok(())
}

/// Refuses a negative range.
pub(super) fn check_range(file: &DataFile, line: usize, range: f64) -> Result<(), DataError> {
    if range < 0.0 {
        return Err(DataError::line(
            &file.name,
            line,
            format!("range {range} m is negative"),
        ));
    }
    Ok(())
}

/// At most 40 characters of `field`, for a message.
pub(super) fn shorten(field: &str) -> String {
    let mut s: String = field.chars().take(40).collect();
    if s.len() < field.len() {
        s.push('…');
    }
    s
}
