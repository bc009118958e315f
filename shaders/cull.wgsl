#import constants
#import common
#import shape
#import far

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

// What the test makes of a node: culled, or kept in one of the two lists.
const CULLED: u32 = 0u;
const INNER: u32 = 1u;
const OUTLINE: u32 = 2u;

// Node i (slice index) at placement p: CULLED, or the list it goes to (`on_outline`,
// with the shape decoded only where its kind does not decide).
fn classify(i: u32, p: u32) -> u32 {
    let placement = placements[p];
    let node = decode_node(nodes[2u * i], nodes[2u * i + 1u], placement.error_scale);
    let disk = view_disk(node, placement);
    if !splat_visible(node, disk) {
        return CULLED;
    }
    let packed = shapes[i];
    if outline_by_kind(packed.clip) || silhouette_near(disk, shape_frame(packed, disk.normal, disk.rotation)) {
        return OUTLINE;
    }
    return INNER;
}

// Appends node i at placement p to the list `kind` names.
fn keep_in(kind: u32, i: u32, p: u32) {
    if kind == OUTLINE {
        keep(arrayLength(&survivors) - 1u - atomicAdd(&compaction.outline.instance_count, 1u), i, p);
    } else {
        keep(atomicAdd(&compaction.inner.instance_count, 1u), i, p);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= compaction.count {
        return;
    }
    let tested = tested_node(id.x);
    let kind = classify(tested.x, tested.y);
    if kind != CULLED {
        keep_in(kind, tested.x, tested.y);
    }
}

// Far instances placed by the GPU (place.wgsl, src/render/far.rs): each placement
// names its model's table slot; a slot's entry lists ranges of the slice with their
// running ends, as `ranges` does for the CPU's.
@group(2) @binding(0) var<storage, read> far_entries: array<FarEntry>;
@group(2) @binding(1) var<storage, read> far_ranges: array<FarRange>;
@group(2) @binding(2) var<storage, read_write> far: FarCounters;
// Bound to the two settling steps only.
@group(3) @binding(0) var<storage, read_write> far_args: FarArgs;

// Node t of `entry`'s ranges (slice index), by binary search over their running ends.
fn far_node(entry: FarEntry, t: u32) -> u32 {
    var lo = entry.first;
    var hi = entry.first + entry.count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if far_ranges[mid].end > t {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    var before = 0u;
    if lo > entry.first {
        before = far_ranges[lo - 1u].end;
    }
    return far_ranges[lo].start + (t - before);
}

// After placing: the dispatch of `cull_far` (a workgroup per placed instance, in rows
// of at most MAX_GROUPS_X), and the survivors left to it: the list's room less what
// the CPU's ranges kept.
@compute @workgroup_size(1)
fn settle_far() {
    let placed = atomicLoad(&far.visible);
    let x = min(placed, MAX_GROUPS_X);
    far_args.cull_x = x;
    far_args.cull_y = select(0u, (placed + x - 1u) / x, x > 0u);
    far_args.cull_z = 1u;
    let room = arrayLength(&survivors);
    let used = atomicLoad(&compaction.inner.instance_count) + atomicLoad(&compaction.outline.instance_count);
    far.budget = room - min(used, room);
}

// Workgroup k tests the nodes of placed instance k's entry. A survivor beyond the
// budget is counted (`kept` then tells how many the frame asked for) but not stored.
@compute @workgroup_size(FAR_WORKGROUP)
fn cull_far(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let k = group.y * groups.x + group.x;
    if k >= atomicLoad(&far.visible) {
        return;
    }
    let p = far.base + k;
    let entry = far_entries[placements[p].slot];
    for (var t = lane; t < entry.nodes; t += FAR_WORKGROUP) {
        let i = far_node(entry, t);
        let kind = classify(i, p);
        if kind != CULLED && atomicAdd(&far.kept, 1u) < far.budget {
            keep_in(kind, i, p);
        }
    }
}

// After culling: the compute rasterizer's dispatch over the slice's longer list (as
// `grid` in raster.rs does for a count the CPU knows).
@compute @workgroup_size(1)
fn settle_raster() {
    let most = max(atomicLoad(&compaction.inner.instance_count), atomicLoad(&compaction.outline.instance_count));
    let groups = (most + RASTER_WORKGROUP - 1u) / RASTER_WORKGROUP;
    let x = clamp(groups, 1u, MAX_GROUPS_X);
    far_args.raster_x = x;
    far_args.raster_y = (groups + x - 1u) / x;
    far_args.raster_z = 1u;
}
