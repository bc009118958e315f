//! How far the leaf surfels are: a count of the samples whose surfel is fitted, told
//! from the parallel loops that fit them, for `spt convert`'s bar and the viewer's.
//!
//! Each path ticks in its main loop, block by block (a count per sample would make
//! every thread fight over one atomic): a cloud's neighbourhoods
//! (`cloud::search::Search::map_neighbourhoods`), a mesh's, a terrain's or a frame's
//! rings (`ring::ring_shapes`). What comes before them (a cloud's search grid, a
//! mesh's face normals and rings, a terrain's first TIN and its layers) is a stage of
//! its own, with a share of the path's samples ([`Stages`]) measured from its time, so
//! that the bar moves through it at about the pace of the rest and its estimate of
//! the time left holds. [`Fitted`] keeps the told total at exactly the samples of the
//! build: ticks past it are dropped, and what the loops did not tell is told at the
//! end.

use std::sync::atomic::{AtomicU64, Ordering};

/// What hears a progress: called from any thread with how many more samples are done.
pub trait Listener: Sync {
    fn heard(&self, n: u64);
}

impl<F: Fn(u64) + Sync> Listener for F {
    fn heard(&self, n: u64) {
        self(n)
    }
}

/// A listener for fitted samples, passed down the paths by value.
#[derive(Clone, Copy)]
pub struct Progress<'a>(&'a dyn Listener);

impl<'a> Progress<'a> {
    /// A progress that ignores every count.
    pub const NONE: Progress<'static> = Progress(&|_| {});

    /// The progress that tells `listener`.
    pub fn to(listener: &'a dyn Listener) -> Progress<'a> {
        Progress(listener)
    }

    /// `n` more samples fitted.
    pub fn done(self, n: usize) {
        self.0.heard(n as u64)
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

    /// Tells what the ticks left of the total: the build is done.
    pub fn finish(&self) {
        let told = self.told.swap(self.total, Ordering::Relaxed);
        let rest = self.total.saturating_sub(told);
        if rest > 0 {
            self.listener.done(rest as usize);
        }
    }
}

impl Listener for Fitted<'_> {
    /// Takes `n` more, passing on what fits under the total.
    fn heard(&self, n: u64) {
        let before = self.told.fetch_add(n, Ordering::Relaxed);
        let passed = n.min(self.total.saturating_sub(before));
        if passed > 0 {
            self.listener.done(passed as usize);
        }
    }
}

/// A path's work on `samples` samples as stages that take known shares of its time:
/// a stage of weight w (of the weights W of the stages that run) tells w / W of the
/// samples, all at its end ([`Stages::ended`]) or, when its loop counts samples, as
/// they come ([`Stages::share`]). The weights are each stage's measured share of the
/// path's time, in percent.
pub struct Stages<'a> {
    samples: u64,
    weights: u32,
    listener: Progress<'a>,
}

impl<'a> Stages<'a> {
    /// `weights`: the sum of the weights of the stages that will run.
    pub fn new(samples: usize, weights: u32, listener: Progress<'a>) -> Stages<'a> {
        Stages {
            samples: samples as u64,
            weights: weights.max(1),
            listener,
        }
    }

    /// A stage of `weight` has ended: its share of the samples is told.
    pub fn ended(&self, weight: u32) {
        let share = self.samples * u64::from(weight) / u64::from(self.weights);
        self.listener.done(share as usize);
    }

    /// A stage of `weight` whose loop counts the samples: what it hears is told as
    /// `weight` / W of it.
    pub fn share(&self, weight: u32) -> Share<'a> {
        Share {
            heard: AtomicU64::new(0),
            weight: u64::from(weight),
            weights: u64::from(self.weights),
            listener: self.listener,
        }
    }
}

/// A stage's counts, scaled to its share: after counts adding up to c, it has told
/// ⌊c · w / W⌋ (each tick tells the difference of two such floors, so no rounding adds
/// up).
pub struct Share<'a> {
    heard: AtomicU64,
    weight: u64,
    weights: u64,
    listener: Progress<'a>,
}

impl Listener for Share<'_> {
    fn heard(&self, n: u64) {
        let before = self.heard.fetch_add(n, Ordering::Relaxed);
        let told =
            |c: u64| (u128::from(c) * u128::from(self.weight) / u128::from(self.weights)) as u64;
        let passed = told(before + n) - told(before);
        if passed > 0 {
            self.listener.done(passed as usize);
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
        fitted.heard(4);
        assert_eq!(heard.load(Ordering::Relaxed), 4);
        fitted.heard(9);
        assert_eq!(heard.load(Ordering::Relaxed), 10, "capped at the total");
        fitted.finish();
        assert_eq!(heard.load(Ordering::Relaxed), 10);
        let short = Fitted::new(7, Progress::to(&listener));
        short.heard(3);
        short.finish();
        assert_eq!(
            heard.load(Ordering::Relaxed),
            17,
            "the rest told at the end"
        );
    }

    #[test]
    fn stages_tell_their_shares_without_rounding_drift() {
        let heard = AtomicU64::new(0);
        let listener = |n: u64| {
            heard.fetch_add(n, Ordering::Relaxed);
        };
        let stages = Stages::new(1000, 30 + 70, Progress::to(&listener));
        stages.ended(30);
        assert_eq!(heard.load(Ordering::Relaxed), 300);
        let share = stages.share(70);
        // 1000 samples counted in ticks of 3 (and one of 1): each alone rounds to 2.
        for _ in 0..333 {
            share.heard(3);
        }
        assert_eq!(heard.load(Ordering::Relaxed), 300 + 699);
        share.heard(1);
        assert_eq!(
            heard.load(Ordering::Relaxed),
            1000,
            "⌊1000 · 70 / 100⌋ told"
        );
    }
}
