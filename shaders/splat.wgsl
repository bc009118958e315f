#import common
#import constants
#import ewa
#import shape
#import surrounded

// Splats through the raster pipeline: pass 1 (visibility, depth only) and pass 2
// (attributes, additive blending), one instanced quad of 4 vertices per node of the
// list slice bound here: every node of the prefix (`vs_splat`, culled here), or the
// survivors that cull.wgsl compacted (`vs_splat_compacted`). What a fragment does is
// ewa.wgsl's, shared with the compute rasterizer (raster.wgsl).

@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read> survivors: array<u32>;
@group(1) @binding(2) var<storage, read> shapes: array<SplatShape>;
// Each node's LiDAR attributes (one u32 of zero for a model without them).
@group(1) @binding(3) var<storage, read> attributes: array<u32>;
// Where the model is drawn, and each survivor's placement (one element for a model
// drawn alone: every survivor's is 0; see cull.wgsl).
@group(1) @binding(4) var<storage, read> placements: array<Placement>;
@group(1) @binding(5) var<storage, read> survivor_placements: array<u32>;
// Pass 1's depth, for pass 2 (`fs_attributes`); read as a float texture, as pass 3 does.
@group(2) @binding(0) var visible_depth: texture_2d<f32>;

fn culled() -> SplatVarying {
    var out: SplatVarying;
    // Every corner at one point outside the clip volume: a degenerate quad.
    out.clip = vec4<f32>(2.0, 2.0, 0.5, 1.0);
    return out;
}

@vertex
fn vs_splat(@builtin(vertex_index) corner: u32, @builtin(instance_index) index: u32) -> SplatVarying {
    return splat_vertex(index, 0u, corner, true);
}

// The cull pass lists the survivors that `on_outline` keeps from the end of the list
// backwards, the others from its start.
@vertex
fn vs_splat_compacted(@builtin(vertex_index) corner: u32, @builtin(instance_index) index: u32) -> SplatVarying {
    let slot = select(index, arrayLength(&survivors) - 1u - index, SPLAT_CLASS == OUTLINE_SPLATS);
    let placement = survivor_placements[min(slot, arrayLength(&survivor_placements) - 1u)];
    return splat_vertex(survivors[slot], placement, corner, false);
}

// A corner of node `index`'s quad at `placement` (its placed box, see `place_splat`).
fn splat_vertex(index: u32, placement: u32, corner: u32, cull: bool) -> SplatVarying {
    let placed = place_splat(index, placement, cull);
    if !placed.drawn {
        return culled();
    }
    let lo = placed.lo;
    let hi = placed.hi;
    var out = placed.splat;
    out.clip = vec4<f32>(select(lo.x, hi.x, (corner & 1u) != 0u), select(lo.y, hi.y, (corner & 2u) != 0u), out.clip.zw);
    return out;
}

// Pass 1's depth at a pixel and its four neighbours (ewa.wgsl's `pixel_coverage`).
fn surrounded_at(texel: vec2<i32>) -> bool {
    return surrounded(visible_depth, texel);
}

struct DepthOnly {
    @builtin(frag_depth) depth: f32,
}

@fragment @early_depth_test(less_equal)
fn fs_visibility(in: SplatVarying) -> DepthOnly {
    let depth = visibility_depth(in);
    if depth <= 0.0 {
        discard;
    }
    return DepthOnly(depth);
}

struct Attributes {
    @location(0) color: vec4<f32>,    // (colour·w, w)
    @location(1) normal: vec4<f32>,   // (normal·w, view distance·w)
    @location(2) coverage: vec4<f32>, // the four coverage samples, blended by max
    @builtin(frag_depth) depth: f32,
}

// A kept fragment's outputs; a dropped one is discarded.
fn written(f: Fragment) -> Attributes {
    if !f.kept {
        discard;
    }
    return Attributes(f.color, f.normal, f.coverage, f.depth);
}

// Pass 2 for the splats on an outline (with the coverage samples).
@fragment @early_depth_test(less_equal)
fn fs_attributes(in: SplatVarying) -> Attributes {
    return written(outline_fragment(in));
}

// Pass 2 for the splats inside the picture's outlines.
@fragment @early_depth_test(less_equal)
fn fs_attributes_inner(in: SplatVarying) -> Attributes {
    return written(inner_fragment(in));
}

// Plain points: nearest wins.
@fragment @early_depth_test(less_equal)
fn fs_points(in: SplatVarying) -> Attributes {
    return written(point_fragment(in));
}
