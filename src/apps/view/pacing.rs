//! A held frame time (`--target-ms`): while the camera moves, the viewer draws with an
//! ε_px of its own, adapted each frame so that frames take the target time; once the
//! camera has rested for [`REST`], it draws with the user's ε_px again.
//!
//! The adaptation works on logarithms. With s = d ln t / d ln ε, the slope of a frame's
//! time t against ε_px (about −2 where the splats a view selects, which fall as ε⁻²,
//! dominate; near 0 where a fixed cost does, such as a software rasteriser's fragments,
//! which coarser splats do not reduce), the ε that takes the target time T from a frame
//! drawn at ε that took t is about ε·exp((ln T − ln t)/s). The pacer estimates s from its
//! own steps (a running mean of Δln t / Δln ε over the steps large enough to tell),
//! takes a share [`GAIN`] of that step (a
//! first-order filter: no overshoot when s is misjudged by less than half), at most
//! ε × 1.5 or ÷ 1.5 a frame, and leaves ε as it is when t is within [`DEAD_BAND`]
//! of T, so that the picture does not shimmer. Where s is flatter than [`MIN_SLOPE`]
//! (the last step, and the running mean within twice that),
//! coarsening no longer buys time: the step that showed it is undone and ε held (a
//! coarser step is tried again every [`PROBE_AFTER`] frames), so that an unreachable
//! target gives the coarsest useful picture instead of a few huge splats. The adapted
//! ε never goes below the user's: the target only ever makes frames coarser.

use std::time::{Duration, Instant};

/// ε_px stays within these bounds (the panel slider's range; the pacer's too).
pub const ERROR_PX_RANGE: (f64, f64) = (0.01, 256.0);

/// How long the camera must be still before the user's ε_px is drawn again: at least
/// this, and two of the last moving frames (a camera moved once a frame is still moving
/// however long frames take), at most [`MAX_REST`].
pub const REST: Duration = Duration::from_millis(300);
const MAX_REST: Duration = Duration::from_millis(1000);
/// The share of the modelled step taken each frame.
const GAIN: f64 = 0.6;
/// The slope s flatter than which coarsening is taken not to pay.
const MIN_SLOPE: f64 = 0.15;
/// The largest change of ln ε in one frame (ε × 1.5 or ÷ 1.5).
const MAX_STEP: f64 = 0.405;
/// Steps of ln ε smaller than this teach nothing of the slope: frame times vary by more
/// than such a step changes them.
const MIN_OBSERVED_STEP: f64 = 0.15;
/// The slope assumed before the pacer has measured one.
const FIRST_SLOPE: f64 = -1.0;
/// Frames held where coarsening did not pay before trying a coarser step again.
const PROBE_AFTER: u32 = 30;
/// Frame times within this factor of the target leave ε as it is.
const DEAD_BAND: f64 = 1.08;

/// The ε_px of the next frame, under a target frame time.
#[derive(Debug, Clone)]
pub struct Pacer {
    /// The frame time to hold while moving, ms (None: always the user's ε_px).
    pub target_ms: Option<f64>,
    /// The ε_px the last moving frames settled on (kept across rests, so that moving
    /// again starts from it).
    adapted_px: f64,
    /// When the camera last moved.
    last_motion: Option<Instant>,
    /// The last moving frame's time.
    frame: Duration,
    /// The estimated d ln t / d ln ε (≤ 0).
    slope: f64,
    /// ln ε_px and ln t of the last moving frame.
    last: Option<(f64, f64)>,
    /// The slope of the last step large enough to tell.
    seen: f64,
    /// Frames held since coarsening was last seen not to pay.
    held: u32,
}

impl Pacer {
    pub fn new(target_ms: Option<f64>) -> Pacer {
        Pacer {
            target_ms,
            adapted_px: ERROR_PX_RANGE.0,
            last_motion: None,
            frame: Duration::ZERO,
            slope: FIRST_SLOPE,
            last: None,
            seen: FIRST_SLOPE,
            held: 0,
        }
    }

    /// The camera moved at `now`.
    pub fn moved(&mut self, now: Instant) {
        self.last_motion = Some(now);
    }

    /// How long the camera must be still to be at rest.
    fn rest(&self) -> Duration {
        (2 * self.frame).clamp(REST, MAX_REST)
    }

    /// Whether the camera moved within [`Pacer::rest`] of `now`.
    pub fn moving(&self, now: Instant) -> bool {
        self.last_motion
            .is_some_and(|t| now.saturating_duration_since(t) < self.rest())
    }

    /// When the camera comes to rest (the user's ε_px is due then), if it is moving.
    pub fn rest_at(&self) -> Option<Instant> {
        self.target_ms?;
        self.last_motion.map(|t| t + self.rest())
    }

    /// The ε_px to draw the frame of `now` with, given the user's.
    pub fn error_px(&self, now: Instant, user_px: f64) -> f64 {
        match self.target_ms {
            Some(_) if self.moving(now) => self.adapted_px.max(user_px),
            _ => user_px,
        }
    }

    /// The last step was flatter than [`MIN_SLOPE`], and so are the recent ones on the
    /// whole (within twice it: one noisy frame alone does not decide).
    fn coarsening_stopped_paying(&self) -> bool {
        self.seen > -MIN_SLOPE && self.slope > -2.0 * MIN_SLOPE
    }

    /// A frame drawn with `used_px` while the camera moved took `frame_ms`: adapts ε_px
    /// toward the target. (Only moving frames are reported: a resting frame at the
    /// user's ε may take as long as it takes.)
    pub fn frame_done(&mut self, used_px: f64, frame_ms: f64, user_px: f64) {
        let Some(target) = self.target_ms else { return };
        if !(frame_ms > 0.0 && used_px > 0.0) {
            return;
        }
        self.frame = Duration::from_secs_f64(frame_ms.min(1e6) * 1e-3);
        let (x, y) = (used_px.ln(), frame_ms.ln());
        let previous = self.last.replace((x, y));
        if let Some((x0, y0)) = previous
            && (x - x0).abs() > MIN_OBSERVED_STEP
        {
            self.seen = ((y - y0) / (x - x0)).clamp(-3.0, 0.0);
            self.slope = 0.5 * (self.slope + self.seen);
            self.held = 0;
        }
        let over = y - target.ln();
        let next = if over.abs() < DEAD_BAND.ln() {
            x
        } else if over > 0.0 && self.coarsening_stopped_paying() {
            // Coarsening stopped paying: back to the ε before the step that showed it,
            // and hold; after PROBE_AFTER frames, try a step again (the view changes).
            self.held += 1;
            if self.held >= PROBE_AFTER {
                // A step is taken; one more flat one and the mean is flat again.
                (self.slope, self.seen, self.held) = (-2.0 * MIN_SLOPE, FIRST_SLOPE, 0);
            }
            match previous {
                Some((x0, _)) if x0 < x => x0,
                _ => x,
            }
        } else {
            x + (GAIN * over / -self.slope.min(-MIN_SLOPE)).clamp(-MAX_STEP, MAX_STEP)
        }
        .exp();
        self.adapted_px = next.clamp(user_px.max(ERROR_PX_RANGE.0), ERROR_PX_RANGE.1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame's time: `fixed` ms plus `k` ms per (1 / ε_px²), saturating at the
    /// leaves (ε_px below `leaves_px`).
    fn cost(px: f64, fixed: f64, k: f64, leaves_px: f64) -> f64 {
        fixed + k / px.max(leaves_px).powi(2)
    }

    /// The Lucy-size model orbited on lavapipe at 1024×768 (`spt view --spin 2
    /// --error-px E`, 2026-11-22): 433, 286, 168, 119, 115, 97 ms at ε_px 1, 2, 4, 8,
    /// 16, 32, about 90 ms of fragments plus 343 ms / ε_px.
    fn lavapipe(px: f64) -> f64 {
        90.0 + 343.0 / px
    }

    /// Runs `frames` moving frames 30 ms apart from `start`, returning the frame times.
    fn run(
        pacer: &mut Pacer,
        start: Instant,
        frames: u32,
        user: f64,
        f: impl Fn(f64) -> f64,
    ) -> Vec<f64> {
        let mut times = Vec::new();
        for i in 0..frames {
            let now = start + Duration::from_millis(30 * i as u64);
            pacer.moved(now);
            let px = pacer.error_px(now, user);
            let ms = f(px);
            pacer.frame_done(px, ms, user);
            times.push(ms);
        }
        times
    }

    #[test]
    fn moving_frames_settle_near_the_target_and_rest_gives_the_users_error_back() {
        let start = Instant::now();
        for (fixed, k) in [(0.0, 400.0), (20.0, 4000.0), (60.0, 100.0)] {
            let mut pacer = Pacer::new(Some(100.0));
            let f = |px| cost(px, fixed, k, 0.05);
            let times = run(&mut pacer, start, 60, 1.0, f);
            let last = &times[40..];
            let user_cost = f(1.0);
            for t in last {
                // Either within the dead band of the target, or already at the user's ε
                // with frames faster than the target.
                assert!(
                    (t / 100.0 - 1.0).abs() <= DEAD_BAND - 1.0 + 1e-9
                        || (*t <= 100.0 && (t - user_cost).abs() < 1e-9),
                    "fixed {fixed}, k {k}: frame {t} ms"
                );
            }
            let moved_last = start + Duration::from_millis(30 * 59);
            assert!(pacer.error_px(moved_last + REST / 2, 1.0) >= 1.0);
            assert!(pacer.rest_at().unwrap() <= moved_last + MAX_REST);
            assert_eq!(
                pacer.error_px(moved_last + MAX_REST, 1.0),
                1.0,
                "at rest: the user's ε"
            );
        }
    }

    #[test]
    fn a_fill_bound_renderer_settles_within_a_fifth_of_the_target_without_running_away() {
        for target in [100.0, 150.0, 300.0] {
            let mut pacer = Pacer::new(Some(target));
            let times = run(&mut pacer, Instant::now(), 60, 1.0, lavapipe);
            for t in &times[30..] {
                assert!(
                    (t / target - 1.0).abs() <= 0.2,
                    "target {target}: frame {t} ms"
                );
            }
            assert!(
                pacer.adapted_px < 64.0,
                "target {target}: ε {}",
                pacer.adapted_px
            );
        }
        // Below the fixed cost no ε reaches the target: ε stops growing where coarsening
        // stops paying, not at the slider's end.
        let mut pacer = Pacer::new(Some(50.0));
        run(&mut pacer, Instant::now(), 200, 1.0, lavapipe);
        assert!(pacer.adapted_px < 64.0, "ε {}", pacer.adapted_px);
    }

    #[test]
    fn frames_slower_than_the_rest_period_still_count_as_moving() {
        let mut pacer = Pacer::new(Some(100.0));
        let start = Instant::now();
        pacer.moved(start);
        pacer.frame_done(1.0, 500.0, 1.0);
        let next = start + Duration::from_millis(500);
        assert!(pacer.moving(next), "moved one 500 ms frame ago");
        assert!(pacer.error_px(next, 1.0) > 1.0);
        assert!(!pacer.moving(start + MAX_REST));
    }

    #[test]
    fn the_target_never_refines_below_the_users_error() {
        let mut pacer = Pacer::new(Some(100.0));
        let times = run(&mut pacer, Instant::now(), 30, 4.0, |px| {
            cost(px, 1.0, 10.0, 0.05)
        });
        assert!(times.iter().all(|t| *t < 100.0));
        assert_eq!(pacer.error_px(Instant::now(), 4.0), 4.0);
    }

    #[test]
    fn without_a_target_the_users_error_is_drawn() {
        let mut pacer = Pacer::new(None);
        let now = Instant::now();
        pacer.moved(now);
        pacer.frame_done(1.0, 1000.0, 1.0);
        assert_eq!(pacer.error_px(now, 1.0), 1.0);
        assert_eq!(pacer.rest_at(), None);
    }
}
