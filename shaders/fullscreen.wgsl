// One triangle that covers the whole target (three vertices, no buffers), for the
// full-screen passes: shading (shade.wgsl) and presentation (present.wgsl).

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}
