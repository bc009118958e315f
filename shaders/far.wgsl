#import constants
// What the placing of far instances (place.wgsl) and their culling (`cull_far` in
// cull.wgsl) share; mirrored by the Pod types of src/render/far.rs.

// A slot of a model's table (a rounded distance at the frame's ε): its ranges,
// `count` of them from `first` in `far_ranges`, holding `nodes` nodes.
struct FarEntry {
    first: u32,
    count: u32,
    nodes: u32,
    pad: u32,
}

// A range of an entry: its first node (slice index), and the running total of the
// nodes of its entry's ranges up to and including it.
struct FarRange {
    start: u32,
    end: u32,
}

// A model's far instances in a frame.
struct FarCounters {
    // Instances placed, the nodes their entries hold, the survivors they asked for.
    visible: atomic<u32>,
    nodes: atomic<u32>,
    kept: atomic<u32>,
    // Survivors the list holds for them (settle_far), and the first of their
    // placements (after the CPU's).
    budget: u32,
    base: u32,
}

// The indirect dispatches of a model's far instances: cull_far's, then the compute
// rasterizer's (a buffer of its own: one a dispatch reads its size from is not bound).
struct FarArgs {
    cull_x: u32,
    cull_y: u32,
    cull_z: u32,
    raster_x: u32,
    raster_y: u32,
    raster_z: u32,
}
