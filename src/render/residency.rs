//! Which slices of a list stay on the GPU under a memory budget: the policy
//! alone, without the GPU, so that tests can drive it.
//!
//! After each frame the caller hands over the slices the frame's asked ε wanted
//! ([`super::EncodedFrame::wanted_slices`]); [`Residency::after_frame`] answers which
//! slices to fetch (the wanted ones missing, in list order: coarse first, since the
//! list holds coarse chunks first) and which to evict first to make room (the least
//! recently wanted; never one the frame wants, never slice 0, which holds the root and
//! the coarse front every fallback needs). Meanwhile frames raise ε until their ranges
//! lie in resident slices (`plan.rs`), so missing slices coarsen the picture, never hole
//! it.
//!
//! **Invariant:** the bytes resident plus the bytes requested and not yet arrived never
//! exceed the budget: a fetch is asked only once evictions make room for it. So the
//! resident bytes stay within the budget whatever order the uploads arrive in.

use std::collections::BTreeMap;

/// `bytes` in MiB.
pub fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

/// What to do after a frame: evict these slices (before the fetches are asked), then
/// fetch those, in order.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Decision {
    pub evict: Vec<usize>,
    pub fetch: Vec<usize>,
}

/// The residency of a list's slices under a budget, as the policy sees it: mirrored by
/// the caller's [`super::GpuScene`] (every `evict` applied, every arrival reported).
#[derive(Debug, Clone)]
pub struct Residency {
    budget: u64,
    /// Resident slices and their bytes.
    resident: BTreeMap<usize, u64>,
    resident_bytes: u64,
    /// Requested, not arrived yet, with their bytes.
    in_flight: BTreeMap<usize, u64>,
    /// The frame that last wanted each slice (0: never).
    last_wanted: Vec<u64>,
    frame: u64,
    /// The most bytes ever resident.
    peak_bytes: u64,
}

impl Residency {
    /// A list of `slices` slices under `budget` bytes, nothing resident yet.
    pub fn new(budget: u64, slices: usize) -> Residency {
        Residency {
            budget,
            resident: BTreeMap::new(),
            resident_bytes: 0,
            in_flight: BTreeMap::new(),
            last_wanted: vec![0; slices],
            frame: 0,
            peak_bytes: 0,
        }
    }

    pub fn budget(&self) -> u64 {
        self.budget
    }

    pub fn resident_bytes(&self) -> u64 {
        self.resident_bytes
    }

    /// The most bytes resident at any time so far.
    pub fn peak_bytes(&self) -> u64 {
        self.peak_bytes
    }

    /// "A MiB resident, peak B MiB, budget C MiB": what `spt render` and the viewer's
    /// screenshot log.
    pub fn memory_line(&self) -> String {
        format!(
            "{:.1} MiB resident, peak {:.1} MiB, budget {:.1} MiB",
            mib(self.resident_bytes),
            mib(self.peak_bytes),
            mib(self.budget)
        )
    }

    /// Slices requested and not arrived yet.
    pub fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    /// Slice `k`, of `bytes`, is on the GPU now (requested or not).
    pub fn arrived(&mut self, k: usize, bytes: u64) {
        self.in_flight.remove(&k);
        if let Some(old) = self.resident.insert(k, bytes) {
            self.resident_bytes -= old;
        }
        self.resident_bytes += bytes;
        self.peak_bytes = self.peak_bytes.max(self.resident_bytes);
    }

    /// Whether slice `k`, of `bytes`, fits the budget beside what is resident and in
    /// flight.
    fn fits(&self, bytes: u64) -> bool {
        let in_flight: u64 = self.in_flight.values().sum();
        self.resident_bytes + in_flight + bytes <= self.budget
    }

    /// The resident slice wanted least recently, not by this frame and not slice 0.
    fn least_recent(&self) -> Option<usize> {
        self.resident
            .keys()
            .copied()
            .filter(|&k| k != 0 && self.last_wanted[k] < self.frame)
            .min_by_key(|&k| (self.last_wanted[k], std::cmp::Reverse(k)))
    }

    /// After a frame that wanted `wanted` (ascending): the slices to evict and to fetch,
    /// at most `max_in_flight` requests outstanding; `bytes_of(k)` is slice k's size on
    /// the GPU. Evictions are applied to the mirror at once.
    pub fn after_frame(
        &mut self,
        wanted: &[usize],
        bytes_of: impl Fn(usize) -> u64,
        max_in_flight: usize,
    ) -> Decision {
        self.frame += 1;
        for &k in wanted.iter().chain([&0]) {
            if let Some(stamp) = self.last_wanted.get_mut(k) {
                *stamp = self.frame;
            }
        }
        let mut decision = Decision::default();
        let missing: Vec<usize> = wanted
            .iter()
            .copied()
            .filter(|k| !self.resident.contains_key(k) && !self.in_flight.contains_key(k))
            .collect();
        for k in missing {
            if self.in_flight.len() >= max_in_flight {
                break;
            }
            let bytes = bytes_of(k);
            while !self.fits(bytes) {
                let Some(old) = self.least_recent() else {
                    return decision; // everything resident is wanted: the budget is full
                };
                self.resident_bytes -= self.resident.remove(&old).expect("resident");
                decision.evict.push(old);
            }
            self.in_flight.insert(k, bytes);
            decision.fetch.push(k);
        }
        decision
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uploads arrive at once: the caller applies the decision.
    fn run(r: &mut Residency, wanted: &[usize]) -> Decision {
        let d = r.after_frame(wanted, |_| 10, 4);
        for &k in &d.fetch {
            r.arrived(k, 10);
        }
        d
    }

    #[test]
    fn wanted_slices_are_fetched_coarse_first_within_the_budget() {
        let mut r = Residency::new(50, 20);
        r.arrived(0, 10);
        let d = run(&mut r, &[0, 3, 1, 7, 9, 12]);
        // At most 4 in flight; the budget holds 5 slices of 10 bytes, slice 0 included.
        assert_eq!(d.fetch, [3, 1, 7, 9]);
        assert!(d.evict.is_empty());
        assert_eq!(r.resident_bytes(), 50);
        // The next frame wants 12 too: nothing resident is unwanted, so it waits.
        let d = run(&mut r, &[0, 1, 3, 7, 9, 12]);
        assert!(d.fetch.is_empty() && d.evict.is_empty());
        assert!(r.peak_bytes() <= 50);
    }

    #[test]
    fn the_least_recently_wanted_slice_is_evicted_never_slice_0() {
        let mut r = Residency::new(40, 20);
        r.arrived(0, 10);
        run(&mut r, &[1, 2, 3]);
        run(&mut r, &[2, 3]);
        // Wanting 5 evicts 1 (wanted two frames ago), not 0, 2 or 3.
        let d = run(&mut r, &[3, 5]);
        assert_eq!(
            (d.evict.as_slice(), d.fetch.as_slice()),
            ([1].as_slice(), [5].as_slice())
        );
        // Wanting 6 and 7 evicts 2 (older than 3 and 5), then nothing else can go.
        let d = run(&mut r, &[3, 5, 6, 7]);
        assert_eq!(
            (d.evict.as_slice(), d.fetch.as_slice()),
            ([2].as_slice(), [6].as_slice())
        );
        assert_eq!(r.resident_bytes(), 40);
    }

    #[test]
    fn requests_in_flight_count_against_the_budget() {
        let mut r = Residency::new(30, 10);
        r.arrived(0, 10);
        // Two requests of 10 in flight fill the budget: a third is not asked.
        let d = r.after_frame(&[1, 2, 3], |_| 10, 8);
        assert_eq!(d.fetch, [1, 2]);
        assert_eq!(r.in_flight(), 2);
        let d = r.after_frame(&[1, 2, 3], |_| 10, 8);
        assert!(d.fetch.is_empty());
        // They arrive out of order; the resident bytes never pass the budget.
        r.arrived(2, 10);
        r.arrived(1, 10);
        assert_eq!(r.peak_bytes(), 30);
    }
}
