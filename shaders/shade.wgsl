#import common
#import fullscreen

// Pass 3: normalize the blended attributes and shade each pixel (Blinn-Phong with a
// movable light); background where no splat contributed. Writes an sRGB target.

@group(1) @binding(0) var color_sum: texture_2d<f32>;
@group(1) @binding(1) var normal_sum: texture_2d<f32>;
// The four coverage samples of each pixel (max over the splats drawn there).
@group(1) @binding(2) var coverage: texture_2d<f32>;
// The depth of the nearest surface at the pixel centre (reversed Z; 0: none).
@group(1) @binding(3) var depth: texture_depth_2d;

// The pixel and its four neighbours.
const CROSS = array<vec2<i32>, 5>(vec2<i32>(0, 0), vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1));

// Whether a surface covers the centre of the pixel and of its four neighbours: then the
// pixel shows no background, whatever the coverage samples that passed the depth test
// say (beside an occluding edge, the hidden surface's samples failed it).
fn surrounded(texel: vec2<i32>) -> bool {
    let last = vec2<i32>(textureDimensions(depth)) - 1;
    for (var k = 0; k < 5; k++) {
        if textureLoad(depth, clamp(texel + CROSS[k], vec2<i32>(0), last), 0) <= 0.0 {
            return false;
        }
    }
    return true;
}

@fragment
fn fs_shade(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(frag.xy);
    let c = textureLoad(color_sum, texel, 0);
    let nz = textureLoad(normal_sum, texel, 0);
    if c.w <= 0.0 {
        return vec4<f32>(frame.background.rgb, 1.0);
    }
    let color = c.rgb / c.w;
    let n = normalize(nz.xyz);
    if frame.mode == MODE_NORMALS {
        return vec4<f32>(n * 0.5 + 0.5, 1.0);
    }
    if frame.mode == MODE_EDL {
        return vec4<f32>(mix(frame.background.rgb, color * eye_dome(texel), coverage_alpha(texel, c.w)), 1.0);
    }
    let q = view_ray(frag.xy) * (nz.w / c.w);
    let l = normalize(frame.light_dir);
    let v = normalize(-q);
    let h = normalize(l + v);
    let diffuse = max(dot(n, l), 0.0);
    let specular = frame.specular * pow(max(dot(n, h), 0.0), 32.0) * select(0.0, 1.0, diffuse > 0.0);
    let shaded = color * (0.25 + 0.75 * diffuse) + vec3<f32>(specular);
    return vec4<f32>(mix(frame.background.rgb, shaded, coverage_alpha(texel, c.w)), 1.0);
}

// The share of the pixel's samples that the splats cover (all of it where the pixel
// and its neighbours show a surface at their centres); pixels reached only by the
// fading rims of splats (total weight `w`) also blend into the background when
// coverage_weight is set.
fn coverage_alpha(texel: vec2<i32>, w: f32) -> f32 {
    var alpha = select(dot(textureLoad(coverage, texel, 0), vec4<f32>(0.25)), 1.0, surrounded(texel));
    if frame.coverage_weight > 0.0 {
        alpha = min(alpha, clamp(w / frame.coverage_weight, 0.0, 1.0));
    }
    return alpha;
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
    let here = textureLoad(depth, texel, 0);
    if here <= 0.0 {
        return 1.0;
    }
    let last = vec2<i32>(textureDimensions(depth)) - 1;
    var sum = 0.0;
    for (var k = 0; k < 8; k++) {
        let offset = vec2<i32>(round(frame.edl_radius_px * EDL_DIRECTIONS[k]));
        let there = textureLoad(depth, clamp(texel + offset, vec2<i32>(0), last), 0);
        if there > 0.0 {
            sum += max(0.0, log2(there) - log2(here));
        }
    }
    return exp(-300.0 * frame.edl_strength * sum / 8.0);
}
