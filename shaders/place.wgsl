#import constants
#import common
#import far

// Places a model's far instances on the GPU (src/render/far.rs): a workgroup per
// group of instances the CPU found far from the eye, a thread per member. A member the
// view cone may see takes its model's ranges at its rounded distance (the table slot
// of lod.rs: ⌊16 log₂(d / r)⌋, d the eye's distance to its sphere in model units), and
// is appended to the frame's placements after the CPU's, with its slot.

// An instance: where its model's origin lies relative to the scene's origin, as an f32
// and the f16 rest of its f64 value; its scale; its unit rotation as four snorm16.
struct FarInstance {
    anchor: vec3<f32>,
    scale: f32,
    anchor_rest: vec2<u32>,
    rotation: vec2<u32>,
}

// The frame, for one model: the eye relative to the scene's origin (f32 and rest),
// the model's sphere (centre relative to its origin, radius), its error scale, and the
// view cone (world axes, tangents of the half field of view, their secants).
struct PlaceParams {
    eye: vec3<f32>,
    radius: f32,
    eye_rest: vec3<f32>,
    error_scale: f32,
    centre: vec3<f32>,
    near: f32,
    right: vec3<f32>,
    tan_x: f32,
    up: vec3<f32>,
    tan_y: f32,
    forward: vec3<f32>,
    secant_x: f32,
    secant_y: f32,
    pad_a: f32,
    pad_b: f32,
    pad_c: f32,
}

@group(1) @binding(0) var<uniform> params: PlaceParams;
@group(1) @binding(1) var<storage, read> instances: array<FarInstance>;
// The far groups' members: model-local instance index ranges.
@group(1) @binding(2) var<storage, read> far_groups: array<vec2<u32>>;
@group(1) @binding(3) var<storage, read> entries: array<FarEntry>;
@group(1) @binding(4) var<storage, read_write> placed: array<Placement>;
@group(1) @binding(5) var<storage, read_write> counters: FarCounters;

// Whether the view may see a sphere at `v` (relative to the eye) of radius `r`: as
// `ViewCone::sees_sphere` on the CPU, with its slack for f32.
fn sees_sphere(v: vec3<f32>, radius: f32) -> bool {
    let x = dot(v, params.right);
    let y = dot(v, params.up);
    let depth = dot(v, params.forward);
    let r = radius + 1e-4 * (length(v) + radius);
    return depth + r >= params.near && abs(x) - r * params.secant_x <= params.tan_x * depth
        && abs(y) - r * params.secant_y <= params.tan_y * depth;
}

@compute @workgroup_size(GROUP)
fn place(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let members = far_groups[group.x];
    let k = members.x + lane;
    if k >= members.y {
        return;
    }
    let instance = instances[k];
    let rest = vec3<f32>(unpack2x16float(instance.anchor_rest.x), unpack2x16float(instance.anchor_rest.y).x);
    let offset = (instance.anchor - params.eye) + (rest - params.eye_rest);
    let q = normalize(vec4<f32>(unpack2x16snorm(instance.rotation.x), unpack2x16snorm(instance.rotation.y)));
    let centre = offset + instance.scale * rotate(q, params.centre);
    if !sees_sphere(centre, params.radius * instance.scale) {
        return;
    }
    // Rounded down, and a little more for f32: the CPU's table holds the ranges of
    // every slot from the groups' nearest to their farthest.
    let d = max(length(centre) / instance.scale - params.radius, 0.0) * (1.0 - 1e-5);
    let step = floor(log2(max(d / params.radius, 1e-30)) * STEPS_PER_OCTAVE);
    let slot = u32(i32(clamp(step, -f32(STEPS), f32(STEPS))) + STEPS);
    let entry = entries[slot];
    if entry.nodes == 0u {
        return;
    }
    let j = atomicAdd(&counters.visible, 1u);
    placed[counters.base + j] = Placement(offset, instance.scale, instance.rotation, params.error_scale * instance.scale, slot);
    atomicAdd(&counters.nodes, entry.nodes);
}
