#import common
#import constants

// A splat's shape beyond its node record (src/surfel/shape.rs packs it; docs/design.md §7):
// its ellipse's frame, its normal field, its clip, and which of the two pass 2 shaders
// draws it. Imported by the splat passes and by the cull pass, which sorts survivors by
// that last test.

// A splat's ellipse, normal field and clip, as src/surfel/shape.rs packs it.
struct SplatShape {
    axis: u32,       // major axis u, octahedral snorm16 × 2
    ratio_a: u32,    // minor / major semi-axis, a: two f16
    b_c: u32,        // b, c: two f16
    clip: u32,       // a line or a wedge, see is_clipped and clip_vector
    color_a: u32,    // the colour field: cx (r, g, b), cy r as snorm8
    color_b: u32,    // cy g, b as snorm8; their shared scale, f16, in the high half
}

// The colour field's cx and cy (RGB change over one major radius along u and v).
fn color_field(packed: SplatShape) -> array<vec3<f32>, 2> {
    let a = unpack4x8snorm(packed.color_a);
    let b = unpack4x8snorm(packed.color_b);
    let scale = unpack2x16float(packed.color_b).y;
    return array<vec3<f32>, 2>(a.xyz * scale, vec3<f32>(a.w, b.x, b.y) * scale);
}

// Whether a packed clip (src/surfel/clip.rs) cuts anything: a wedge (its tag sets the
// high bits) or a line at a finite offset; NO_CLIP is a line at +∞.
fn is_clipped(bits: u32) -> bool {
    return (bits >> 16u) != (NO_CLIP >> 16u);
}

// The ellipse's axes in view space: u along the stored major axis, v = n × u.
struct ShapeFrame {
    u: vec3<f32>,
    v: vec3<f32>,
    ratio: f32,        // minor / major semi-axis
    gradient: vec3<f32>, // the normal field G = [[a, b], [b, c]] per major radius: a, b, c
}

// `normal`: the splat's, view space; `rotation`: its placement's (ViewDisk::rotation).
fn shape_frame(packed: SplatShape, normal: vec3<f32>, rotation: vec4<f32>) -> ShapeFrame {
    let model_axis = oct_decode(unpack2x16snorm(packed.axis));
    let axis = (frame.view * vec4<f32>(rotate(rotation, model_axis), 0.0)).xyz;
    let u = major_axis(normal, axis);
    let ratio_a = unpack2x16float(packed.ratio_a);
    return ShapeFrame(u, cross(normal, u), ratio_a.x, vec3<f32>(ratio_a.y, unpack2x16float(packed.b_c)));
}

// The unit tangent nearest to `axis` (made ⟂ to `normal`), or any tangent when the
// two are (numerically) parallel.
fn major_axis(normal: vec3<f32>, axis: vec3<f32>) -> vec3<f32> {
    let t = axis - normal * dot(axis, normal);
    if dot(t, t) > 1e-12 {
        return normalize(t);
    }
    return normalize(select(cross(normal, vec3<f32>(0.0, 0.0, 1.0)), cross(normal, vec3<f32>(1.0, 0.0, 0.0)), abs(normal.z) > 0.9));
}

// Which splats a pipeline draws (pipeline-overridable, see splats.rs): all of them, or
// only those whose rim may lie on an outline of the picture (`OUTLINE_SPLATS`), or only
// the others (`INNER_SPLATS`). Pass 2 draws the two kinds with two fragment shaders, so
// that the coverage samples, which only an outline needs, are not compiled into the
// shader of the rest: llvmpipe pays for code under a branch that no fragment takes.
override SPLAT_CLASS: u32 = ALL_SPLATS;

// How near (pixels) an outline may come to a splat's patch before the splat samples its
// coverage: the samples' reach (0.4 px) with room for the estimate of `on_outline`.
const OUTLINE_MARGIN_PX: f32 = 4.0;

// Whether the splat's rim may lie on an outline, so that pass 2 must sample which parts
// of its pixels it covers. Elsewhere its neighbours cover whatever its rim leaves and
// pass 3 takes the pixel as covered. An outline is a border (a clipped splat) or a
// silhouette, where the normal field n(x, y) = n + G (x, y) turns away from the eye:
// over the ellipse x² + (y/ratio)² ≤ 1, e·n(x, y) (e toward the eye) falls at least to
// m = |e·n| − |(w.x, ratio w.y)| − R/d, where w = G (u·e, v·e) is its slope per major
// radius and R/d bounds the turn of e across the patch. Carried on past the rim at that
// slope, it reaches 0 after m/|w| radii, which project to ∫ (m − |w| s) ds = m²/(2|w|)
// radii on the screen (the surface shrinks by e·n as it turns away). Clouds, whose
// normals are not oriented outward, sample every splat.
fn on_outline(disk: ViewDisk, f: ShapeFrame, clip_bits: u32) -> bool {
    return outline_by_kind(clip_bits) || silhouette_near(disk, f);
}

// Whether a splat is on an outline whatever its shape: a border (clipped), or any
// splat of a cloud. The cull pass asks this first, before decoding the shape.
fn outline_by_kind(clip_bits: u32) -> bool {
    return frame.oriented_normals == 0u || is_clipped(clip_bits);
}

// Whether a silhouette may come within OUTLINE_MARGIN_PX of the splat (`on_outline`).
fn silhouette_near(disk: ViewDisk, f: ShapeFrame) -> bool {
    let g = f.gradient;
    let r = disk.radius;
    let d = length(disk.center);
    let e = -disk.center / d;
    let ue = dot(f.u, e);
    let ve = dot(f.v, e);
    let w = vec2<f32>(g.x * ue + g.y * ve, (g.y * ue + g.z * ve) * f.ratio);
    let slope = length(w);
    let m = abs(dot(disk.normal, e)) - slope - r / d;
    let radius_px = 0.5 * frame.viewport.y / frame.tan_half_fov.y * r / d;
    return m <= 0.0 || m * m * radius_px < 2.0 * slope * OUTLINE_MARGIN_PX;
}

