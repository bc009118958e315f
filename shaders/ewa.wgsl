#import common
#import constants
#import shape

// One splat's mathematics, shared by the two ways of drawing it (the raster pipeline,
// splat.wgsl; the compute rasterizer, raster.wgsl): where it lands on the screen
// (`place_splat`), where a pixel's ray meets its curved patch (`hit`), and what each
// pass makes of that pixel (`visibility_depth`, `outline_fragment`, `inner_fragment`,
// `point_fragment`). A module that imports it declares the slice's `nodes`, `shapes`
// and `attributes`, and `surrounded_at` (whether pass 1 found a surface at a pixel and
// its four neighbours).

// A splat's clip (src/surfel/clip.rs) in one vec4, for the fragments: a wedge as the
// unit directions (start, end) of its sides, a line as (cos θ, sin θ, d, LINE_TAG). No
// clip: a line beyond the ellipse (d = 2).
fn clip_vector(bits: u32) -> vec4<f32> {
    if (bits & WEDGE_TAG) == WEDGE_TAG {
        let steps = 1u << WEDGE_ANGLE_BITS;
        let step = 6.283185307179586 / f32(steps);
        let s = f32((bits >> WEDGE_ANGLE_BITS) & (steps - 1u)) * step;
        let e = f32(bits & (steps - 1u)) * step;
        return vec4<f32>(cos(s), sin(s), cos(e), sin(e));
    }
    if !is_clipped(bits) {
        return vec4<f32>(1.0, 0.0, 2.0, LINE_TAG);
    }
    let angle = f32(bits & 0xffffu) * (6.283185307179586 / 65536.0);
    return vec4<f32>(cos(angle), sin(angle), unpack2x16float(bits).y, LINE_TAG);
}

// Marks a line in clip_vector's w (a unit direction's component never reaches it).
const LINE_TAG: f32 = 4.0;

// Whether the clip `c` (clip_vector) cuts plane point p (major radii) away: beyond the
// line; for a wedge, beyond its start side (`start` turned clockwise) or its end side
// (`end` turned counter-clockwise), each moved out by WEDGE_MARGIN, on a convex wedge
// beyond either, on a reflex one beyond both. Both tests are made and one is chosen,
// without a branch: in the five ray tests a fragment may make, a branch here cost
// lavapipe 4 % of the knot's frame, the selects 2 %.
fn clipped(c: vec4<f32>, p: vec2<f32>) -> bool {
    let beyond_line = dot(c.xy, p) > c.z;
    let beyond_start = c.y * p.x - c.x * p.y > WEDGE_MARGIN;
    let beyond_end = c.z * p.y - c.w * p.x > WEDGE_MARGIN;
    let convex = c.x * c.w - c.y * c.z >= 0.0;
    let beyond_wedge = select(beyond_start && beyond_end, beyond_start || beyond_end, convex);
    return select(beyond_wedge, beyond_line, c.w > 2.0);
}

// A splat as its fragments see it: the vertex stage's output, which the raster pipeline
// interpolates flat, or the compute rasterizer's own copy. `clip.xy` is the pixel
// (framebuffer position of its centre), `clip.z` the quad's depth.
struct SplatVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) center: vec3<f32>,   // view space
    @location(1) @interpolate(flat) normal: vec3<f32>,
    @location(2) @interpolate(flat) tangent_u: vec3<f32>,
    @location(3) @interpolate(flat) color: vec4<f32>,
    // x: major radius R, y, z: projected centre (pixels), w: minor / major ratio
    @location(4) @interpolate(flat) extra: vec4<f32>,
    // The normal field G = [[a, b], [b, c]] per major radius: a, b, c
    @location(5) @interpolate(flat) gradient: vec3<f32>,
    // The prefiltered screen-space ellipse as a conic Q (pixels⁻²): Q11, Q12, Q22
    @location(6) @interpolate(flat) conic: vec3<f32>,
    // The same without the prefilter (the flat ellipse's own projection), and in w how
    // much its ρ changes at most over SUBSAMPLE_REACH pixels (see screen_rho)
    @location(7) @interpolate(flat) conic0: vec4<f32>,
    // The clip, see clip_vector
    @location(8) @interpolate(flat) clip_cut: vec4<f32>,
    // How far pass 1 pushes the splat back (view units), before the footprint term
    @location(9) @interpolate(flat) push: f32,
    // The colour field (the node's own colours only): RGB change over one major radius
    // along u and v
    @location(10) @interpolate(flat) color_dx: vec3<f32>,
    @location(11) @interpolate(flat) color_dy: vec3<f32>,
}

// How far beyond a splat's patch its quad reaches, so that it holds every fragment the
// pipeline keeps (pipeline-overridable, see splats.rs and raster.rs). REACH_PATCH: pass 1 and pass 2
// of the inner splats keep only fragments whose centre the patch covers. REACH_SAMPLES:
// pass 2 of the outline splats also keeps those whose coverage samples the patch
// covers, up to SUBSAMPLE_SPAN px away (a fragment of the prefilter's band that covers
// none weighs 0). REACH_BAND: the points keep the whole band. A sub-pixel splat's quad
// is mostly margin: the tighter, the fewer fragments.
override QUAD_REACH: u32 = REACH_BAND;

// Whether pass 2 reads pass 1's depth to spare the coverage samples of surrounded pixels
// (`pixel_coverage`; pipeline-overridable, see splats.rs): a GPU skips the rays; on a
// CPU rasterizer, which runs the five depth loads for every fragment of the shader
// whatever the branch, they cost more than the rays they spare.
override SKIP_SURROUNDED_SAMPLES: bool = true;

// Where a splat's colour comes from (pipeline-overridable: src/render/splats.rs makes a
// pipeline per source, so that each vertex runs only its own).
override COLOR_SOURCE: u32 = COLOR_NODE;

fn splat_color(node: Node, index: u32) -> vec4<f32> {
    switch COLOR_SOURCE {
        case COLOR_LEVELS: { return vec4<f32>(level_color(node.level), 1.0); }
        case COLOR_RADIUS: { return vec4<f32>(radius_color(node.radius), 1.0); }
        case COLOR_ELEVATION: { return vec4<f32>(elevation_color(node.position), 1.0); }
        case COLOR_ATTRIBUTES: {
            let a = attributes[min(index, arrayLength(&attributes) - 1u)];
            return vec4<f32>(attribute_color(frame.mode, a), 1.0);
        }
        default: { return node.color; }
    }
}

// Pixels per view-space unit of a displacement `d` at view-space point `c`: the
// Jacobian of the projection to pixels (y down), applied to d.
fn project_delta(c: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let f = 0.5 * frame.viewport / frame.tan_half_fov;
    let z = -c.z;
    return vec2<f32>(f.x * (d.x + c.x * d.z / z) / z, -f.y * (d.y + c.y * d.z / z) / z);
}

// The splat's ellipse mapped to the screen by the projection's Jacobian at its centre,
// A = [J·R u, J·ratio R v], as the covariance A Aᵀ = (M11, M12, M22), pixels².
fn screen_covariance(center: vec3<f32>, u: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let a = project_delta(center, u);
    let b = project_delta(center, v);
    return vec3<f32>(a.x * a.x + b.x * b.x, a.x * a.y + b.x * b.y, a.y * a.y + b.y * b.y);
}

// The EWA resampling filter (Zwicker et al. 2001): the screen covariance `m` convolved
// with the prefilter of radius p (covariances add: M + p² I), returned as the conic
// (M + p² I)⁻¹.
fn prefiltered_conic(m: vec3<f32>, p: f32) -> vec3<f32> {
    let m11 = m.x + p * p;
    let m22 = m.z + p * p;
    let det = m11 * m22 - m.y * m.y;
    return vec3<f32>(m22, -m.y, m11) / det;
}

// The screen box (NDC, lower and upper corners) of the ellipse c + a cos θ + b sin θ,
// which lies in front of the eye. With C, A, B the clip coordinates of c, a and b (the
// last two as directions), the line x = X touches the projected ellipse where (C_x − X
// C_w) + (A_x − X A_w) cos θ + (B_x − X B_w) sin θ has a double root in θ: (C_x − X C_w)²
// = (A_x − X A_w)² + (B_x − X B_w)², a quadratic α X² − 2 β X + γ whose roots are the
// box's sides (likewise y). Its discriminant β² − α γ is written as (C_w A_x − C_x A_w)²
// + (C_w B_x − C_x B_w)² − (A_w B_x − A_x B_w)², which a splat far smaller than its
// distance does not lose to cancellation. Tighter than the box of the ellipse's
// bounding rectangle by up to √2 along each axis.
fn ellipse_box(c: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> array<vec2<f32>, 2> {
    let pc = frame.proj * vec4<f32>(c, 1.0);
    let pa = frame.proj * vec4<f32>(a, 0.0);
    let pb = frame.proj * vec4<f32>(b, 0.0);
    let alpha = pc.w * pc.w - pa.w * pa.w - pb.w * pb.w;
    let beta = pc.xy * pc.w - pa.xy * pa.w - pb.xy * pb.w;
    let ca = pc.w * pa.xy - pc.xy * pa.w;
    let cb = pc.w * pb.xy - pc.xy * pb.w;
    let ab = pa.w * pb.xy - pa.xy * pb.w;
    let root = sqrt(max(ca * ca + cb * cb - ab * ab, vec2<f32>(0.0)));
    return array<vec2<f32>, 2>((beta - root) / alpha, (beta + root) / alpha);
}

// A splat placed on the screen: what its fragments need, and the box (NDC, lower and
// upper corners) that holds every fragment the pipeline keeps (see QUAD_REACH).
struct Placed {
    splat: SplatVarying,
    lo: vec2<f32>,
    hi: vec2<f32>,
    drawn: bool,
}

// Not drawn: culled, or crossing the near plane.
fn not_placed() -> Placed {
    var out: Placed;
    out.drawn = false;
    return out;
}

// Node `index` of the slice at placement `placement_index` (its instance's, or 0 for a
// model drawn alone) placed on the screen; with `cull`, tested first (the
// selection test and, for one class of splat, `on_outline`). The splat's `clip` holds
// its quad's depth, its xy are the caller's.
fn place_splat(index: u32, placement_index: u32, cull: bool) -> Placed {
    let placement = placements[placement_index];
    let node = decode_node(nodes[2u * index], nodes[2u * index + 1u], placement.error_scale);
    let disk = view_disk(node, placement);
    if cull && !splat_visible(node, disk) {
        return not_placed();
    }
    let center = disk.center;
    let normal = disk.normal;
    let r = disk.radius;
    let near = frame.near;
    let packed = shapes[index];
    let shape = shape_frame(packed, normal, disk.rotation);
    let u = shape.u;
    let v = shape.v;
    let ratio = shape.ratio;
    // Vertex culling draws pass 2 twice, each draw keeping its own kind of splat (the
    // compacted draws read lists that the cull pass sorted by the same test).
    if cull && SPLAT_CLASS != ALL_SPLATS && on_outline(disk, shape, packed.clip) != (SPLAT_CLASS == OUTLINE_SPLATS) {
        return not_placed();
    }
    // Footprint: the screen box of the ellipse p + R u cos θ + ratio R v sin θ. A splat
    // crossing the near plane is skipped rather than drawn garbled.
    let a = r * u;
    let b = ratio * r * v;
    if -center.z - length(vec2<f32>(a.z, b.z)) < near {
        return not_placed();
    }
    let footprint = ellipse_box(center, a, b);
    var lo = footprint[0];
    var hi = footprint[1];
    // Grow by the bulge of the curved patch off its plane, |h| ≤ ½ ‖G‖ R (ρ ≤ 1, see
    // patch_hit) as projected at the centre, up to the prefilter radius, and by what
    // QUAD_REACH adds; the band's reach, the prefilter radius, holds the bulge too.
    let band_px = select(0.0, frame.prefilter_px, frame.ewa > 0.0);
    let g = shape.gradient;
    let g_norm = abs(0.5 * (g.x + g.z)) + sqrt(0.25 * (g.x - g.z) * (g.x - g.z) + g.y * g.y);
    let bulge_px = min(abs(project_delta(center, normal * (0.5 * g_norm * r))), vec2<f32>(band_px));
    var reach_px = bulge_px;
    if QUAD_REACH == REACH_SAMPLES {
        reach_px = min(bulge_px + SUBSAMPLE_SPAN, vec2<f32>(band_px));
    } else if QUAD_REACH == REACH_BAND {
        reach_px = vec2<f32>(band_px);
    }
    let grow = 2.0 * reach_px * frame.inv_viewport;
    lo -= grow;
    hi += grow;
    let cp = frame.proj * vec4<f32>(center, 1.0);
    let center_px = vec2<f32>((cp.x / cp.w * 0.5 + 0.5) * frame.viewport.x, (0.5 - cp.y / cp.w * 0.5) * frame.viewport.y);
    var out: SplatVarying;
    out.clip = vec4<f32>(0.0, 0.0, nearest_depth(center, r), 1.0);
    out.center = center;
    out.normal = normal;
    out.tangent_u = u;
    out.color = splat_color(node, index);
    if COLOR_SOURCE == COLOR_NODE {
        let field = color_field(packed);
        out.color_dx = field[0];
        out.color_dy = field[1];
    }
    out.extra = vec4<f32>(r, center_px, ratio);
    out.gradient = shape.gradient;
    let covariance = screen_covariance(center, a, b);
    out.conic = prefiltered_conic(covariance, frame.prefilter_px);
    let conic0 = prefiltered_conic(covariance, 1e-3);
    out.conic0 = vec4<f32>(conic0, rho_reach(conic0));
    out.clip_cut = clip_vector(packed.clip);
    // A fraction of the radius, plus the node's own error for an inner node: its patch
    // may lie that far off the surface its neighbours draw.
    out.push = frame.depth_push * r + node.error;
    return Placed(out, lo, hi, true);
}

// The quad's depth: that of the nearest point the splat can have (view distance
// −c.z − R, see `hit`), at most 1. Every fragment shader writes a depth no nearer
// (`@early_depth_test(less_equal)`: reversed-Z, nearer is greater), so the GPU may
// reject a fragment by the quad's depth before running it.
fn nearest_depth(center: vec3<f32>, r: f32) -> f32 {
    return depth_of(max(-center.z - r, frame.near));
}

// The depth a fragment writes at view distance z ≥ −c.z − R: no nearer than the
// quad's (`nearest_depth`), however near z comes to the eye.
fn fragment_depth(z: f32) -> f32 {
    return depth_of(max(z, frame.near));
}

// Where the ray through a framebuffer position meets a splat's patch.
struct PatchHit {
    // The ellipse's ρ² = x² + (y / ratio)² at the hit; 10⁹ when the ray misses the patch.
    object2: f32,
    // Ray parameter of the hit (view distance, as view rays have z = −1).
    t: f32,
    // Plane coordinates of the hit, in major radii.
    xy: vec2<f32>,
}

// The splat is the paraboloid patch h = −½ (x, y) G (x, y)ᵀ over its plane (the surface
// whose normals are the field), in major radii. From the plane hit (x₀, y₀) the ray
// moves by (s du, s dv, s dn): s dn + ½ Q(x₀ + s du, y₀ + s dv) = 0, whose root nearest
// the plane is taken. No root: the ray passes beside the curved patch's silhouette. A
// hit the clip cuts away misses too.
fn patch_hit(in: SplatVarying, pixel: vec2<f32>) -> PatchHit {
    let miss = PatchHit(1e9, -in.center.z, vec2<f32>(0.0));
    let dir = view_ray(pixel);
    let denom = dot(dir, in.normal);
    if abs(denom) < 1e-7 * length(dir) {
        return miss;
    }
    let t = dot(in.center, in.normal) / denom;
    if t <= 0.0 {
        return miss;
    }
    let r = in.extra.x;
    let ratio = in.extra.w;
    let v = cross(in.normal, in.tangent_u);
    let g = in.gradient;
    let p0 = dir * t - in.center;
    let xy0 = vec2<f32>(dot(p0, in.tangent_u), dot(p0, v)) / r;
    let dxy = vec2<f32>(dot(dir, in.tangent_u), dot(dir, v)) / r;
    let qa = 0.5 * (g.x * dxy.x * dxy.x + 2.0 * g.y * dxy.x * dxy.y + g.z * dxy.y * dxy.y);
    let qb = denom / r + g.x * xy0.x * dxy.x + g.y * (xy0.x * dxy.y + xy0.y * dxy.x) + g.z * xy0.y * dxy.y;
    let qc = 0.5 * (g.x * xy0.x * xy0.x + 2.0 * g.y * xy0.x * xy0.y + g.z * xy0.y * xy0.y);
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return miss;
    }
    let root = qb + select(-1.0, 1.0, qb >= 0.0) * sqrt(disc);
    let s = select(-2.0 * qc / root, 0.0, abs(root) < 1e-30);
    let xy = xy0 + s * dxy;
    if clipped(in.clip_cut, xy) {
        return miss;
    }
    return PatchHit(xy.x * xy.x + xy.y * xy.y / (ratio * ratio), t + s, xy);
}

// Offsets of the coverage samples within a pixel (a rotated grid).
const SUBSAMPLES = array<vec2<f32>, 4>(
    vec2<f32>(0.125, -0.375), vec2<f32>(0.375, 0.125), vec2<f32>(-0.125, 0.375), vec2<f32>(-0.375, -0.125));
// The largest coordinate of SUBSAMPLES: a fragment whose samples a patch covers lies
// within that many pixels of it along x and y.
const SUBSAMPLE_SPAN: f32 = 0.375;

// Which of the pixel's four coverage samples the splat's patch covers (1 or 0 each).
fn subsample_coverage(in: SplatVarying) -> vec4<f32> {
    var covered = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        covered[k] = select(0.0, 1.0, patch_hit(in, in.clip.xy + SUBSAMPLES[k]).object2 <= 1.0);
    }
    return covered;
}

// Farthest coverage sample from the pixel centre (pixels), with a margin of 2 for the
// patch's curvature and perspective, which the projected ellipse leaves out.
const SUBSAMPLE_REACH: f32 = 2.0 * 0.3953;

// How much the projected ellipse's ρ changes at most over SUBSAMPLE_REACH pixels: √λmax
// of its conic q times the reach (once per splat).
fn rho_reach(q: vec3<f32>) -> f32 {
    let lmax = 0.5 * (q.x + q.z) + sqrt(0.25 * (q.x - q.z) * (q.x - q.z) + q.y * q.y);
    return sqrt(lmax) * SUBSAMPLE_REACH;
}

// The projected ellipse's ρ (1 on its rim) at the pixel centre.
fn screen_rho(in: SplatVarying) -> f32 {
    return sqrt(conic_at(in.conic0.xyz, in.clip.xy - in.extra.yz));
}

// The pixel's four coverage samples that the patch covers (pass 2 only). Far enough
// inside the projected ellipse, all four; far enough outside, none. A fragment whose
// centre the patch covers counts as covering at least one sample (the centre's share).
// Where the pixel is surrounded, pass 3 does not read the samples, and they only set a
// fragment's weight: one whose centre the patch covers weighs the same whatever they
// say (all four, then), and one of the prefilter's band, which weighs 1/16 of those at
// most, takes them from the flat ellipse's conic (`conic_coverage`). That spares the
// rays inside the picture's outlines, which cost an H100 most of pass 2.
fn pixel_coverage(in: SplatVarying, h: Hit) -> vec4<f32> {
    let rho = screen_rho(in);
    let reach = in.conic0.w;
    if h.centre_inside && rho <= 1.0 - reach {
        return vec4<f32>(1.0);
    }
    if !h.centre_inside && rho > 1.0 + reach {
        return vec4<f32>(0.0);
    }
    if SKIP_SURROUNDED_SAMPLES && surrounded_at(vec2<i32>(in.clip.xy)) {
        if h.centre_inside {
            return vec4<f32>(1.0);
        }
        return conic_coverage(in);
    }
    var covered = subsample_coverage(in);
    covered.x = select(covered.x, 1.0, h.centre_inside && all(covered == vec4<f32>(0.0)));
    return covered;
}

// Which of the pixel's coverage samples the flat ellipse's projection covers: the conic
// of its affine projection at the centre, without the patch's curvature, perspective
// or clip (cheap, and exact enough for a weight).
fn conic_coverage(in: SplatVarying) -> vec4<f32> {
    var covered = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let d = in.clip.xy + SUBSAMPLES[k] - in.extra.yz;
        covered[k] = select(0.0, 1.0, conic_at(in.conic0.xyz, d) <= 1.0);
    }
    return covered;
}

struct Hit {
    // Squared splat-space distance (object space, or screen space under the prefilter).
    rho2: f32,
    // View distance of the hit.
    depth: f32,
    // The normal field there (view space, unit).
    normal: vec3<f32>,
    // Whether the patch itself (not only the prefilter) covers the pixel centre.
    centre_inside: bool,
    // Plane coordinates of the hit in major radii, held within the rim.
    xy: vec2<f32>,
}

// dᵀ Q d for a conic Q = (Q11, Q12, Q22).
fn conic_at(q: vec3<f32>, d: vec2<f32>) -> f32 {
    return q.x * d.x * d.x + 2.0 * q.y * d.x * d.y + q.z * d.y * d.y;
}

// The pixel centre's ray against the splat. Whether a fragment whose centre the patch
// misses is kept is each pass's choice: pass 2 keeps it if the patch covers one of its
// coverage samples (weighed by the prefilter's band and the share covered), the points
// if the band reaches it.
fn hit(in: SplatVarying) -> Hit {
    let h = patch_hit(in, in.clip.xy);
    var rho2 = h.object2;
    if h.object2 > 1.0 && frame.ewa > 0.0 && screen_rho(in) > 1.0 {
        // The prefilter widens the splat by a band around its projected rim; inside the
        // rim, where the curved patch turns away from the ray, it adds nothing.
        rho2 = min(rho2, conic_at(in.conic, in.clip.xy - in.extra.yz));
    }
    // Every point of the splat lies within ±R of its centre's depth. Under the prefilter
    // a pixel beside a splat meets its plane far from it (or not at all): keep its depth
    // in the splat's range so it cannot win the depth test wrongly, and read the normal
    // field at the rim.
    let r = in.extra.x;
    let depth = clamp(h.t, -in.center.z - r, -in.center.z + r);
    let xy = h.xy / max(1.0, sqrt(min(h.object2, 1e6)));
    let g = in.gradient;
    let v = cross(in.normal, in.tangent_u);
    let n = in.normal + in.tangent_u * (g.x * xy.x + g.y * xy.y) + v * (g.y * xy.x + g.z * xy.y);
    return Hit(rho2, depth, normalize(n), h.object2 <= 1.0, xy);
}

// Beyond the rim (of the patch, or of the prefilter's band), or where the weight is too
// small for the half-float targets (it would leave colour 0 with w > 0: black).
fn outside(rho2: f32) -> bool {
    return rho2 > 1.0 || kernel(rho2) < MIN_WEIGHT;
}

// Pass 1: depth pushed back along the view ray so that the splats of one surface that
// share a pixel pass pass 2's depth test and blend: by a fraction of the radius and the
// node's error, plus the depth range the pixel's prefilter footprint spans on the
// splat's plane (large when the surface is seen at a grazing angle and minified).
// Returns the reversed-Z depth, or 0 (none) where the patch misses the pixel centre:
// fragments the prefilter alone adds do not occlude (what lies behind them shows
// through their partial coverage); the patches cover the surface, so a pixel centre on
// it always meets one.
fn visibility_depth(in: SplatVarying) -> f32 {
    let h = hit(in);
    if !h.centre_inside {
        return 0.0;
    }
    return fragment_depth(h.depth + push_back(in, h));
}

// How far pass 1 pushes a fragment back (view units): the splat's push, and the depth
// range the pixel's prefilter footprint spans on its plane.
fn push_back(in: SplatVarying, h: Hit) -> f32 {
    let dir = normalize(view_ray(in.clip.xy));
    let c = max(abs(dot(dir, in.normal)), 0.02);
    let pixel = h.depth * 2.0 * frame.tan_half_fov.y * frame.inv_viewport.y;
    let footprint = frame.prefilter_px * pixel * sqrt(1.0 - c * c) / c;
    return in.push + footprint;
}

// What a fragment of pass 2 (or a point) writes, if it is `kept`: (colour·w, w),
// (normal·w, view distance·w), the four coverage samples (blended by max) and its depth.
struct Fragment {
    kept: bool,
    color: vec4<f32>,
    normal: vec4<f32>,
    coverage: vec4<f32>,
    depth: f32,
}

// A fragment that writes nothing.
fn dropped() -> Fragment {
    var out: Fragment;
    out.kept = false;
    return out;
}

// Splat kernel: a Gaussian of the splat-space distance, shifted and rescaled to reach 0
// at the rim (ρ = 1) so that where a splat ends the blend has no step.
fn kernel(rho2: f32) -> f32 {
    let rim = exp(-KERNEL_SHARPNESS);
    return max(exp(-KERNEL_SHARPNESS * rho2) - rim, 0.0) / (1.0 - rim);
}

const KERNEL_SHARPNESS: f32 = 2.5;

// What a fragment seen from behind weighs against front ones, on a model whose normals
// face outward. Where only such fragments reach a pixel the weight cancels out in pass 3;
// where front ones blend with them they dominate. Measured, leaves only, 8 views (knot,
// bunny, dragon FLIP): 1 (no weighting) 0.0737, 0.0362, 0.0323; 1/16 0.0703, 0.0348,
// 0.0297; 1/64 0.0700, 0.0346, 0.0294; 1/256 0.0699, 0.0346, 0.0292.
const BACK_WEIGHT: f32 = 1.0 / 64.0;
// The least weight a fragment adds: below it, colour·w would fall to the half-float
// targets' subnormals (a band fragment's is set to 0, see `centre_weight` for the others).
const MIN_WEIGHT: f32 = 1.0 / 1024.0;
// What a fragment of the prefilter's band weighs against one whose centre a patch
// covers: it gives colour to a pixel that no patch covers at its centre (a silhouette
// pixel the patches cover in part) and next to nothing elsewhere. At full weight the
// bands of neighbouring splats blurred the normals across the inside of the surface
// (knot FLIP 0.0758 against 0.0736). 1/16 keeps the sums of band-only pixels well above
// the half-float targets' subnormals.
const BAND_WEIGHT: f32 = 1.0 / 16.0;

// Pass 2 for the splats on an outline: kernel weight of the splat-space distance,
// additive blending, and the pixel's coverage samples.
fn outline_fragment(in: SplatVarying) -> Fragment {
    let h = hit(in);
    let coverage = pixel_coverage(in, h);
    // A fragment of the prefilter's band weighs by the share of the pixel it covers,
    // and BAND_WEIGHT: one that covers none of it adds nothing.
    if !h.centre_inside && all(coverage == vec4<f32>(0.0)) {
        return dropped();
    }
    var w = kernel(h.rho2) * dot(coverage, vec4<f32>(0.25)) * BAND_WEIGHT;
    if w < MIN_WEIGHT * BAND_WEIGHT {
        w = 0.0;
    }
    return blended(in, h, select(w, centre_weight(h.rho2), h.centre_inside), coverage);
}

// Pass 2 for the splats inside the picture's outlines: fragments whose centre the patch
// covers, as covering the whole pixel. Those of the prefilter's band are left out: they
// only give colour where no patch covers a pixel's centre, which inside the outlines
// the neighbouring patches do.
fn inner_fragment(in: SplatVarying) -> Fragment {
    let h = hit(in);
    if !h.centre_inside {
        return dropped();
    }
    return blended(in, h, centre_weight(h.rho2), vec4<f32>(1.0));
}

// The weight of a fragment whose centre the patch covers: the kernel, but at least
// MIN_WEIGHT, so that a pixel centre that only a patch's outermost rim reaches is not
// left empty (a pinhole of background: terrain_utm's holes 0.47 → 0.32 %, kinect_rgb's
// 0.20 → 0.12 %).
fn centre_weight(rho2: f32) -> f32 {
    return max(kernel(rho2), MIN_WEIGHT);
}

// A pass 2 fragment of weight w: (colour·w, w), (normal·w, z·w) and the coverage.
fn blended(in: SplatVarying, h: Hit, weight: f32, coverage: vec4<f32>) -> Fragment {
    var w = weight;
    let q = view_ray(in.clip.xy) * h.depth;
    // Two-sided: a normal facing away from the eye is flipped before blending. Where
    // normals face out of the surface (a mesh's, given ones, a terrain's turned up:
    // cloud_quality --terrain 0.2280 -> 0.2265), such a fragment shows its back, which
    // is what the pixel shows where nothing else reaches it (inside a hole's rim); but
    // where front fragments blend with it (a silhouette or a fold, within pass 1's
    // push) it is the far side that the surface hides, and weighs BACK_WEIGHT of them.
    let back = dot(h.normal, q) > 0.0;
    let n = select(h.normal, -h.normal, back);
    let hidden_side = back && (frame.oriented_normals != 0u || frame.normals_up != 0u);
    w *= select(1.0, BACK_WEIGHT, hidden_side);
    var out: Fragment;
    out.kept = true;
    let color = clamp(in.color.rgb + in.color_dx * h.xy.x + in.color_dy * h.xy.y, vec3<f32>(0.0), vec3<f32>(1.0));
    out.color = vec4<f32>(color * w, w);
    out.normal = vec4<f32>(n * w, h.depth * w);
    out.coverage = select(OFF_FRONT_COVERAGE * coverage, coverage, h.centre_inside && !hidden_side);
    out.depth = fragment_depth(h.depth);
    return out;
}

// Plain points (no blending): the disk's centre pixel area, nearest wins.
fn point_fragment(in: SplatVarying) -> Fragment {
    let h = hit(in);
    if outside(h.rho2) {
        return dropped();
    }
    let q = view_ray(in.clip.xy) * h.depth;
    let n = select(h.normal, -h.normal, dot(in.normal, q) > 0.0);
    var out: Fragment;
    out.kept = true;
    out.color = vec4<f32>(in.color.rgb, 1.0);
    out.normal = vec4<f32>(n, h.depth);
    out.coverage = vec4<f32>(1.0);
    out.depth = fragment_depth(h.depth);
    return out;
}
