#import common
#import fullscreen
#import surrounded

// Pass 3: divide the blended attributes by their weight and shade each pixel (Blinn-Phong with a
// movable light); background where no splat contributed, unless the pixel is a gap
// between two pixels of one surface, and a surface's front where only its hidden side
// shows through a slit in it (`fill_between`). Writes an sRGB target and the mask of
// the pixels that show a surface: as a full-screen triangle through the raster
// pipeline (`fs_shade`), or one compute thread per pixel (`cs_shade`, after the compute
// rasterizer, so that no pass of its frames goes through the raster pipeline).

@group(1) @binding(0) var color_sum: texture_2d<f32>;
@group(1) @binding(1) var normal_sum: texture_2d<f32>;
// The four coverage samples of each pixel (max over the splats drawn there).
@group(1) @binding(2) var coverage: texture_2d<f32>;
// The depth of the nearest surface at the pixel centre (reversed Z; 0: none), read as
// a float texture (GLSL cannot load texels of a depth texture).
@group(1) @binding(3) var depth: texture_2d<f32>;
// `cs_shade`'s targets: the output's bytes (sRGB-encoded here, as the raster pipeline
// encodes what `fs_shade` writes) and the covered mask.
@group(2) @binding(0) var shaded_out: texture_storage_2d<rgba8unorm, write>;
@group(2) @binding(1) var covered_out: texture_storage_2d<r32uint, write>;

// A pixel's G-buffer sums: colour·w and w, normal·w and view distance·w.
struct Sums {
    c: vec4<f32>,
    nz: vec4<f32>,
}

// A shaded pixel: its linear colour, and 1 where it shows a surface, 0 where it shows
// the background (what image metrics read back as the covered pixels).
struct Pixel {
    color: vec3<f32>,
    covered: u32,
}

// `fs_shade`'s targets: the linear colour (the sRGB target encodes it) and the mask.
struct Shaded {
    @location(0) color: vec4<f32>,
    @location(1) covered: u32,
}

@fragment
fn fs_shade(@builtin(position) frag: vec4<f32>) -> Shaded {
    let pixel = shade_pixel(vec2<i32>(frag.xy));
    return Shaded(vec4<f32>(pixel.color, 1.0), pixel.covered);
}

@compute @workgroup_size(PIXEL_TILE, PIXEL_TILE)
fn cs_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= vec2<u32>(frame.viewport)) {
        return;
    }
    let texel = vec2<i32>(id.xy);
    let pixel = shade_pixel(texel);
    textureStore(shaded_out, texel, vec4<f32>(srgb_encode(pixel.color), 1.0));
    textureStore(covered_out, texel, vec4<u32>(pixel.covered, 0u, 0u, 0u));
}

// The sRGB encoding of a linear colour, clamped to [0, 1] (IEC 61966-2-1): 12.92 c up
// to 0.0031308, 1.055 c^(1/2.4) − 0.055 above.
fn srgb_encode(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    let curve = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(curve, 12.92 * c, c <= vec3<f32>(0.0031308));
}

// The pixel at `texel`, whose centre is texel + 0.5.
fn shade_pixel(texel: vec2<i32>) -> Pixel {
    let centre = vec2<f32>(texel) + 0.5;
    var sums = Sums(textureLoad(color_sum, texel, 0), textureLoad(normal_sum, texel, 0));
    let marked = textureLoad(coverage, texel, 0);
    let samples = ceil(marked);
    var covered = sums.c.w > 0.0 && any(samples > vec4<f32>(0.0));
    // A gap of a cloud's sampling (no patch covers the centre) or a slit in a front
    // surface (only patches seen from behind do); one call, so that the shader holds
    // the fill's code once (a CPU rasterizer runs every branch under a mask).
    let here = textureLoad(depth, texel, 0).x;
    let slit = here > 0.0 && !front_at_centre(marked);
    var fill = Sums(vec4<f32>(0.0), vec4<f32>(0.0));
    if slit || (here <= 0.0 && fills_gaps()) {
        fill = fill_between(texel, slit);
    }
    let filled = fill.c.w > 0.0;
    if filled {
        sums = fill;
        covered = true;
    }
    if sums.c.w <= 0.0 {
        return Pixel(frame.background.rgb, 0u);
    }
    let inside = surrounded(depth, texel);
    let alpha = select(coverage_alpha(samples, inside), 1.0, filled);
    return Pixel(shade(centre, texel, sums, alpha, inside), u32(covered));
}

// The colour of a pixel whose G-buffer sums are `sums`, blended over the background
// by `alpha`; `inside`: the pixel and its four neighbours show a surface.
//
// The diffuse term is linear in the normal, so the mean of the blended fragments'
// n·l is l·n̄ with n̄ = Σ w n / Σ w, the weighted mean normal, not normalized: where
// the splats' normals disagree within the pixel's filter (the one-pixel ridges of a
// quantised depth frame), |n̄| < 1 darkens the pixel as averaging the reference's
// shaded supersamples does. Beside the background the blended fragments are a rim's,
// whose normals turn edge-on and flip to face the eye where the reference shows one
// front side: there the diffuse term takes the normalized n̄ (docs/point-clouds.md).
fn shade(frag: vec2<f32>, texel: vec2<i32>, sums: Sums, alpha: f32, inside: bool) -> vec3<f32> {
    let color = sums.c.rgb / sums.c.w;
    let mean_n = rim_normal(texel, sums.nz.xyz / sums.c.w);
    let n = normalize(mean_n);
    if frame.mode == MODE_NORMALS {
        return n * 0.5 + 0.5;
    }
    if frame.mode == MODE_EDL {
        return mix(frame.background.rgb, color * eye_dome(texel), alpha);
    }
    let q = view_ray(frag) * (sums.nz.w / sums.c.w);
    let l = normalize(frame.light_dir);
    let v = normalize(-q);
    let h = normalize(l + v);
    let diffuse = max(dot(select(n, mean_n, inside), l), 0.0);
    let exponent = toksvig_exponent(select(1.0, length(mean_n), inside));
    let lobe = (1.0 + exponent) / (1.0 + SHININESS) * pow(max(dot(n, h), 0.0), exponent);
    let specular = frame.specular * lobe * select(0.0, 1.0, diffuse > 0.0);
    let shaded = color * (0.25 + 0.75 * diffuse) + vec3<f32>(specular);
    return mix(frame.background.rgb, shaded, alpha);
}

// The mean normal `mean_n` at a pixel; on a cloud of unknown orientation where it has
// cancelled (shorter than CANCELLED), the mean of the normals of the pixel's four
// neighbours that show the same surface and did not cancel. Normals flipped to face
// the eye cancel only where they lie nearly in the picture's plane and point opposite
// ways: on a rim, where a splat just past the horizon faces away, flips, and points
// into the surface (docs/point-clouds.md); its pixel showed as a dark dot.
fn rim_normal(texel: vec2<i32>, mean_n: vec3<f32>) -> vec3<f32> {
    if frame.normals_unknown == 0u || dot(mean_n, mean_n) >= CANCELLED * CANCELLED {
        return mean_n;
    }
    let here = textureLoad(depth, texel, 0).x;
    var borrowed = vec3<f32>(0.0);
    for (var k = 1; k < 5; k++) {
        let there = texel + CROSS[k];
        if !one_surface(here, side_depth(there, false)) {
            continue;
        }
        let w = textureLoad(color_sum, there, 0).w;
        let nz = textureLoad(normal_sum, there, 0).xyz / max(w, 1e-30);
        if w > 0.0 && dot(nz, nz) >= CANCELLED * CANCELLED {
            borrowed += normalize(nz);
        }
    }
    return select(mean_n, normalize(borrowed), dot(borrowed, borrowed) > 0.0);
}

// Below this length an unoriented cloud's mean normal has cancelled (`rim_normal`).
const CANCELLED: f32 = 0.5;

// The Blinn-Phong exponent of the highlight.
const SHININESS: f32 = 32.0;

// The highlight's exponent for blended normals whose mean has length `mean_length`
// (Toksvig 2005): the normals spread about their mean as a Gaussian lobe would, so the
// mean of their highlights is a wider and dimmer one, of exponent s·f with f = |n̄| /
// (|n̄| + s (1 − |n̄|)), its peak scaled by (1 + s·f) / (1 + s) to keep its energy.
// Unlike the diffuse term, the highlight is not linear in the normal: shading the
// normalized mean lit every pixel where disagreeing normals met as if they agreed, in
// bright specks on a terrain's facets (cloud_quality --terrain 0.1542 → 0.1531).
fn toksvig_exponent(mean_length: f32) -> f32 {
    let m = clamp(mean_length, 0.0, 1.0);
    return SHININESS * m / max(m + SHININESS * (1.0 - m), 1e-6);
}

// The share of the pixel's coverage `samples` that the splats cover (all of it where
// the pixel and its neighbours show a surface at their centres: `inside`).
fn coverage_alpha(samples: vec4<f32>, inside: bool) -> f32 {
    return select(dot(samples, vec4<f32>(0.25)), 1.0, inside);
}

// The eight unit directions eye-dome lighting looks in, every 45°.
const EDL_DIRECTIONS = array<vec2<f32>, 8>(
    vec2<f32>(1.0, 0.0), vec2<f32>(0.70710678, 0.70710678), vec2<f32>(0.0, 1.0), vec2<f32>(-0.70710678, 0.70710678),
    vec2<f32>(-1.0, 0.0), vec2<f32>(-0.70710678, -0.70710678), vec2<f32>(0.0, -1.0), vec2<f32>(0.70710678, -0.70710678));

// Eye-dome lighting (Boucheny 2009, as Potree draws it): with D = log₂ of the view
// distance, the mean over 8 neighbours at edl_radius_px of max(0, D(pixel) −
// D(neighbour)) (how far the pixel lies behind what surrounds it), as the factor
// exp(−300 · strength · mean). D comes from pass 1's f32 depth (reversed Z: depth =
// near / distance, so D(p) − D(n) = log₂ depth(n) − log₂ depth(p)): the blended depth
// of pass 2 is a half-float sum, whose rounding the factor 300 would make visible.
// Background neighbours count nothing.
fn eye_dome(texel: vec2<i32>) -> f32 {
    let here = textureLoad(depth, texel, 0).x;
    if here <= 0.0 {
        return 1.0;
    }
    let last = vec2<i32>(textureDimensions(depth)) - 1;
    var sum = 0.0;
    for (var k = 0; k < 8; k++) {
        let offset = vec2<i32>(round(frame.edl_radius_px * EDL_DIRECTIONS[k]));
        let there = textureLoad(depth, clamp(texel + offset, vec2<i32>(0), last), 0).x;
        if there > 0.0 {
            sum += max(0.0, log2(there) - log2(here));
        }
    }
    return exp(-300.0 * frame.edl_strength * sum / 8.0);
}

// Directions across which a pixel may be a gap: x, y and the two diagonals.
const GAP_DIRECTIONS = array<vec2<i32>, 4>(vec2<i32>(1, 0), vec2<i32>(0, 1), vec2<i32>(1, 1), vec2<i32>(1, -1));

// How much nearer one side of a gap may be than the other, as a ratio of pass 1's
// reversed-Z depths (= inverse view distances): 10 %.
const GAP_DEPTH_RATIO = 1.1;

// Across how many of the four directions a pixel must lie between one surface's pixels
// to be a gap: two. A pixel inside a slit of any slope lies across at least two (the
// one nearest the slit's normal and a diagonal); a one-pixel notch in an outline,
// across one. (One: the outline's notches filled, more spill; three: the tile's worst
// view kept 0.58 % holes. docs/point-clouds.md.)
const GAP_MIN_DIRECTIONS = 2;

// Whether pixels whose centre no splat covers are filled as gaps (`fill_between`):
// the sampling left a slit narrower than the splats' spacing, which the triangles
// between the same samples would cover. Only on clouds whose normals were estimated
// (not oriented), as `on_outline` tells them: a mesh's splats cover its triangles by
// construction, so a gap between them is the mesh's own (and the mesh pass has none);
// plain points show the splats as they are.
fn fills_gaps() -> bool {
    return frame.mode != MODE_MESH && frame.mode != MODE_POINTS && frame.oriented_normals == 0u;
}

// Whether a patch's front covers the pixel centre: a covered sample of the pixel is 1
// (OFF_FRONT_COVERAGE where only fragments seen from behind, or the prefilter's band,
// cover it).
fn front_at_centre(marked: vec4<f32>) -> bool {
    return any(marked >= vec4<f32>(1.0));
}

// Fills a pixel when, along GAP_MIN_DIRECTIONS or more of x, y and the diagonals, the
// pixels on both sides within two pixels show one surface (pass 1's depth at their
// centres, within GAP_DEPTH_RATIO). Returns the sums of the two sides' mean
// attributes, for every direction across which the pixel is such a gap (w = the
// number of pixels summed; w = 0: not a gap). Two kinds of pixel are filled:
// - a gap of a cloud's sampling, whose centre no splat covers (`fills_gaps`);
// - with `slit`, a pixel whose centre only patches seen from behind cover (the hidden
//   side of an outward-facing surface) between pixels that a front covers: a slit in
//   that front surface, not a view into a hole. Seen edge-on near a contour, patches
//   that lie a little off the surface they sample meet the view rays beyond their rims
//   (an offset h off the surface moves the hit by h / tan θ along it) and leave such
//   slits, through which the sheet behind the contour showed as specks facing the
//   other way (docs/image-quality.md).
fn fill_between(texel: vec2<i32>, slit: bool) -> Sums {
    var sums = Sums(vec4<f32>(0.0), vec4<f32>(0.0));
    var across = 0;
    for (var k = 0; k < 4; k++) {
        let d = GAP_DIRECTIONS[k];
        let ahead = side_depth(texel + d, slit);
        let behind = side_depth(texel - d, slit);
        var sides = vec2<i32>(0);
        if one_surface(ahead, behind) {
            sides = vec2<i32>(1, 1);
        } else if one_surface(ahead, side_depth(texel - 2 * d, slit)) {
            sides = vec2<i32>(1, 2);
        } else if one_surface(side_depth(texel + 2 * d, slit), behind) {
            sides = vec2<i32>(2, 1);
        } else {
            continue;
        }
        add_mean(&sums, texel + sides.x * d);
        add_mean(&sums, texel - sides.y * d);
        across += 1;
    }
    if across < GAP_MIN_DIRECTIONS {
        sums = Sums(vec4<f32>(0.0), vec4<f32>(0.0));
    }
    return sums;
}

// Pass 1's depth at a texel's centre; 0 (none) outside the target, and with
// `front_only` where no patch's front covers the texel's centre.
fn side_depth(texel: vec2<i32>, front_only: bool) -> f32 {
    if any(texel < vec2<i32>(0)) || any(texel >= vec2<i32>(textureDimensions(depth))) {
        return 0.0;
    }
    if front_only && !front_at_centre(textureLoad(coverage, texel, 0)) {
        return 0.0;
    }
    return textureLoad(depth, texel, 0).x;
}

// Whether two pass 1 depths are both of a surface, and within GAP_DEPTH_RATIO.
fn one_surface(a: f32, b: f32) -> bool {
    return min(a, b) > 0.0 && max(a, b) <= GAP_DEPTH_RATIO * min(a, b);
}

// Adds a texel's mean colour, normal and view distance (its sums over their weight) to
// `sums`, weight 1.
fn add_mean(sums: ptr<function, Sums>, texel: vec2<i32>) {
    let c = textureLoad(color_sum, texel, 0);
    if c.w <= 0.0 {
        return;
    }
    let nz = textureLoad(normal_sum, texel, 0);
    (*sums).c += vec4<f32>(c.rgb / c.w, 1.0);
    (*sums).nz += nz / c.w;
}
