//! Progress of a long analysis, and a request to stop it early.
//!
//! The pipelines that can run for seconds or minutes (fluids, the Zeitlin
//! model, large systems) count their steps in a [`Progress`] and look at
//! [`Progress::is_cancelled`] between steps. A caller on another thread
//! reads [`Progress::snapshot`] to draw a bar and calls
//! [`Progress::cancel`] to stop the work (Ctrl-C in Python). A cancelled
//! analysis returns an error that says so ([`Cancelled`]); it never returns
//! a verdict, so an interrupted run cannot leave a certificate behind.
//!
//! An analysis plans its whole total first ([`Progress::plan`]), so the
//! fraction done only grows. A phase whose length is not known in advance
//! (a search) is given a budget ([`Progress::phase`]): its steps count up
//! to the budget and no further (a search that runs long holds the count at
//! the phase's end instead of running it to the total), and when it ends
//! early its unused steps count as done. `done` never passes `total`, and
//! [`Progress::settle`] brings it there when the work is over.
//!
//! ```
//! use outcome::Progress;
//! let p = Progress::new();
//! p.plan(30);
//! {
//!     let _search = p.phase(20); // at most 20 steps
//!     p.step(4);
//!     assert_eq!(p.snapshot(), (4, 30));
//! } // it ended after 4: the other 16 count as done
//! assert_eq!(p.snapshot(), (20, 30));
//! p.settle();
//! assert_eq!(p.snapshot(), (30, 30));
//! p.cancel();
//! assert!(p.is_cancelled());
//! ```

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Steps done, steps planned, and whether the work should stop (shared
/// between the working threads and an observer; every method takes `&self`).
#[derive(Debug)]
pub struct Progress {
    done: AtomicU64,
    total: AtomicU64,
    /// The end of the innermost open phase (`u64::MAX` outside phases).
    ceiling: AtomicU64,
    cancelled: AtomicBool,
}

impl Default for Progress {
    fn default() -> Progress {
        Progress {
            done: AtomicU64::new(0),
            total: AtomicU64::new(0),
            ceiling: AtomicU64::new(u64::MAX),
            cancelled: AtomicBool::new(false),
        }
    }
}

/// The work stopped early because [`Progress::cancel`] was called.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the analysis was cancelled before it finished")]
pub struct Cancelled;

impl Progress {
    /// Nothing planned, nothing done, not cancelled.
    pub fn new() -> Progress {
        Progress::default()
    }

    /// Plan `steps` more steps (the next phase).
    pub fn plan(&self, steps: u64) {
        self.total.fetch_add(steps, Ordering::Relaxed);
    }

    /// `steps` more steps are done (never counted past the plan, nor past
    /// the end of the open phase; never moving `done` back).
    pub fn step(&self, steps: u64) {
        let limit = self.total.load(Ordering::Relaxed).min(self.ceiling.load(Ordering::Relaxed));
        let _ = self
            .done
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |d| Some(d.max(d.saturating_add(steps).min(limit))));
    }

    /// A phase of `steps` steps, starting now: until the returned guard is
    /// dropped, steps count only up to its end; when it is dropped, `done`
    /// is at least that end. Phases nest (the guards are dropped in
    /// reverse order of creation).
    pub fn phase(&self, steps: u64) -> Phase<'_> {
        let outer = self.ceiling.load(Ordering::Relaxed);
        let end = self.done.load(Ordering::Relaxed).saturating_add(steps).min(outer);
        self.ceiling.store(end, Ordering::Relaxed);
        Phase { progress: self, end, outer }
    }

    /// Every planned step counts as done: the work is over.
    pub fn settle(&self) {
        self.done.fetch_max(self.total.load(Ordering::Relaxed), Ordering::Relaxed);
    }

    /// `(done, total)`, with `done <= total`.
    pub fn snapshot(&self) -> (u64, u64) {
        let total = self.total.load(Ordering::Relaxed);
        (self.done.load(Ordering::Relaxed).min(total), total)
    }

    /// Ask the work to stop at its next step.
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Release);
    }

    /// Whether [`Progress::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Acquire)
    }

    /// `Err(Cancelled)` once [`Progress::cancel`] was called: `progress.check()?`
    /// between the phases of an analysis.
    pub fn check(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }

    /// The cancellation flag itself, for code that takes an `AtomicBool`.
    pub fn cancel_flag(&self) -> &AtomicBool {
        &self.cancelled
    }
}

/// A phase of a [`Progress`] (see [`Progress::phase`]).
#[derive(Debug)]
#[must_use = "the phase ends when the guard is dropped"]
pub struct Phase<'a> {
    progress: &'a Progress,
    end: u64,
    outer: u64,
}

impl Drop for Phase<'_> {
    fn drop(&mut self) {
        let total = self.progress.total.load(Ordering::Relaxed);
        self.progress.done.fetch_max(self.end.min(total), Ordering::Relaxed);
        self.progress.ceiling.store(self.outer, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps from many threads add up; `done` stops at the plan and a
    /// settle brings it there; `check` turns a cancel into an error.
    #[test]
    fn counts_across_threads_and_never_passes_the_plan() {
        let p = Progress::new();
        p.plan(1000);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| (0..100).for_each(|_| p.step(1)));
            }
        });
        assert_eq!(p.snapshot(), (400, 1000));
        p.step(5000);
        assert_eq!(p.snapshot(), (1000, 1000));
        p.plan(7);
        assert_eq!(p.snapshot(), (1000, 1007));
        p.settle();
        assert_eq!(p.snapshot(), (1007, 1007));
        assert_eq!(p.check(), Ok(()));
        p.cancel();
        assert_eq!(p.check(), Err(Cancelled));
        assert!(p.cancel_flag().load(Ordering::Relaxed));
    }

    /// A phase caps its steps at its end (a long search holds the count
    /// there), phases nest, and a phase ended early counts as done.
    #[test]
    fn phases_cap_their_steps_and_nest() {
        let p = Progress::new();
        p.plan(100);
        {
            let _outer = p.phase(50);
            p.step(10);
            {
                let _inner = p.phase(20);
                p.step(1000);
                assert_eq!(p.snapshot(), (30, 100), "held at the inner phase's end");
            }
            p.step(1000);
            assert_eq!(p.snapshot(), (50, 100), "held at the outer phase's end");
        }
        p.step(5);
        assert_eq!(p.snapshot(), (55, 100));
        {
            let _short = p.phase(30);
            p.step(2);
        }
        assert_eq!(p.snapshot(), (85, 100), "the unused 28 count as done");
    }
}
