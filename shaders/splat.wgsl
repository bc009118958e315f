#import common

// Splats: pass 1 (visibility, depth only) and pass 2 (attributes, additive blending),
// one instanced quad of 4 vertices per node of the list slice bound here: every node
// of the prefix (`vs_splat`, culled here), or the survivors that cull.wgsl compacted
// (`vs_splat_compacted`).

@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read> survivors: array<u32>;

struct SplatVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) center: vec3<f32>,   // view space
    @location(1) @interpolate(flat) normal: vec3<f32>,
    @location(2) @interpolate(flat) tangent_u: vec3<f32>,
    @location(3) @interpolate(flat) color: vec4<f32>,
    // x: radius, y, z: projected centre (pixels), w: unused
    @location(4) @interpolate(flat) extra: vec4<f32>,
}

fn culled() -> SplatVarying {
    var out: SplatVarying;
    // Every corner at one point outside the clip volume: a degenerate quad.
    out.clip = vec4<f32>(2.0, 2.0, 0.5, 1.0);
    return out;
}

@vertex
fn vs_splat(@builtin(vertex_index) corner: u32, @builtin(instance_index) index: u32) -> SplatVarying {
    return splat_vertex(index, corner, true);
}

@vertex
fn vs_splat_compacted(@builtin(vertex_index) corner: u32, @builtin(instance_index) index: u32) -> SplatVarying {
    return splat_vertex(survivors[index], corner, false);
}

fn splat_vertex(index: u32, corner: u32, cull: bool) -> SplatVarying {
    let node = decode_node(nodes[2u * index], nodes[2u * index + 1u]);
    let disk = view_disk(node);
    if cull && !splat_visible(node, disk) {
        return culled();
    }
    let center = disk.center;
    let normal = disk.normal;
    let r = disk.radius;
    let near = frame.near;
    // Footprint: the screen box of the disk's four tangent corners p ± r u ± r v. A disk
    // crossing the near plane is skipped rather than drawn garbled.
    let u = normalize(select(cross(normal, vec3<f32>(0.0, 0.0, 1.0)), cross(normal, vec3<f32>(1.0, 0.0, 0.0)), abs(normal.z) > 0.9));
    let v = cross(normal, u);
    var lo = vec2<f32>(1e30, 1e30);
    var hi = vec2<f32>(-1e30, -1e30);
    for (var k = 0u; k < 4u; k++) {
        let s = vec2<f32>(select(-1.0, 1.0, (k & 1u) != 0u), select(-1.0, 1.0, (k & 2u) != 0u));
        let c = center + r * (s.x * u + s.y * v);
        if -c.z < near {
            return culled();
        }
        let p = frame.proj * vec4<f32>(c, 1.0);
        lo = min(lo, p.xy / p.w);
        hi = max(hi, p.xy / p.w);
    }
    // Grow by the prefilter radius, so that sub-pixel splats still cover a pixel.
    let grow = 2.0 * frame.prefilter_px * frame.inv_viewport * select(0.0, 1.0, frame.ewa > 0.0);
    lo -= grow;
    hi += grow;
    let pick = vec2<f32>(select(lo.x, hi.x, (corner & 1u) != 0u), select(lo.y, hi.y, (corner & 2u) != 0u));
    let cp = frame.proj * vec4<f32>(center, 1.0);
    let center_px = vec2<f32>((cp.x / cp.w * 0.5 + 0.5) * frame.viewport.x, (0.5 - cp.y / cp.w * 0.5) * frame.viewport.y);
    var out: SplatVarying;
    out.clip = vec4<f32>(pick, 0.5, 1.0);
    out.center = center;
    out.normal = normal;
    out.tangent_u = u;
    var color = node.color;
    switch frame.mode {
        case MODE_LEVELS: { color = vec4<f32>(level_color(node.level), 1.0); }
        case MODE_RADIUS: { color = vec4<f32>(radius_color(node.radius), 1.0); }
        default: {}
    }
    out.color = color;
    out.extra = vec4<f32>(r, center_px, 0.0);
    return out;
}

struct Hit {
    // Squared splat-space distance (object space, or screen space under the prefilter).
    rho2: f32,
    // View distance of the ray's intersection with the splat plane.
    depth: f32,
}

// Ray through the pixel against the splat: outside the unit disk (and outside the
// prefilter footprint) → discard.
fn hit(in: SplatVarying) -> Hit {
    let dir = view_ray(in.clip.xy);
    let denom = dot(dir, in.normal);
    if abs(denom) < 1e-7 * length(dir) {
        discard;
    }
    let t = dot(in.center, in.normal) / denom;
    if t <= 0.0 {
        discard;
    }
    let q = dir * t;
    let r = in.extra.x;
    let local_u = dot(q - in.center, in.tangent_u) / r;
    let local_v = dot(q - in.center, cross(in.normal, in.tangent_u)) / r;
    var rho2 = local_u * local_u + local_v * local_v;
    if frame.ewa > 0.0 {
        let screen = (in.clip.xy - in.extra.yz) / frame.prefilter_px;
        rho2 = min(rho2, dot(screen, screen));
    }
    // Both passes keep the same fragments: beyond the rim, or where the weight is too
    // small for the half-float targets (it would leave colour 0 with w > 0: black).
    if rho2 > 1.0 || kernel(rho2) < MIN_WEIGHT {
        discard;
    }
    // Every point of the disk lies within ±r of its centre's depth. Under the prefilter
    // a pixel near a grazing splat's projected centre meets the plane far from the disk:
    // keep its depth in the disk's range so it cannot win the depth test wrongly.
    let depth = clamp(-q.z, -in.center.z - r, -in.center.z + r);
    return Hit(rho2, depth);
}

struct DepthOnly {
    @builtin(frag_depth) depth: f32,
}

// Pass 1: depth pushed back along the view ray so that the splats of one surface that
// share a pixel pass pass 2's depth test and blend: by a fraction of the radius, plus
// the depth range the pixel's prefilter footprint spans on the splat's plane (large
// when the surface is seen at a grazing angle and minified).
@fragment
fn fs_visibility(in: SplatVarying) -> DepthOnly {
    let h = hit(in);
    let dir = normalize(view_ray(in.clip.xy));
    let c = max(abs(dot(dir, in.normal)), 0.02);
    let pixel = h.depth * 2.0 * frame.tan_half_fov.y * frame.inv_viewport.y;
    let footprint = frame.prefilter_px * pixel * sqrt(1.0 - c * c) / c;
    return DepthOnly(depth_of(h.depth + frame.depth_push * in.extra.x + footprint));
}

struct Attributes {
    @location(0) color: vec4<f32>,    // (colour·w, w)
    @location(1) normal: vec4<f32>,   // (normal·w, view distance·w)
    @builtin(frag_depth) depth: f32,
}

// Splat kernel: a Gaussian of the splat-space distance, shifted and rescaled to reach 0
// at the rim (ρ = 1) so that where a splat ends the blend has no step.
fn kernel(rho2: f32) -> f32 {
    let rim = exp(-KERNEL_SHARPNESS);
    return max(exp(-KERNEL_SHARPNESS * rho2) - rim, 0.0) / (1.0 - rim);
}

const KERNEL_SHARPNESS: f32 = 2.5;
const MIN_WEIGHT: f32 = 1.0 / 1024.0;

// Pass 2: kernel weight of the splat-space distance, additive blending.
@fragment
fn fs_attributes(in: SplatVarying) -> Attributes {
    let h = hit(in);
    let w = kernel(h.rho2);
    let q = view_ray(in.clip.xy) * h.depth;
    // Two-sided: a normal facing away from the eye is flipped before blending.
    let n = select(in.normal, -in.normal, dot(in.normal, q) > 0.0);
    var out: Attributes;
    out.color = vec4<f32>(in.color.rgb * w, w);
    out.normal = vec4<f32>(n * w, h.depth * w);
    out.depth = depth_of(h.depth);
    return out;
}

// Plain points (no blending): the disk's centre pixel area, nearest wins.
@fragment
fn fs_points(in: SplatVarying) -> Attributes {
    let h = hit(in);
    let q = view_ray(in.clip.xy) * h.depth;
    let n = select(in.normal, -in.normal, dot(in.normal, q) > 0.0);
    var out: Attributes;
    out.color = vec4<f32>(in.color.rgb, 1.0);
    out.normal = vec4<f32>(n, h.depth);
    out.depth = depth_of(h.depth);
    return out;
}
