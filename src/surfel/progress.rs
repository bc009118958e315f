//! How far the leaf surfels are: a count of the samples whose surfel is fitted, told
//! from the parallel loops that fit them, for `spt convert`'s bar and the viewer's.
//!
//! Each path ticks in its main loop, block by block (a count per sample would make
//! every thread fight over one atomic): a cloud's neighbourhoods
//! (`cloud::search::Search::map_neighbourhoods`), a mesh's, a terrain's or a frame's
//! rings (`ring::ring_shapes`). What comes before them (the search's grid, a TIN) is
//! not counted. [`Fitted`] keeps the told total at exactly the samples of the build:
//! ticks past it are dropped, and what the loops did not tell is told at the end.

use std::sync::atomic::{AtomicU64, Ordering};

/// A listener for fitted samples: called from any thread with how many more are done.
#[derive(Clone, Copy)]
pub struct Progress<'a>(&'a (dyn Fn(u64) + Sync));

impl<'a> Progress<'a> {
    /// A progress that ignores every count.
    pub const NONE: Progress<'static> = Progress(&|_| {});

    /// The progress that tells `listener`.
    pub fn to(listener: &'a (dyn Fn(u64) + Sync)) -> Progress<'a> {
        Progress(listener)
    }

    /// `n` more samples fitted.
    pub fn done(self, n: usize) {
        (self.0)(n as u64)
    }
}

/// Counts the ticks of one build of `total` samples and passes them on, at most
/// `total` in all ([`Fitted::finish`] tells the rest).
pub struct Fitted<'a> {
    told: AtomicU64,
    total: u64,
    listener: Progress<'a>,
}

impl<'a> Fitted<'a> {
    pub fn new(total: usize, listener: Progress<'a>) -> Fitted<'a> {
        Fitted {
            told: AtomicU64::new(0),
            total: total as u64,
            listener,
        }
    }

    /// Takes `n` more, passing on what fits under the total.
    pub fn tick(&self, n: u64) {
        let before = self.told.fetch_add(n, Ordering::Relaxed);
        let passed = n.min(self.total.saturating_sub(before));
        if passed > 0 {
            self.listener.done(passed as usize);
        }
    }

    /// Tells what the ticks left of the total: the build is done.
    pub fn finish(&self) {
        let told = self.told.swap(self.total, Ordering::Relaxed);
        let rest = self.total.saturating_sub(told);
        if rest > 0 {
            self.listener.done(rest as usize);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_told_counts_add_up_to_the_total() {
        let heard = AtomicU64::new(0);
        let listener = |n: u64| {
            heard.fetch_add(n, Ordering::Relaxed);
        };
        let fitted = Fitted::new(10, Progress::to(&listener));
        fitted.tick(4);
        assert_eq!(heard.load(Ordering::Relaxed), 4);
        fitted.tick(9);
        assert_eq!(heard.load(Ordering::Relaxed), 10, "capped at the total");
        fitted.finish();
        assert_eq!(heard.load(Ordering::Relaxed), 10);
        let short = Fitted::new(7, Progress::to(&listener));
        short.tick(3);
        short.finish();
        assert_eq!(
            heard.load(Ordering::Relaxed),
            17,
            "the rest told at the end"
        );
    }
}
