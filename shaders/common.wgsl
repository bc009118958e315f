#import constants
// Shared by every pass: the per-frame uniforms, node record decoding, the selection
// test (docs/design.md §5) and view rays. Passes import it (`#import common`).

struct Frame {
    // World-aligned camera-relative → view space (a rotation).
    view: mat4x4<f32>,
    // Reversed-Z, infinite far plane: depth = near / view distance.
    proj: mat4x4<f32>,
    // Model origin − eye, computed in f64 on the CPU.
    model_offset: vec3<f32>,
    // Eye-dome lighting's strength (MODE_EDL).
    edl_strength: f32,
    // Target size in pixels, and its inverse.
    viewport: vec2<f32>,
    inv_viewport: vec2<f32>,
    // ε: world error per unit of distance of the selection test.
    eps: f32,
    // What stored errors are relative to (model units).
    error_scale: f32,
    near: f32,
    // Pass 1 pushes each splat back by this fraction of its radius.
    depth_push: f32,
    // tan of the half field of view, horizontally and vertically.
    tan_half_fov: vec2<f32>,
    // Radius of the EWA screen-space prefilter, pixels.
    prefilter_px: f32,
    // 1 with the EWA prefilter, 0 without.
    ewa: f32,
    // Direction toward the light, view space, and the specular strength.
    light_dir: vec3<f32>,
    specular: f32,
    background: vec4<f32>,
    // Display mode (MODE_*), back faces culled, level of detail on, LOD frozen at lod_eye.
    mode: u32,
    cull_back_faces: u32,
    lod_on: u32,
    lod_frozen: u32,
    // 1 for a terrain's estimated normals, which face up (the rule that turned them):
    // a splat seen from behind is then the ground's underside (see fs_attributes).
    normals_up: u32,
    // 1 for a cloud's estimated normals that no rule turned: each faces either way, and
    // a splat is drawn from whichever side the eye sees (see shade.wgsl's rim_normal).
    normals_unknown: u32,
    // Lowest and highest node centre height along elevation_up, relative to the model
    // origin (MODE_ELEVATION).
    elevation_range: vec2<f32>,
    // The eye the level of detail is chosen for, relative to the camera's eye
    // (world-aligned); used when lod_frozen is set.
    lod_eye: vec3<f32>,
    // Eye-dome lighting's neighbour distance, pixels (MODE_EDL).
    edl_radius_px: f32,
    // The intensities drawn black and white (MODE_INTENSITY): the model's 1st and 99th
    // percentiles.
    intensity_range: vec2<f32>,
    // 1 when the nodes carry LiDAR attributes (the attribute modes read them).
    has_attributes: u32,
    // 1 when the model's normals face out of its surface (meshes, clouds with given
    // normals): a splat seen from behind is then the surface's back (see fs_attributes).
    oriented_normals: u32,
    // The model's up (z, or a sensor frame's image up), unit: heights are taken along it.
    elevation_up: vec3<f32>,
    elevation_pad: f32,
}

// The display modes' MODE_* constants come from Rust (`Mode::wgsl_constants`, through
// the generated `constants` module).

// What pass 2 writes for each coverage sample a fragment covers when the fragment
// does not show a front side at the pixel centre (one seen from behind, which weighs
// BACK_WEIGHT, or one of the prefilter's band; splat.wgsl), instead of 1. Blended by
// max, a pixel's samples stay at or below it only where no patch's front covers the
// pixel centre, which pass 3 reads as a slit in the nearer surface when that surface's
// pixels lie on both sides (`fill_between`, shade.wgsl).
const OFF_FRONT_COVERAGE: f32 = 0.5;

// The colour of ASPRS class `c` (LAS 1.4, table 17), linear RGB. Kept in step with the
// viewer's legend (src/apps/view/legend.rs, CLASS_COLORS).
fn class_color(c: u32) -> vec3<f32> {
    switch c {
        case 2u: { return vec3<f32>(0.35, 0.17, 0.04); }   // ground: brown
        case 3u: { return vec3<f32>(0.35, 0.75, 0.15); }   // low vegetation: light green
        case 4u: { return vec3<f32>(0.1, 0.45, 0.03); }    // medium vegetation: green
        case 5u: { return vec3<f32>(0.01, 0.2, 0.01); }    // high vegetation: dark green
        case 6u: { return vec3<f32>(0.8, 0.12, 0.03); }    // building: red
        case 7u, 18u: { return vec3<f32>(0.9, 0.0, 0.9); } // noise: magenta
        case 9u: { return vec3<f32>(0.02, 0.15, 0.85); }   // water: blue
        case 10u: { return vec3<f32>(0.3, 0.2, 0.12); }    // rail: dark brown
        case 11u: { return vec3<f32>(0.12, 0.12, 0.12); }  // road surface: dark grey
        case 17u: { return vec3<f32>(0.9, 0.7, 0.02); }    // bridge deck: yellow
        case 13u, 14u, 15u, 16u: { return vec3<f32>(0.02, 0.7, 0.8); } // wires, towers: cyan
        default: { return vec3<f32>(0.45, 0.45, 0.45); }   // unclassified and others: grey
    }
}

// Intensity as grey, linear, from black at intensity_range.x to white at .y.
fn intensity_grey(i: f32) -> vec3<f32> {
    let span = max(frame.intensity_range.y - frame.intensity_range.x, 1.0);
    let t = clamp((i - frame.intensity_range.x) / span, 0.0, 1.0);
    return vec3<f32>(t * t);
}

// Returns (return number n of m): single (1 of 1) yellow, first of several green,
// last of several red, intermediate blue. Linear RGB.
fn returns_color(n: u32, m: u32) -> vec3<f32> {
    if m <= 1u { return vec3<f32>(0.9, 0.7, 0.02); }
    if n <= 1u { return vec3<f32>(0.05, 0.6, 0.05); }
    if n >= m { return vec3<f32>(0.75, 0.03, 0.02); }
    return vec3<f32>(0.03, 0.15, 0.8);
}

// The colour of a node with attributes `a` (intensity, class, returns packed as
// src/io/geometry.rs's PointAttributes) in attribute mode `mode`.
fn attribute_color(mode: u32, a: u32) -> vec3<f32> {
    if frame.has_attributes == 0u { return vec3<f32>(0.45, 0.45, 0.45); }
    switch mode {
        case MODE_CLASSIFICATION: { return class_color((a >> 16u) & 0xffu); }
        case MODE_INTENSITY: { return intensity_grey(f32(a & 0xffffu)); }
        default: { return returns_color((a >> 24u) & 15u, a >> 28u); }
    }
}

// The elevation ramp: blue (lowest) through cyan, green and yellow to red (highest),
// linear RGB, at `position` relative to the model origin. Kept in step with the
// viewer's legend (src/apps/view/legend.rs, ELEVATION_RAMP).
fn elevation_color(position: vec3<f32>) -> vec3<f32> {
    let z = dot(position, frame.elevation_up);
    let span = max(frame.elevation_range.y - frame.elevation_range.x, 1e-30);
    let t = clamp((z - frame.elevation_range.x) / span, 0.0, 1.0) * 4.0;
    let k = min(u32(t), 3u);
    let stops = array<vec3<f32>, 5>(
        vec3<f32>(0.02, 0.08, 0.6), vec3<f32>(0.0, 0.55, 0.65), vec3<f32>(0.1, 0.55, 0.05),
        vec3<f32>(0.9, 0.75, 0.02), vec3<f32>(0.7, 0.02, 0.01));
    return mix(stops[k], stops[k + 1u], t - f32(k));
}

@group(0) @binding(0) var<uniform> frame: Frame;

// One node of the sequential list: 32 bytes, as src/tree/record.rs writes it.
struct Node {
    position: vec3<f32>,   // relative to the model origin
    radius: f32,
    normal: vec3<f32>,
    color: vec4<f32>,
    error: f32,            // model units
    parent_error: f32,
    delta: f32,
    level: u32,
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - abs(e.x) - abs(e.y);
    let t = max(-z, 0.0);
    let x = e.x + select(t, -t, e.x >= 0.0);
    let y = e.y + select(t, -t, e.y >= 0.0);
    return normalize(vec3<f32>(x, y, z));
}

// A node's record, its errors in world units: `error_scale` is the placement's (the
// model's error scale times the instance's scale).
fn decode_node(a: vec4<u32>, b: vec4<u32>, error_scale: f32) -> Node {
    var n: Node;
    n.position = bitcast<vec3<f32>>(a.xyz);
    n.radius = bitcast<f32>(a.w);
    n.normal = oct_decode(unpack2x16snorm(b.x));
    n.color = unpack4x8unorm(b.y);
    let errors = unpack2x16float(b.z) * error_scale;
    n.error = errors.x;
    n.parent_error = errors.y;
    n.delta = unpack2x16float(b.w).x * error_scale;
    n.level = b.w >> 16u;
    return n;
}

// Where a model is drawn (src/render/placement.rs): one per instance of the frame, or
// the one of a model drawn alone. A model point x lies at offset + scale · R x, world
// axes, relative to the eye (the offset is computed in f64 on the CPU, so that an
// instance far from the origin keeps its precision). The identity (R = I, scale 1)
// gives the same bits as no placement: R x = x and 1 · x = x exactly.
struct Placement {
    offset: vec3<f32>,
    scale: f32,
    // The unit quaternion of R, (x, y, z, w) as four snorm16.
    rotation: vec2<u32>,
    // The model's error scale times `scale`: stored errors to world units.
    error_scale: f32,
    // A far instance placed by the GPU: its model's table slot (place.wgsl); else 0.
    slot: u32,
}

fn placement_rotation(p: Placement) -> vec4<f32> {
    return normalize(vec4<f32>(unpack2x16snorm(p.rotation.x), unpack2x16snorm(p.rotation.y)));
}

// v rotated by the unit quaternion q: v + w t + q × t with t = 2 q × v.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

// Drawn iff fine enough (e ≤ ε·d) and its parent is not, seen conservatively
// (ε·(d − δ) < e_parent). Without level of detail: the leaves (and zero-error nodes).
fn selected(n: Node, d: f32) -> bool {
    let eps = select(0.0, frame.eps, frame.lod_on != 0u);
    return n.error <= eps * d && eps * (d - n.delta) < n.parent_error;
}

// View-space direction of the ray through a framebuffer position (pixel centre).
fn view_ray(frag: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(frag.x * frame.inv_viewport.x * 2.0 - 1.0, 1.0 - frag.y * frame.inv_viewport.y * 2.0);
    return vec3<f32>(ndc.x * frame.tan_half_fov.x, ndc.y * frame.tan_half_fov.y, -1.0);
}

// Reversed-Z depth of a point at view distance `z` (> 0) in front of the eye.
fn depth_of(z: f32) -> f32 {
    return frame.near / z;
}

// A colour for a tree level (cycles through 8).
fn level_color(level: u32) -> vec3<f32> {
    var palette = array<vec3<f32>, 8>(
        vec3<f32>(0.90, 0.30, 0.25), vec3<f32>(0.95, 0.65, 0.20), vec3<f32>(0.85, 0.85, 0.25),
        vec3<f32>(0.40, 0.80, 0.30), vec3<f32>(0.25, 0.75, 0.75), vec3<f32>(0.30, 0.50, 0.90),
        vec3<f32>(0.60, 0.35, 0.85), vec3<f32>(0.85, 0.40, 0.70));
    return palette[level % 8u];
}

// Blue (small) to red (large) over log2 of the radius relative to the model size.
fn radius_color(radius: f32) -> vec3<f32> {
    let t = clamp((log2(radius / frame.error_scale) + 14.0) / 12.0, 0.0, 1.0);
    return mix(vec3<f32>(0.15, 0.3, 0.95), vec3<f32>(0.95, 0.25, 0.15), t);
}

// A node's disk in view space: centre, unit normal, rendered radius; and its centre
// in world axes relative to the eye, and the rotation of its placement.
struct ViewDisk {
    center: vec3<f32>,
    normal: vec3<f32>,
    radius: f32,
    world: vec3<f32>,
    rotation: vec4<f32>,
}

fn view_disk(n: Node, p: Placement) -> ViewDisk {
    let q = placement_rotation(p);
    let world = p.offset + p.scale * rotate(q, n.position);
    let center = (frame.view * vec4<f32>(world, 1.0)).xyz;
    let normal = normalize((frame.view * vec4<f32>(rotate(q, n.normal), 0.0)).xyz);
    return ViewDisk(center, normal, n.radius * p.scale, world, q);
}

// The per-splat culling of both strategies (vertex stage, or compute compaction): the
// selection test, the view frustum (bounding sphere against the four sides and the near
// plane) and, when asked, back faces.
fn splat_visible(n: Node, disk: ViewDisk) -> bool {
    var lod_distance = length(disk.center);
    if frame.lod_frozen != 0u {
        lod_distance = length(disk.world - frame.lod_eye);
    }
    if !selected(n, lod_distance) {
        return false;
    }
    let r = disk.radius;
    let depth = -disk.center.z;
    let sx = sqrt(1.0 + frame.tan_half_fov.x * frame.tan_half_fov.x);
    let sy = sqrt(1.0 + frame.tan_half_fov.y * frame.tan_half_fov.y);
    if depth + r < frame.near || abs(disk.center.x) - r * sx > frame.tan_half_fov.x * depth
        || abs(disk.center.y) - r * sy > frame.tan_half_fov.y * depth {
        return false;
    }
    return !(frame.cull_back_faces != 0u && dot(disk.normal, disk.center) > 0.0);
}
