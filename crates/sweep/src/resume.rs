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
    // Indices in file order (not sorted, possibly repeated after a
    // concatenation); Done sorts and deduplicates them once at the end.
    let mut indices = Vec::new();
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
                    "a record of another sweep (id {}; this sweep's id is {id}): the spec, the ranges, the sampling or the level differ",
                    exact::quote(s, 40) // ids are 16 hex digits; a line may be megabytes
                )));
            }
            None => return Err(foreign("not a sweep record (no \"sweep\" id)".into())),
        }
        let index = v.get("index").and_then(Value::as_u64).filter(|&i| i < len);
        let Some(index) = index else {
            return Err(foreign(format!("no valid \"index\" below {len}")));
        };
        indices.push(index);
        out.valid_len = start as u64;
    }
    out.done = Done::from_indices(indices);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn file_with(name: &str, text: &str) -> (std::path::PathBuf, std::fs::File) {
        let path = std::env::temp_dir().join(format!("sweep-resume-{name}-{}", std::process::id()));
        std::fs::File::create(&path).unwrap().write_all(text.as_bytes()).unwrap();
        let file = std::fs::File::open(&path).unwrap();
        (path, file)
    }

    /// A resume of a 10^12-point grid whose only line carries an index near
    /// 10^12: the old bitset allocated index/8 bytes (125 GB) here; the
    /// points done now take one entry.
    #[test]
    fn resume_near_a_huge_index_stores_one_entry() {
        let range = |name: &str| spec::ParamRange::parse(&format!("{name}=0:1:1000000")).unwrap();
        let plan = crate::Plan::new(vec![range("p"), range("q")], crate::Sampling::Grid).unwrap();
        let len = plan.len();
        assert_eq!(len, 1_000_000_000_000);
        let last = len - 1;
        let (path, mut file) = file_with("huge", &format!("{{\"sweep\":\"abc\",\"index\":{last}}}\n"));
        let existing = scan(&mut file, "abc", len).unwrap();
        assert_eq!(existing.done.len(), 1);
        assert_eq!(existing.done.stored(), 1);
        assert!(existing.done.contains(last));
        assert!(!existing.done.contains(last - 1) && !existing.done.contains(0));
        std::fs::remove_file(path).unwrap();
    }

    /// Lines out of order and repeated (concatenated shards of one sweep)
    /// count once each.
    #[test]
    fn repeated_and_unordered_lines_count_once() {
        let text: String =
            [5u64, 1, 5, 3, 1].iter().map(|i| format!("{{\"sweep\":\"abc\",\"index\":{i}}}\n")).collect();
        let (path, mut file) = file_with("unordered", &text);
        let existing = scan(&mut file, "abc", 10).unwrap();
        assert_eq!(existing.done.len(), 3);
        let done: Vec<u64> = (0..10).filter(|i| existing.done.contains(*i)).collect();
        assert_eq!(done, [1, 3, 5]);
        std::fs::remove_file(path).unwrap();
    }

    /// A foreign id of a megabyte is quoted as an excerpt.
    #[test]
    fn a_huge_foreign_id_is_not_echoed() {
        let id = "z".repeat(1_000_000);
        let (path, mut file) = file_with("foreign", &format!("{{\"sweep\":\"{id}\",\"index\":0}}\n"));
        let message = scan(&mut file, "abc", 10).unwrap_err().to_string();
        // 40 characters kept, plus the fixed explanation (about 200 bytes).
        assert!(message.len() < 400, "{} bytes", message.len());
        assert!(message.contains("(1000000 bytes)"), "{message}");
        std::fs::remove_file(path).unwrap();
    }
}
