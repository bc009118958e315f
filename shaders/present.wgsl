#import fullscreen

// Presentation: copies the finished frame (scene and panel, already sRGB-encoded) to
// the window's surface texel for texel, so the window shows the bytes a screenshot
// saves.

@group(0) @binding(0) var finished: texture_2d<f32>;

@fragment
fn fs_present(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(finished, vec2<i32>(frag.xy), 0);
}
