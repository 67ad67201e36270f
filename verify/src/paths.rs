//! Output paths: file stems made from input data (a spec's or certificate's
//! `name`), the checks on output files and directories named on the command
//! line, and atomic whole-file writes.
//!
//! An output *file* named `-` ([`STDOUT`]: `-o -`, `--npz -`) is standard
//! output, as in most Unix tools; an output *directory* named `-` (`--out`,
//! `--plot`) is refused ([`ensure_output_dir`]): several files cannot go to
//! one stream, and a directory literally named `-` is never what was meant.
//!
//! A name is data, never a path: [`file_stem`] maps any string to a stem that
//! cannot leave the output directory, whatever it holds (`../x`, `/abs/x`,
//! NUL, a 50 MB string).

use crate::Failure;
use std::ffi::OsString;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Longest file stem made from a name, in bytes. The suffixes appended to it
/// (`-convergence.png` is the longest, 16 bytes) keep file names far below
/// the 255-byte limit of common filesystems.
pub const MAX_STEM_BYTES: usize = 100;

/// The stem used when a name keeps nothing (empty, or only dots).
const EMPTY_STEM: &str = "unnamed";

/// A safe file stem for `name`: ASCII letters, digits, `.`, `_` and `-` are
/// kept, every other character becomes one `_`, leading dots are dropped
/// (no hidden files, never `.` or `..`), at most [`MAX_STEM_BYTES`] bytes,
/// never empty. The result contains no path separator, so joining it to a
/// directory stays inside that directory.
pub fn file_stem(name: &str) -> String {
    let mut stem = String::with_capacity(name.len().min(MAX_STEM_BYTES));
    for c in name.chars() {
        let c = if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') { c } else { '_' };
        if stem.is_empty() && c == '.' {
            continue;
        }
        stem.push(c);
        // Every kept character is ASCII (one byte), so this bounds the bytes.
        if stem.len() == MAX_STEM_BYTES {
            break;
        }
    }
    if stem.is_empty() {
        stem.push_str(EMPTY_STEM);
    }
    stem
}

/// [`file_stem`], with a note on stderr when the stem differs from the name,
/// so the user can find the files.
pub fn file_stem_noted(name: &str) -> String {
    let stem = file_stem(name);
    if stem != name {
        eprintln!("note: the name '{}' is written as the file stem '{stem}'", crate::messages::excerpt(name));
    }
    stem
}

/// `path` with `suffix` appended to its last component (`a/b.c` + `.svg` is
/// `a/b.c.svg`). Unlike [`Path::with_extension`] it never replaces a dot
/// inside a stem such as `v1.2`.
pub fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s: OsString = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

/// The name of standard output where the command line names an output file.
pub const STDOUT: &str = "-";

/// Whether an output file named on the command line is [`STDOUT`].
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == STDOUT
}

/// Write a whole output named on the command line: to standard output for
/// [`STDOUT`], else atomically to the file ([`write_atomic`]).
pub fn write_output(path: &Path, bytes: &[u8]) -> io::Result<()> {
    if is_stdout(path) {
        let mut out = io::stdout().lock();
        out.write_all(bytes)?;
        out.flush()
    } else {
        write_atomic(path, bytes)
    }
}

/// How an output file named on the command line is shown in messages.
pub fn shown(path: &Path) -> String {
    if is_stdout(path) {
        "standard output".to_string()
    } else {
        path.display().to_string()
    }
}

/// Refuse [`STDOUT`] for a second output (`flag`) when `other` (shown as
/// `other_flag`) goes there too: two files cannot share one stream.
pub fn check_one_stdout(path: &Path, flag: &str, other: &Path, other_flag: &str) -> Result<(), Failure> {
    if is_stdout(path) && is_stdout(other) {
        return Err(Failure::BadInput(format!(
            "{flag} - and {other_flag} -: only one output can go to standard output; name a file for the other"
        )));
    }
    Ok(())
}

/// Check an output file named on the command line (`flag FILE`) before any
/// work: its directory must exist (it is not created), and it must not be a
/// directory. Both are bad input (exit status 2). [`STDOUT`] passes.
pub fn check_output_file(path: &Path, flag: &str) -> Result<(), Failure> {
    if is_stdout(path) {
        return Ok(());
    }
    if path.is_dir() {
        return Err(Failure::BadInput(format!("{flag} {}: is a directory, not a file", path.display())));
    }
    if path.file_name().is_none() {
        return Err(Failure::BadInput(format!("{flag} {}: names no file", path.display())));
    }
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(Failure::BadInput(format!(
            "{flag} {}: the directory {} does not exist (create it first)",
            path.display(),
            dir.display()
        ))),
        _ => Ok(()),
    }
}

/// Refuse a second output (`flag PATH`) that names the same file as another
/// output or an input (`other`, shown as `other_flag`): writing it would
/// overwrite what the run reads or writes. Compared after resolving links
/// and `..` where the files exist, else as written.
pub fn check_distinct(path: &Path, flag: &str, other: &Path, other_flag: &str) -> Result<(), Failure> {
    let resolve = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    if path == other || resolve(path) == resolve(other) {
        return Err(Failure::BadInput(format!(
            "{flag} {}: the same file as {other_flag} {}; choose another name",
            path.display(),
            other.display()
        )));
    }
    Ok(())
}

/// Create an output directory named on the command line (`flag DIR`) if it
/// is missing. A path that cannot be a directory (a file is in the way, no
/// permission) is bad input: exit status 2, naming the flag and the path.
/// It must also be writable, checked with a probe file, so that a long
/// computation does not end in a failed write.
pub fn ensure_output_dir(path: &Path, flag: &str) -> Result<(), Failure> {
    if is_stdout(path) {
        return Err(Failure::BadInput(format!(
            "{flag} -: {flag} names a directory for several files, which cannot go to standard output; name a directory (`{flag} ./-` if you really mean one called '-')"
        )));
    }
    std::fs::create_dir_all(path).map_err(|e| {
        Failure::BadInput(format!("{flag} {}: cannot create the output directory: {e}", path.display()))
    })?;
    let probe = temporary_path(&path.join("probe"))
        .and_then(|p| std::fs::OpenOptions::new().write(true).create_new(true).open(&p).map(|_| p));
    match probe {
        Ok(p) => {
            let _ = std::fs::remove_file(p);
            Ok(())
        }
        Err(e) => Err(Failure::BadInput(format!("{flag} {}: cannot write into the directory: {e}", path.display()))),
    }
}

/// The failure for an error while writing `path`: the user's choice of path
/// (no permission, read-only filesystem, a directory in the way, a missing
/// directory) is bad input (exit status 2); anything else (a full disk, an
/// I/O error) is a failure (exit status 1).
pub fn write_failure(path: &Path, e: &io::Error) -> Failure {
    use io::ErrorKind::*;
    if is_stdout(path) {
        return Failure::Failed(format!("standard output: cannot write: {e}"));
    }
    let message = format!("{}: cannot write: {e} (nothing was written; an existing file is unchanged)", path.display());
    match e.kind() {
        PermissionDenied | NotFound | IsADirectory | NotADirectory | ReadOnlyFilesystem | InvalidInput => {
            Failure::BadInput(message)
        }
        _ => Failure::Failed(message),
    }
}

/// Write `bytes` to `path` atomically: see [`write_atomic_with`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |target| {
        let mut file = if is_special(target) {
            std::fs::OpenOptions::new().write(true).open(target)?
        } else {
            // A fresh temporary name: never follow a file planted there.
            std::fs::OpenOptions::new().write(true).create_new(true).open(target)?
        };
        file.write_all(bytes)?;
        file.flush()
    })
}

/// Whether `path` exists and is neither a regular file nor a directory (a
/// device such as `/dev/stdout` or `/dev/full`, a FIFO): such a file is
/// written in place, never replaced by a rename.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Make `path` by letting `produce` write a temporary file in the same
/// directory, flushing it to disk, then renaming it over `path`. A failure
/// at any step (a full disk, say) removes the temporary file and leaves
/// `path` as it was: never a partial or empty file, and an existing file is
/// not destroyed. The temporary name keeps `path`'s extension, because some
/// writers (the PNG encoder) choose the format by it.
///
/// A symbolic link is followed (its target is replaced, the link kept);
/// a device or FIFO (`-o /dev/stdout`) is written in place.
pub fn write_atomic_with(path: &Path, produce: impl FnOnce(&Path) -> io::Result<()>) -> io::Result<()> {
    if is_special(path) {
        return produce(path);
    }
    let resolved;
    let path = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            resolved = std::fs::canonicalize(path)?;
            resolved.as_path()
        }
        _ => path,
    };
    let tmp = temporary_path(path)?;
    let result =
        produce(&tmp).and_then(|()| std::fs::File::open(&tmp)?.sync_all()).and_then(|()| std::fs::rename(&tmp, path));
    match result {
        Ok(()) => {
            // Persist the rename itself; a failure here loses nothing that
            // is not already visible, so it is not reported.
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                let _ = std::fs::File::open(dir).and_then(|d| d.sync_all());
            }
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// `.DIR/.tmp-PID-N-NAME`: hidden, unique within the process and across
/// processes, in the same directory as `path` (so the rename is atomic).
fn temporary_path(path: &Path) -> io::Result<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?
        .to_string_lossy();
    // Keep the end of the name (its extension) within the filesystem's
    // 255-byte limit once the prefix is added.
    let mut start = name.len().saturating_sub(200);
    while !name.is_char_boundary(start) {
        start += 1;
    }
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp_name = format!(".tmp-{}-{n}-{}", std::process::id(), &name[start..]);
    Ok(path.with_file_name(tmp_name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn assert_safe(stem: &str) {
        assert!(!stem.is_empty());
        assert!(stem.len() <= MAX_STEM_BYTES, "{} bytes", stem.len());
        assert!(stem != "." && stem != "..");
        assert!(!stem.starts_with('.'), "{stem}");
        assert!(!stem.contains(['/', '\\', '\0']), "{stem}");
        assert!(stem.bytes().all(|b| b.is_ascii_alphanumeric() || b"._-".contains(&b)), "{stem}");
        // Joined to a directory, the stem is one normal component inside it.
        let joined = Path::new("/out").join(stem);
        assert_eq!(joined.parent(), Some(Path::new("/out")), "{stem}");
    }

    #[test]
    fn hostile_names_become_plain_stems() {
        let cases = [
            ("rigid-body-major-axis", "rigid-body-major-axis"),
            ("../escape", "_escape"),
            ("/tmp/abs", "_tmp_abs"),
            ("a/../../b", "a_.._.._b"),
            ("..", "unnamed"),
            (".", "unnamed"),
            ("", "unnamed"),
            (".hidden", "hidden"),
            ("v1.2", "v1.2"),
            ("C:\\win\\x", "C__win_x"),
            ("nul\0byte", "nul_byte"),
            ("héllo wörld", "h_llo_w_rld"),
        ];
        for (name, stem) in cases {
            assert_eq!(file_stem(name), stem, "{name:?}");
            assert_safe(&file_stem(name));
        }
        // A long name is cut at MAX_STEM_BYTES (ASCII: one byte a character).
        assert_eq!(file_stem(&"x".repeat(10_000)), "x".repeat(MAX_STEM_BYTES));
    }

    #[test]
    fn suffix_keeps_dots_in_the_stem() {
        // with_extension would give "v1.svg" and "v1.json": distinct names collide.
        assert_eq!(with_suffix(Path::new("out/v1.2-density"), ".svg"), Path::new("out/v1.2-density.svg"));
    }

    #[test]
    fn atomic_write_replaces_or_leaves_the_file_unchanged() {
        let dir = std::env::temp_dir().join(format!("verify-atomic-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("cert.json");
        write_atomic(&path, b"first").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        // A producer that writes part of the file and then fails (as a full
        // disk would) must leave the old contents and no temporary file.
        let failed = write_atomic_with(&path, |tmp| {
            std::fs::write(tmp, b"par")?;
            Err(io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("cert.json")], "no temporary file is left");
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_written_in_place_and_links_kept() {
        // /dev/null must stay a device: replacing it by a rename would
        // break the machine (found by writing to /dev/full).
        write_atomic(Path::new("/dev/null"), b"discarded").unwrap();
        assert!(std::fs::metadata("/dev/null").is_ok_and(|m| !m.is_file()));
        // A full device fails and stays a device.
        if Path::new("/dev/full").exists() {
            assert!(write_atomic(Path::new("/dev/full"), b"x").is_err());
            assert!(std::fs::metadata("/dev/full").is_ok_and(|m| !m.is_file()));
        }
        let dir = std::env::temp_dir().join(format!("verify-atomic-link-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("target.json");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("link.json");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    proptest! {
        #[test]
        fn any_string_gives_a_safe_stem(name in any::<String>()) {
            assert_safe(&file_stem(&name));
        }

        #[test]
        fn path_like_strings_give_a_safe_stem(parts in proptest::collection::vec("[./\\\\a-z\u{0}-\u{1f}é]{0,6}", 0..8)) {
            let name = parts.join("/");
            assert_safe(&file_stem(&name));
        }

        #[test]
        fn safe_names_are_kept(name in "[A-Za-z0-9_-][A-Za-z0-9._-]{0,99}") {
            prop_assert_eq!(file_stem(&name), name);
        }
    }
}
