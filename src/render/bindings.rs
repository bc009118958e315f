//! The bind slots that the passes share with their WGSL: one [`Slot`] per resource a
//! shader declares with `@group(g) @binding(b)`. Rust builds every bind group layout and
//! bind group from these constants; the test below reflects each composed shader with
//! naga and fails when a WGSL declaration and its slot disagree, or when a shader
//! declares a resource no slot names.

/// Where a shader resource is bound: its bind group, its binding, and the name of the
/// WGSL variable that declares it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slot {
    pub group: u32,
    pub binding: u32,
    pub name: &'static str,
}

const fn slot(group: u32, binding: u32, name: &'static str) -> Slot {
    Slot {
        group,
        binding,
        name,
    }
}

/// The frame uniform (`shaders/common.wgsl`), group 0 of every pass.
pub const FRAME: Slot = slot(0, 0, "frame");

/// Group 1 of the cull pass (`shaders/cull.wgsl`): one slice of the list.
pub mod cull {
    use super::{Slot, slot};
    pub const NODES: Slot = slot(1, 0, "nodes");
    pub const SURVIVORS: Slot = slot(1, 1, "survivors");
    pub const COMPACTION: Slot = slot(1, 2, "compaction");
    pub const RANGES: Slot = slot(1, 3, "ranges");
    pub const SHAPES: Slot = slot(1, 4, "shapes");
    pub const PLACEMENTS: Slot = slot(1, 5, "placements");
    pub const SURVIVOR_PLACEMENTS: Slot = slot(1, 6, "survivor_placements");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[
        super::FRAME,
        NODES,
        SURVIVORS,
        COMPACTION,
        RANGES,
        SHAPES,
        PLACEMENTS,
        SURVIVOR_PLACEMENTS,
    ];
}

/// Group 2 of the culling of far instances (`cull_far` in `shaders/cull.wgsl`): a
/// model's table at the frame's ε and its placed far instances (`render/far.rs`).
pub mod far {
    use super::{Slot, slot};
    pub const ENTRIES: Slot = slot(2, 0, "far_entries");
    pub const RANGES: Slot = slot(2, 1, "far_ranges");
    pub const COUNTERS: Slot = slot(2, 2, "far");
    /// Group 3 of the two settling steps: the indirect dispatches.
    pub const ARGS: Slot = slot(3, 0, "far_args");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[ENTRIES, RANGES, COUNTERS, ARGS];
}

/// Group 1 of the placing of far instances (`shaders/place.wgsl`).
pub mod place {
    use super::{Slot, slot};
    pub const PARAMS: Slot = slot(1, 0, "params");
    pub const INSTANCES: Slot = slot(1, 1, "instances");
    pub const GROUPS: Slot = slot(1, 2, "far_groups");
    pub const ENTRIES: Slot = slot(1, 3, "entries");
    pub const PLACED: Slot = slot(1, 4, "placed");
    pub const COUNTERS: Slot = slot(1, 5, "counters");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[
        super::FRAME,
        PARAMS,
        INSTANCES,
        GROUPS,
        ENTRIES,
        PLACED,
        COUNTERS,
    ];
}

/// Groups 1 and 2 of the splat passes (`shaders/splat.wgsl`): one slice of the list
/// (survivors only after compute culling), and pass 1's depth for pass 2.
pub mod splat {
    use super::{Slot, slot};
    pub const NODES: Slot = slot(1, 0, "nodes");
    pub const SURVIVORS: Slot = slot(1, 1, "survivors");
    pub const SHAPES: Slot = slot(1, 2, "shapes");
    pub const ATTRIBUTES: Slot = slot(1, 3, "attributes");
    pub const PLACEMENTS: Slot = slot(1, 4, "placements");
    pub const SURVIVOR_PLACEMENTS: Slot = slot(1, 5, "survivor_placements");
    pub const VISIBLE_DEPTH: Slot = slot(2, 0, "visible_depth");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[
        super::FRAME,
        NODES,
        SURVIVORS,
        SHAPES,
        ATTRIBUTES,
        PLACEMENTS,
        SURVIVOR_PLACEMENTS,
        VISIBLE_DEPTH,
    ];
}

/// Group 2 of the compute rasterizer and its resolve (`shaders/accumulate.wgsl`): the
/// frame's per-pixel buffers.
pub mod accumulate {
    use super::{Slot, slot};
    pub const VISIBLE: Slot = slot(2, 0, "visible");
    pub const SUMS: Slot = slot(2, 1, "sums");
    pub const CARRIES: Slot = slot(2, 2, "carries");
    pub const COVERED: Slot = slot(2, 3, "covered");
    pub const NEAREST_POINT: Slot = slot(2, 4, "nearest_point");
    pub const ALL: [Slot; 5] = [VISIBLE, SUMS, CARRIES, COVERED, NEAREST_POINT];
}

/// Group 1 of the compute rasterizer (`shaders/raster.wgsl`): one slice's survivors,
/// bound where the raster pipeline's compacted draw binds them, and its compaction
/// record.
pub mod raster {
    pub use super::splat::{ATTRIBUTES, NODES, SHAPES, SURVIVORS};
    use super::{Slot, slot};
    pub const COMPACTION: Slot = slot(1, 4, "compaction");
    pub const PLACEMENTS: Slot = slot(1, 5, "placements");
    pub const SURVIVOR_PLACEMENTS: Slot = slot(1, 6, "survivor_placements");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[
        super::FRAME,
        NODES,
        SURVIVORS,
        SHAPES,
        ATTRIBUTES,
        COMPACTION,
        PLACEMENTS,
        SURVIVOR_PLACEMENTS,
    ];
}

/// Group 1 of the compute rasterizer's resolve (`shaders/resolve.wgsl`): the G-buffer
/// it writes.
pub mod resolve {
    use super::{Slot, slot};
    pub const COLOR_OUT: Slot = slot(1, 0, "color_out");
    pub const NORMAL_OUT: Slot = slot(1, 1, "normal_out");
    pub const COVERAGE_OUT: Slot = slot(1, 2, "coverage_out");
    pub const DEPTH_OUT: Slot = slot(1, 3, "depth_out");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[super::FRAME, COLOR_OUT, NORMAL_OUT, COVERAGE_OUT, DEPTH_OUT];
}

/// Groups 1 and 2 of pass 3 (`shaders/shade.wgsl`): the G-buffer, and the targets
/// that its compute version writes as storage textures.
pub mod shade {
    use super::{Slot, slot};
    pub const COLOR_SUM: Slot = slot(1, 0, "color_sum");
    pub const NORMAL_SUM: Slot = slot(1, 1, "normal_sum");
    pub const COVERAGE: Slot = slot(1, 2, "coverage");
    pub const DEPTH: Slot = slot(1, 3, "depth");
    pub const SHADED_OUT: Slot = slot(2, 0, "shaded_out");
    pub const COVERED_OUT: Slot = slot(2, 1, "covered_out");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[
        super::FRAME,
        COLOR_SUM,
        NORMAL_SUM,
        COVERAGE,
        DEPTH,
        SHADED_OUT,
        COVERED_OUT,
    ];
}

/// The viewer's presentation pass (`shaders/present.wgsl`): the finished frame.
pub mod present {
    use super::{Slot, slot};
    pub const FINISHED: Slot = slot(0, 0, "finished");
    #[cfg(test)]
    pub const ALL: &[Slot] = &[FINISHED];
}

/// Every pipeline module and the slots it may declare (in groups of slots).
#[cfg(test)]
pub const MODULES: &[(&str, &[&[Slot]])] = &[
    ("cull", &[cull::ALL, far::ALL]),
    ("place", &[place::ALL]),
    ("splat", &[splat::ALL]),
    ("raster", &[raster::ALL, &accumulate::ALL]),
    ("resolve", &[resolve::ALL, &accumulate::ALL]),
    ("shade", &[shade::ALL]),
    ("mesh", &[&[FRAME]]),
    ("present", &[present::ALL]),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the resources `source` (module `module`) declares disagree with `slots`:
    /// a binding elsewhere than its slot, or a resource no slot names.
    fn mismatches(module: &str, source: &str, slots: &[Slot]) -> Vec<String> {
        let parsed = naga::front::wgsl::parse_str(source).expect("parses");
        let mut wrong = Vec::new();
        for (_, var) in parsed.global_variables.iter() {
            let (Some(b), Some(name)) = (&var.binding, &var.name) else {
                continue;
            };
            match slots.iter().find(|s| s.name == name) {
                None => wrong.push(format!("{module}.wgsl: `{name}` has no Rust slot")),
                Some(s) if (s.group, s.binding) != (b.group, b.binding) => wrong.push(format!(
                    "{module}.wgsl: `{name}` at @group({}) @binding({}), Rust says ({}, {})",
                    b.group, b.binding, s.group, s.binding
                )),
                Some(_) => {}
            }
        }
        wrong
    }

    #[test]
    fn every_wgsl_binding_is_its_rust_slot() {
        for (module, groups) in MODULES {
            let source = crate::render::shaders::compose(module);
            assert!(source.contains("@binding"), "{module} declares no resource");
            let slots: Vec<Slot> = groups.concat();
            let wrong = mismatches(module, &source, &slots);
            assert!(wrong.is_empty(), "{wrong:#?}");
        }
    }

    #[test]
    fn a_moved_or_unknown_binding_is_caught() {
        let cull = crate::render::shaders::compose("cull");
        let slots = [cull::ALL, far::ALL].concat();
        let moved = cull.replace("@group(1) @binding(4)", "@group(1) @binding(5)");
        assert_eq!(mismatches("cull", &moved, &slots).len(), 1);
        let renamed = cull.replace("var<storage, read> ranges", "var<storage, read> spans");
        let renamed = renamed.replace("far_ranges[", "FAR[");
        let renamed = renamed
            .replace("ranges[", "spans[")
            .replace("FAR[", "far_ranges[");
        assert_eq!(mismatches("cull", &renamed, &slots).len(), 1);
    }
}
