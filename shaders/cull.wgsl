#import constants
#import common

// Compute culling: each node of the prefix (of the list slice bound here) is tested
// once; survivors are appended to a list whose length is the instance count of the
// indirect draw that follows (4 vertices per survivor).

struct Compaction {
    // DrawIndirectArgs: vertex count (4), instance count (the survivors), first vertex,
    // first instance.
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
    // Nodes of this slice in the prefix.
    count: u32,
}

@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> survivors: array<u32>;
@group(1) @binding(2) var<storage, read_write> compaction: Compaction;

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= compaction.count {
        return;
    }
    let node = decode_node(nodes[2u * i], nodes[2u * i + 1u]);
    if splat_visible(node, view_disk(node)) {
        survivors[atomicAdd(&compaction.instance_count, 1u)] = i;
    }
}
