#import constants

// The compute rasterizer's per-pixel buffers, one entry per pixel of the frame,
// row-major, top row first: raster.wgsl writes them with atomics, resolve.wgsl turns
// them into the G-buffer and clears them with plain loads and stores (it runs alone:
// on a CPU adapter, which cannot vectorise atomics, that is several times faster). Both
// declare them at group 2 (src/render/bindings.rs, `accumulate`):
//
// visible        pass 1: the nearest pushed-back depth, reversed Z, as its f32 bits
//                (positive floats order as their bits: atomicMax keeps the nearest);
//                0: none. The points' depth.
// sums           pass 2's sums in fixed point (FIXED_ONE = 1), channel-major: channel c
// carries        of pixel p at c · pixels + p (channels: SUM_*). `sums` holds the low
//                32 bits, `carries` the high ones: an add whose low word wraps carries
//                one into its high word, so that a sum holds 2⁶⁴ / FIXED_ONE = 2³⁴
//                full-weight fragments.
// covered        the four coverage samples, two bits each (sample k at bits 2k): 3
//                where a patch's front covers it, 1 where only OFF_FRONT_COVERAGE
//                does; OR-ed, so the larger wins.
// nearest_point  the points: the bitwise complement of the winning fragment's list
//                index (atomicMax: among fragments at the same depth the first of the
//                list wins, whatever the order threads run in).

// The channels of `sums`: colour·w (3), w, (normal + 1)·w (3, so that none is
// negative), and (z / z₁)·w with z the fragment's view distance and z₁ that of pass 1's
// depth at the pixel (≤ 1: a fragment behind pass 1's depth fails its test).
const SUM_COLOR: u32 = 0u;
const SUM_WEIGHT: u32 = 3u;
const SUM_NORMAL: u32 = 4u;
const SUM_DEPTH: u32 = 7u;

// Fixed point: 1.0 is 2³⁰. A fragment adds at most 2 (a normal channel) = 2³¹, which a
// u32 holds. The least weight a kept fragment adds is 2⁻²⁰ (MIN_WEIGHT · BAND_WEIGHT ·
// BACK_WEIGHT, ewa.wgsl) = 2¹⁰ units: rounding each add to a unit (half a unit off, in
// a colour sum and in the weight) moves a pixel's mean colour by at most 2⁻¹⁰ of its
// range, a quarter of an 8-bit step.
const FIXED_ONE: f32 = 1073741824.0;

fn pixel_count() -> u32 {
    return arrayLength(&visible);
}

