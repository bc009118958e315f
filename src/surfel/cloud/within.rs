//! The places of the values within a bound, packed to the front of a buffer: the
//! neighbour search's step from a block's squared distances (about 140) to those that
//! may be among a query's k nearest (about 30).
//!
//! On x86-64 with AVX2 and BMI2 (spt's default build target) eight distances are
//! compared at once and their places packed by one permutation: the comparison's mask,
//! one bit per lane, is spread to one byte per lane (`pdep`), which picks the lanes'
//! indices out of the bytes 7…0 (`pext`), widened to a permutation of the eight places
//! (`vpermd`); the eight are stored whole and the count moves by the mask's popcount.
//! Elsewhere, one place at a time, each written and kept only if its value is within
//! the bound. Both give the same places in the same order.

/// Writes to the start of `out` (resized as needed) the places, ascending, of the
/// `values` that are at most `bound` (as floats: a NaN is never within); returns how
/// many.
pub(super) fn places_within(values: &[f32], bound: f32, out: &mut Vec<u32>) -> usize {
    // Room for a whole group of eight past the last place kept.
    out.resize(values.len() + LANES, 0);
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "bmi2"
    ))]
    {
        // SAFETY: the target has AVX2 and BMI2 (checked at compile time); `out` holds
        // `values.len()` places and a group more (resized above).
        unsafe { x86::places_within(values, bound, out) }
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "bmi2"
    )))]
    {
        one_by_one(values, bound, 0, out, 0)
    }
}

/// Lanes compared at once.
const LANES: usize = 8;

/// [`places_within`] for `values[from..]`, writing from `out[kept]` on, one value at a
/// time without a branch: each place is written, and the next one overwrites it unless
/// its value is within the bound. Returns the count kept in all.
fn one_by_one(values: &[f32], bound: f32, from: usize, out: &mut [u32], kept: usize) -> usize {
    let mut kept = kept;
    for (i, &v) in values.iter().enumerate().skip(from) {
        out[kept] = i as u32;
        kept += usize::from(v <= bound);
    }
    kept
}

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "bmi2"
))]
mod x86 {
    use super::{LANES, one_by_one};
    use std::arch::x86_64::*;

    /// [`super::places_within`] by groups of eight lanes (module doc), the remainder
    /// one by one.
    ///
    /// # Safety
    /// `out` holds at least `values.len() + LANES` places.
    pub(super) unsafe fn places_within(values: &[f32], bound: f32, out: &mut [u32]) -> usize {
        assert!(out.len() >= values.len() + LANES);
        let groups = values.len() / LANES;
        let mut kept = 0;
        // SAFETY: every load reads `values[LANES g..LANES (g + 1)]` with g < groups, and
        // every store writes `out[kept..kept + LANES]` with kept ≤ LANES g (asserted room).
        unsafe {
            let limit = _mm256_set1_ps(bound);
            let mut places = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
            let step = _mm256_set1_epi32(LANES as i32);
            for g in 0..groups {
                let v = _mm256_loadu_ps(values.as_ptr().add(g * LANES));
                let within = _mm256_cmp_ps::<_CMP_LE_OQ>(v, limit);
                let mask = _mm256_movemask_ps(within) as u32 as u64;
                // One byte of ones per lane within; those bytes of 7…0, packed low.
                let bytes = _pdep_u64(mask, 0x0101_0101_0101_0101) * 0xFF;
                let picked = _pext_u64(0x0706_0504_0302_0100, bytes);
                let order = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(picked as i64));
                let packed = _mm256_permutevar8x32_epi32(places, order);
                _mm256_storeu_si256(out.as_mut_ptr().add(kept).cast(), packed);
                kept += mask.count_ones() as usize;
                places = _mm256_add_epi32(places, step);
            }
        }
        one_by_one(values, bound, groups * LANES, out, kept)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_places_within_are_those_a_filter_keeps() {
        // Every length from none to five groups (whole groups and remainders), bounds
        // that keep none, some and all, values equal to the bound, a NaN and an infinity.
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state % 1000) as f32 / 10.0
        };
        let mut out = Vec::new();
        for len in 0..40 {
            let mut values: Vec<f32> = (0..len).map(|_| next()).collect();
            if len > 5 {
                values[3] = f32::NAN;
                values[5] = f32::INFINITY;
            }
            for bound in [-1.0, 0.0, 25.0, 50.0, 99.9, f32::INFINITY, f32::NAN] {
                let expected: Vec<u32> = (0..len as u32)
                    .filter(|&i| values[i as usize] <= bound)
                    .collect();
                let count = places_within(&values, bound, &mut out);
                assert_eq!(&out[..count], &expected[..], "{len} values, bound {bound}");
            }
        }
    }
}
