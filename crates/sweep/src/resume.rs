//! Reading back a sweep's output file to resume it.

use crate::run::Done;
use serde_json::Value;
use std::io::{self, Read, Seek, SeekFrom};

/// What an existing output file holds.
#[derive(Debug, Default)]
pub struct Existing {
    /// The points with a complete line.
    pub done: Done,
    /// Bytes of complete lines: anything after (a line cut short by a kill)
    /// must be truncated away before appending.
    pub valid_len: u64,
    /// Whether a partial last line was found.
    pub truncated_line: bool,
}

/// Why a file cannot be resumed.
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    /// Reading failed.
    #[error("cannot read: {0}")]
    Io(#[from] io::Error),
    /// A complete line that is not a record of this sweep.
    #[error("line {line}: {message}")]
    Foreign {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// Scan `file` for the lines of sweep `id` with indices below `len`.
///
/// A complete line is one ending in a newline. Every complete line must be a
/// record of this sweep (same `sweep` id, an `index` below `len`); anything
/// else is refused rather than silently mixed. Only the last line may be
/// incomplete (the process was killed while writing it); it is reported so
/// the caller truncates it and computes that point again.
pub fn scan(file: &mut std::fs::File, id: &str, len: u64) -> Result<Existing, ResumeError> {
    file.seek(SeekFrom::Start(0))?;
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes)?;
    let mut out = Existing::default();
    let mut start = 0usize;
    let mut line_no = 0usize;
    while start < bytes.len() {
        let Some(nl) = bytes[start..].iter().position(|&b| b == b'\n') else {
            out.truncated_line = true;
            break;
        };
        line_no += 1;
        let line = &bytes[start..start + nl];
        start += nl + 1;
        if line.iter().all(u8::is_ascii_whitespace) {
            out.valid_len = start as u64;
            continue;
        }
        let foreign = |message: String| ResumeError::Foreign { line: line_no, message };
        let v: Value = serde_json::from_slice(line).map_err(|e| foreign(format!("not a JSON record: {e}")))?;
        match v.get("sweep").and_then(Value::as_str) {
            Some(s) if s == id => {}
            Some(s) => {
                return Err(foreign(format!(
                    "a record of another sweep (id {s}; this sweep's id is {id}): the spec, the ranges, the sampling or the level differ"
                )))
            }
            None => return Err(foreign("not a sweep record (no \"sweep\" id)".into())),
        }
        let index = v.get("index").and_then(Value::as_u64).filter(|&i| i < len);
        let Some(index) = index else {
            return Err(foreign(format!("no valid \"index\" below {len}")));
        };
        out.done.insert(index);
        out.valid_len = start as u64;
    }
    Ok(out)
}
