//! The records the far instances' passes share with their WGSL (`shaders/far.wgsl`,
//! `shaders/place.wgsl`), and how positions are split for them.

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// Mirrors `struct FarInstance` in place.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct FarInstance {
    pub anchor: [f32; 3],
    pub scale: f32,
    pub anchor_rest: [u32; 2],
    pub rotation: [u32; 2],
}

/// Mirrors `struct FarEntry` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub(super) struct FarEntry {
    pub first: u32,
    pub count: u32,
    pub nodes: u32,
    pub pad: u32,
}

/// Mirrors `struct FarRange` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub(super) struct FarRange {
    pub start: u32,
    pub end: u32,
}

/// Mirrors `struct FarCounters` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub(in crate::render) struct FarCounters {
    pub visible: u32,
    pub nodes: u32,
    pub kept: u32,
    pub budget: u32,
    pub base: u32,
}

impl FarCounters {
    /// Bytes of what is read back: visible, nodes, kept, budget.
    pub const READ_BYTES: u64 = 16;
}

/// Mirrors `struct FarArgs` in far.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub(in crate::render) struct FarArgs {
    cull: [u32; 3],
    raster: [u32; 3],
}

impl FarArgs {
    /// Byte offset of `cull_far`'s dispatch arguments.
    pub const CULL_AT: u64 = std::mem::offset_of!(FarArgs, cull) as u64;
    /// Byte offset of the compute rasterizer's dispatch arguments.
    pub const RASTER_AT: u64 = std::mem::offset_of!(FarArgs, raster) as u64;
}

/// Mirrors `struct PlaceParams` in place.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct PlaceParams {
    pub eye: [f32; 3],
    pub radius: f32,
    pub eye_rest: [f32; 3],
    pub error_scale: f32,
    pub centre: [f32; 3],
    pub near: f32,
    pub right: [f32; 3],
    pub tan_x: f32,
    pub up: [f32; 3],
    pub tan_y: f32,
    pub forward: [f32; 3],
    pub secant_x: f32,
    pub secant_y: f32,
    pub pad: [f32; 3],
}

/// What the GPU measured of a frame's far instances, all models together.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FarCounts {
    /// Instances placed, and the nodes their slots hold (tested).
    pub visible: u64,
    pub tested: u64,
    /// Survivors they asked for, and the room left to them.
    pub asked: u64,
    pub room: u64,
    /// The fullest model's share of its room asked for (over 1: some were not stored).
    pub fill: f64,
}

impl FarCounts {
    /// Adds one model's counters (as read back: visible, nodes, kept, budget).
    pub(in crate::render) fn add(&mut self, c: [u32; 4]) {
        self.visible += c[0] as u64;
        self.tested += c[1] as u64;
        self.asked += c[2] as u64;
        self.room += c[3] as u64;
        if c[2] > 0 {
            self.fill = self.fill.max(c[2] as f64 / c[3].max(1) as f64);
        }
    }
}

/// `v` as an f32 and its f16 rest.
pub(super) fn split(v: DVec3) -> ([f32; 3], [f32; 3]) {
    let head = v.as_vec3();
    (head.to_array(), (v - head.as_dvec3()).as_vec3().to_array())
}

/// Three f16 packed two a word (WGSL's `unpack2x16float` inverts it).
pub(super) fn pack_f16(v: [f32; 3]) -> [u32; 2] {
    let h = v.map(|x| half::f16::from_f32(x).to_bits() as u32);
    [h[0] | (h[1] << 16), h[2]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::shaders::assert_wgsl_size;

    #[test]
    fn far_records_have_the_sizes_of_the_wgsl_structs() {
        assert_wgsl_size::<FarInstance>("place", "FarInstance");
        assert_wgsl_size::<PlaceParams>("place", "PlaceParams");
        assert_wgsl_size::<FarEntry>("far", "FarEntry");
        assert_wgsl_size::<FarRange>("far", "FarRange");
        assert_wgsl_size::<FarCounters>("far", "FarCounters");
        assert_wgsl_size::<FarArgs>("far", "FarArgs");
    }

    #[test]
    fn the_fill_is_the_fullest_model_s_not_the_sum_s() {
        let mut counts = FarCounts::default();
        // One model asks 3 survivors of a room of 2; another 1 of 1,000.
        counts.add([1, 10, 3, 2]);
        counts.add([5, 50, 1, 1000]);
        assert_eq!((counts.visible, counts.tested), (6, 60));
        assert_eq!(counts.fill, 1.5);
        assert!(counts.asked < counts.room, "the sums alone would hide it");
    }

    #[test]
    fn an_anchor_and_its_f16_rest_hold_a_position_a_million_units_away() {
        let v = DVec3::new(1e6 + 0.123_456_7, -2.5e5 - 0.000_31, 7.25);
        let (head, rest) = split(v);
        let [a, b] = pack_f16(rest);
        let unpack = |w: u32| half::f16::from_bits(w as u16).to_f32() as f64;
        let back = DVec3::from(head.map(f64::from))
            + DVec3::new(unpack(a & 0xffff), unpack(a >> 16), unpack(b & 0xffff));
        let error = (back - v).abs().max_element();
        assert!(error < 1e-4, "placed {error} units off");
        // The f32 alone is 0.03 units off here.
        assert!((DVec3::from(head.map(f64::from)) - v).abs().max_element() > 1e-3);
    }
}
