// When a pixel's coverage samples matter: shared by pass 2, which skips them where they
// do not, and pass 3, which reads them only where they do.

// The pixel and its four neighbours.
const CROSS = array<vec2<i32>, 5>(vec2<i32>(0, 0), vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1));

// Whether a surface covers the centre of the pixel and of its four neighbours, in pass
// 1's `depth` (reversed Z; 0: none). Then the pixel shows no background, whatever its
// coverage samples say (beside an occluding edge, the hidden surface's samples failed
// the depth test): pass 3 takes it as covered, so pass 2 need not sample its coverage.
fn surrounded(depth: texture_2d<f32>, texel: vec2<i32>) -> bool {
    let last = vec2<i32>(textureDimensions(depth)) - 1;
    for (var k = 0; k < 5; k++) {
        if textureLoad(depth, clamp(texel + CROSS[k], vec2<i32>(0), last), 0).x <= 0.0 {
            return false;
        }
    }
    return true;
}
