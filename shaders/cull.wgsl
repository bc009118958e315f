#import constants
#import common

// Compute culling: each node of the frame's ranges in the list slice bound here (the
// visible chunks' prefixes) is tested once; survivors are appended to a list whose
// length is the instance count of the indirect draw that follows (4 vertices per
// survivor).

struct Compaction {
    // DrawIndirectArgs: vertex count (4), instance count (the survivors), first vertex,
    // first instance.
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
    // Nodes of this slice to test, in how many ranges.
    count: u32,
    range_count: u32,
}

// A range of the slice to test: its first node, and the running total of the nodes of
// the ranges up to and including it.
struct TestRange {
    start: u32,
    end: u32,
}

@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> survivors: array<u32>;
@group(1) @binding(2) var<storage, read_write> compaction: Compaction;
@group(1) @binding(3) var<storage, read> ranges: array<TestRange>;

// The node (slice index) that thread i tests: in the first range whose running end
// exceeds i, found by binary search.
fn tested_node(i: u32) -> u32 {
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
    return ranges[lo].start + (i - before);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= compaction.count {
        return;
    }
    let i = tested_node(id.x);
    let node = decode_node(nodes[2u * i], nodes[2u * i + 1u]);
    if splat_visible(node, view_disk(node)) {
        survivors[atomicAdd(&compaction.instance_count, 1u)] = i;
    }
}
