//! rayon's global pool, sized once in `main`: `RAYON_NUM_THREADS` when it is
//! a positive integer, else the available parallelism, and never more than
//! [`cap`]. Each thread reserves a stack and, in `simulate`, its own
//! statistics; 10 000 threads on 2 cores took 97 s and 1.2 GB for a run of
//! a second.

use crate::messages::excerpt;
use std::ffi::OsStr;

/// Most threads on any machine.
pub const MAX_THREADS: usize = 256;

/// Threads per available core at most: oversubscription beyond this only
/// adds scheduling and memory.
pub const THREADS_PER_CORE: usize = 4;

/// The most threads used with `available` cores: `4 × available`, at most 256.
pub fn cap(available: usize) -> usize {
    (THREADS_PER_CORE * available.max(1)).min(MAX_THREADS)
}

/// The thread count for the value of `RAYON_NUM_THREADS` (if set) on a
/// machine with `available` cores, and a note for stderr when the value is
/// not used as given.
pub fn choose(requested: Option<&OsStr>, available: usize) -> (usize, Option<String>) {
    let available = available.max(1);
    let cap = cap(available);
    let Some(raw) = requested else { return (available, None) };
    let text = raw.to_string_lossy();
    let trimmed = text.trim();
    let digits = !trimmed.is_empty() && trimmed.bytes().all(|b| b.is_ascii_digit());
    // All digits but too large for usize is still a (huge) positive integer.
    let value = if digits { Some(trimmed.parse::<usize>().unwrap_or(usize::MAX)) } else { None };
    match value {
        Some(n) if n > cap => (
            cap,
            Some(format!(
                "note: RAYON_NUM_THREADS={}: capped at {cap} threads ({THREADS_PER_CORE} x the {available} available cores, at most {MAX_THREADS})",
                excerpt(trimmed)
            )),
        ),
        Some(n) if n > 0 => (n, None),
        _ => (
            available,
            Some(format!(
                "note: RAYON_NUM_THREADS='{}' is not a positive integer; using {available} threads",
                excerpt(&text)
            )),
        ),
    }
}

/// Build rayon's global pool from the environment, printing a note when
/// `RAYON_NUM_THREADS` is capped or ignored.
pub fn configure_global_pool() {
    let available = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let requested = std::env::var_os("RAYON_NUM_THREADS");
    let (threads, note) = choose(requested.as_deref(), available);
    if let Some(note) = note {
        eprintln!("{note}");
    }
    if let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(threads).build_global() {
        // Only possible if a pool exists already; rayon's default then runs.
        eprintln!("note: could not size the thread pool ({e}); using rayon's default");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pick(v: &str, cores: usize) -> (usize, bool) {
        let (n, note) = choose(Some(OsStr::new(v)), cores);
        (n, note.is_some())
    }

    #[test]
    fn valid_counts_within_the_cap_are_used() {
        assert_eq!(choose(None, 2), (2, None));
        assert_eq!(pick("1", 2), (1, false));
        // 4 x 2 cores = 8 is the cap itself: allowed, no note.
        assert_eq!(pick("8", 2), (8, false));
    }

    #[test]
    fn huge_counts_are_capped_with_a_note() {
        assert_eq!(pick("10000", 2), (8, true));
        assert_eq!(pick("99999999999999999999999999", 2), (8, true));
        // 4 x 100 cores = 400 exceeds the absolute cap of 256.
        assert_eq!(pick("10000", 100), (MAX_THREADS, true));
    }

    #[test]
    fn invalid_values_fall_back_to_the_cores_with_a_note() {
        for v in ["0", "-3", "two", "", "1.5"] {
            assert_eq!(pick(v, 2), (2, true), "{v:?}");
        }
    }
}
