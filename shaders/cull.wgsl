#import constants
#import common
#import shape

// Compute culling: each node of the frame's ranges in the list slice bound here (the
// visible chunks' prefixes) is tested once. Survivors go to two lists in one array,
// each counted as the instance count of an indirect draw (4 vertices per survivor):
// those whose rim may lie on an outline (`on_outline`) from the array's end backwards,
// the others from its start.

// DrawIndirectArgs: vertex count (4), instance count (the survivors), first vertex,
// first instance.
struct DrawArgs {
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
}

struct Compaction {
    // The draws of the survivors on an outline, then of the others.
    outline: DrawArgs,
    inner: DrawArgs,
    // Nodes of this slice to test, in how many ranges; the slice's first node (list
    // index: the compute rasterizer's order of points at one depth, raster.wgsl).
    count: u32,
    range_count: u32,
    first: u32,
}

// A range of the slice to test: its first node, the running total of the nodes of the
// ranges up to and including it, and the placement it is drawn at (`placements`).
struct TestRange {
    start: u32,
    end: u32,
    placement: u32,
}

@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> survivors: array<u32>;
@group(1) @binding(2) var<storage, read_write> compaction: Compaction;
@group(1) @binding(3) var<storage, read> ranges: array<TestRange>;
@group(1) @binding(4) var<storage, read> shapes: array<SplatShape>;
@group(1) @binding(5) var<storage, read> placements: array<Placement>;
// Each survivor's placement, beside `survivors`; a model drawn alone binds one element,
// which every survivor shares (its placement 0).
@group(1) @binding(6) var<storage, read_write> survivor_placements: array<u32>;

// The node (slice index) that thread i tests, and its range's placement: in the first
// range whose running end exceeds i, found by binary search.
fn tested_node(i: u32) -> vec2<u32> {
    var lo = 0u;
    var hi = compaction.range_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if ranges[mid].end > i {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    var before = 0u;
    if lo > 0u {
        before = ranges[lo - 1u].end;
    }
    return vec2<u32>(ranges[lo].start + (i - before), ranges[lo].placement);
}

// Stores survivor `i` at `placement` in list slot `slot`.
fn keep(slot: u32, i: u32, placement: u32) {
    survivors[slot] = i;
    survivor_placements[min(slot, arrayLength(&survivor_placements) - 1u)] = placement;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= compaction.count {
        return;
    }
    let tested = tested_node(id.x);
    let i = tested.x;
    let placement = placements[tested.y];
    let node = decode_node(nodes[2u * i], nodes[2u * i + 1u], placement.error_scale);
    let disk = view_disk(node, placement);
    if !splat_visible(node, disk) {
        return;
    }
    let packed = shapes[i];
    // `on_outline`, with the shape decoded only where its kind does not decide.
    if outline_by_kind(packed.clip) || silhouette_near(disk, shape_frame(packed, disk.normal, disk.rotation)) {
        keep(arrayLength(&survivors) - 1u - atomicAdd(&compaction.outline.instance_count, 1u), i, tested.y);
    } else {
        keep(atomicAdd(&compaction.inner.instance_count, 1u), i, tested.y);
    }
}
