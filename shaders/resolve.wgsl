#import accumulate
#import common
#import constants

// The compute rasterizer's last step, one thread per pixel: its fixed-point sums
// (accumulate.wgsl) become the G-buffer that pass 3 reads, and the buffers are cleared
// for the next frame. The sums are written already divided by their weight, (colour,
// 1) and (normal, view distance), which pass 3's divisions leave as they are; pass 1's
// depth as a float texture.

@group(1) @binding(0) var color_out: texture_storage_2d<rgba16float, write>;
@group(1) @binding(1) var normal_out: texture_storage_2d<rgba16float, write>;
@group(1) @binding(2) var coverage_out: texture_storage_2d<rgba8unorm, write>;
@group(1) @binding(3) var depth_out: texture_storage_2d<r32float, write>;
@group(2) @binding(0) var<storage, read_write> visible: array<u32>;
@group(2) @binding(1) var<storage, read_write> sums: array<u32>;
@group(2) @binding(2) var<storage, read_write> carries: array<u32>;
@group(2) @binding(3) var<storage, read_write> covered: array<u32>;
@group(2) @binding(4) var<storage, read_write> nearest_point: array<u32>;

// The sum of channel `c` at pixel `p`, as a float (FIXED_ONE = 1).
fn sum_at(c: u32, p: u32) -> f32 {
    let i = c * pixel_count() + p;
    return (f32(carries[i]) * 4294967296.0 + f32(sums[i])) / FIXED_ONE;
}

@compute @workgroup_size(PIXEL_TILE, PIXEL_TILE)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let p = id.y * size.x + id.x;
    let texel = vec2<i32>(id.xy);
    let held = bitcast<f32>(visible[p]);
    let w = sum_at(SUM_WEIGHT, p);
    var color = vec4<f32>(0.0);
    var normal = vec4<f32>(0.0);
    if w > 0.0 {
        let c = vec3<f32>(sum_at(SUM_COLOR, p), sum_at(SUM_COLOR + 1u, p), sum_at(SUM_COLOR + 2u, p));
        let n = vec3<f32>(sum_at(SUM_NORMAL, p), sum_at(SUM_NORMAL + 1u, p), sum_at(SUM_NORMAL + 2u, p));
        // Pass 1's view distance z₁ = near / depth; the sum holds (z / z₁)·w.
        let z = sum_at(SUM_DEPTH, p) / w * frame.near / max(held, 1e-30);
        color = vec4<f32>(c / w, 1.0);
        normal = vec4<f32>(n / w - 1.0, z);
    }
    textureStore(color_out, texel, color);
    textureStore(normal_out, texel, normal);
    textureStore(coverage_out, texel, coverage_of(covered[p]));
    textureStore(depth_out, texel, vec4<f32>(held, 0.0, 0.0, 0.0));
    clear(p);
}

// The coverage samples of accumulate.wgsl's bits: 1, OFF_FRONT_COVERAGE or 0 each.
fn coverage_of(bits: u32) -> vec4<f32> {
    var out = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let sample = (bits >> (2u * k)) & 3u;
        out[k] = select(select(0.0, OFF_FRONT_COVERAGE, sample != 0u), 1.0, sample == 3u);
    }
    return out;
}

// Every buffer of pixel p back to its state before a frame.
fn clear(p: u32) {
    visible[p] = 0u;
    covered[p] = 0u;
    nearest_point[p] = 0u;
    let n = pixel_count();
    for (var c = 0u; c < SUM_CHANNELS; c++) {
        sums[c * n + p] = 0u;
        carries[c * n + p] = 0u;
    }
}
