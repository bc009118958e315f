#import accumulate
#import common
#import constants
#import ewa
#import shape
#import surrounded

// The splat passes as compute rasterization, over the survivors that cull.wgsl
// compacted: one dispatch per slice and kind of splat (SPLAT_CLASS), each pass
// (RASTER_PASS) writing accumulate.wgsl's buffers with atomics, the fragments being
// ewa.wgsl's, as in the raster pipeline:
//
//   visibility    atomicMax of the pushed-back depth (reversed Z: the nearest)
//   attributes    fragments no farther than pass 1's depth add their weighted sums
//                 (fixed point) and OR their coverage
//   point depth   atomicMax of each point's depth
//   point winner  among the points at that depth, the first of the list (atomicMax of
//                 its complemented index)
//   point write   the winner stores its attributes
//
// Thread t of a dispatch places survivor t; its workgroup then draws the pixels of its
// splats together (see `raster`).

@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read> survivors: array<u32>;
@group(1) @binding(2) var<storage, read> shapes: array<SplatShape>;
@group(1) @binding(3) var<storage, read> attributes: array<u32>;
@group(1) @binding(4) var<storage, read> compaction: Survivors;
@group(1) @binding(5) var<storage, read> placements: array<Placement>;
@group(1) @binding(6) var<storage, read> survivor_placements: array<u32>;
@group(2) @binding(0) var<storage, read_write> visible: array<atomic<u32>>;
@group(2) @binding(1) var<storage, read_write> sums: array<atomic<u32>>;
@group(2) @binding(2) var<storage, read_write> carries: array<atomic<u32>>;
@group(2) @binding(3) var<storage, read_write> covered: array<atomic<u32>>;
@group(2) @binding(4) var<storage, read_write> nearest_point: array<atomic<u32>>;

// cull.wgsl's `Compaction`, read: the survivors of each kind and the slice's first node.
struct Survivors {
    outline_vertices: u32,
    outline: u32,
    outline_first_vertex: u32,
    outline_first_instance: u32,
    inner_vertices: u32,
    inner: u32,
    inner_first_vertex: u32,
    inner_first_instance: u32,
    count: u32,
    range_count: u32,
    first: u32,
}

// Which pass a pipeline runs (RASTER_* from Rust: src/render/raster.rs).
override RASTER_PASS: u32 = RASTER_VISIBILITY;

// The workgroup's splats: each thread places one, then the workgroup draws the pixels
// of all of them, thread i taking pixels i, i + RASTER_WORKGROUP, … of their boxes laid
// end to end (`ends`: the running total of their pixel counts). Neighbouring threads
// thus draw neighbouring pixels of one splat, whatever the sizes of the footprints: no
// thread walks a close-up splat's thousands of pixels alone, and none idles beside it.
var<workgroup> placed_splats: array<SplatVarying, RASTER_WORKGROUP>;
var<workgroup> boxes: array<vec4<i32>, RASTER_WORKGROUP>;
var<workgroup> placed_nodes: array<u32, RASTER_WORKGROUP>;
var<workgroup> ends: array<u32, RASTER_WORKGROUP>;
var<workgroup> total_pixels: u32;

// The survivors of this dispatch's kind; survivor t (outline splats from the list's
// end backwards, the others from its start).
fn survivor_count() -> u32 {
    return select(compaction.inner, compaction.outline, SPLAT_CLASS == OUTLINE_SPLATS);
}

// Survivor t: its node, and its placement (cull.wgsl's `keep`).
fn survivor(t: u32) -> vec2<u32> {
    let slot = select(t, arrayLength(&survivors) - 1u - t, SPLAT_CLASS == OUTLINE_SPLATS);
    return vec2<u32>(survivors[slot], survivor_placements[min(slot, arrayLength(&survivor_placements) - 1u)]);
}

// The pixels whose centres lie in a placed box (NDC lo, hi): the first pixel, and the
// box's width and height in pixels (0 when it holds none).
fn pixel_box(lo: vec2<f32>, hi: vec2<f32>) -> vec4<i32> {
    let size = frame.viewport;
    let top_left = vec2<f32>(lo.x * 0.5 + 0.5, 0.5 - hi.y * 0.5) * size;
    let bottom_right = vec2<f32>(hi.x * 0.5 + 0.5, 0.5 - lo.y * 0.5) * size;
    let first = vec2<i32>(ceil(clamp(top_left, vec2<f32>(0.0), size + 1.0) - 0.5));
    let end = vec2<i32>(ceil(clamp(bottom_right, vec2<f32>(0.0), size + 1.0) - 0.5));
    let start = max(first, vec2<i32>(0));
    return vec4<i32>(start, max(min(end, vec2<i32>(size)) - start, vec2<i32>(0)));
}

@compute @workgroup_size(RASTER_WORKGROUP)
fn raster(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let t = (group.y * groups.x + group.x) * RASTER_WORKGROUP + lane;
    var box = vec4<i32>(0);
    if t < survivor_count() {
        let kept = survivor(t);
        let node = kept.x;
        let placed = place_splat(node, kept.y, false);
        if placed.drawn {
            box = pixel_box(placed.lo, placed.hi);
        }
        placed_splats[lane] = placed.splat;
        placed_nodes[lane] = node;
    }
    boxes[lane] = box;
    ends[lane] = u32(box.z) * u32(box.w);
    // Running totals, by one thread: a parallel scan's barriers cost a CPU adapter
    // (which runs a workgroup's threads as coroutines that switch at each barrier)
    // more than the 64 adds.
    workgroupBarrier();
    if lane == 0u {
        var sum = 0u;
        for (var k = 0u; k < RASTER_WORKGROUP; k++) {
            sum += ends[k];
            ends[k] = sum;
        }
        total_pixels = sum;
    }
    let total = workgroupUniformLoad(&total_pixels);
    for (var i = lane; i < total; i += RASTER_WORKGROUP) {
        // The splat whose pixels hold i: the first whose running total exceeds it.
        var lo = 0u;
        var hi = RASTER_WORKGROUP - 1u;
        while lo < hi {
            let mid = (lo + hi) / 2u;
            if ends[mid] > i {
                hi = mid;
            } else {
                lo = mid + 1u;
            }
        }
        let j = i - select(0u, ends[max(lo, 1u) - 1u], lo > 0u);
        let b = boxes[lo];
        let width = u32(b.z);
        draw_pixel(placed_splats[lo], placed_nodes[lo], b.xy + vec2<i32>(i32(j % width), i32(j / width)));
    }
}

// Whether pass 1 found a surface at the centre of a pixel and of its four neighbours
// (ewa.wgsl's `pixel_coverage`; surrounded.wgsl's test on the buffer).
fn surrounded_at(texel: vec2<i32>) -> bool {
    let last = vec2<i32>(frame.viewport) - 1;
    for (var k = 0; k < 5; k++) {
        let t = clamp(texel + CROSS[k], vec2<i32>(0), last);
        if atomicLoad(&visible[u32(t.y) * u32(frame.viewport.x) + u32(t.x)]) == 0u {
            return false;
        }
    }
    return true;
}

// What this pass does with splat `s` (slice node `node`) at `pixel`. Each pass first
// rejects the pixel where the splat's nearest depth (its quad's) is farther than what
// the pixel holds, as the raster pipeline's early depth test does.
fn draw_pixel(s: SplatVarying, node: u32, pixel: vec2<i32>) {
    var at = s;
    at.clip = vec4<f32>(vec2<f32>(pixel) + 0.5, s.clip.zw);
    let p = u32(pixel.y) * u32(frame.viewport.x) + u32(pixel.x);
    let held = atomicLoad(&visible[p]);
    if s.clip.z < bitcast<f32>(held) {
        return;
    }
    switch RASTER_PASS {
        case RASTER_VISIBILITY: {
            // Only a nearer depth than the pixel holds (held ≥ 0): a farther one's
            // atomicMax would change nothing, and saves its trip to memory.
            let depth = visibility_depth(at);
            if depth > bitcast<f32>(held) {
                atomicMax(&visible[p], bitcast<u32>(depth));
            }
        }
        case RASTER_ATTRIBUTES: {
            var f: Fragment;
            if SPLAT_CLASS == OUTLINE_SPLATS {
                f = outline_fragment(at);
            } else {
                f = inner_fragment(at);
            }
            if f.kept && f.depth >= bitcast<f32>(held) {
                accumulate(p, f, bitcast<f32>(held));
            }
        }
        case RASTER_POINT_DEPTH: {
            let f = point_fragment(at);
            if f.kept {
                atomicMax(&visible[p], bitcast<u32>(f.depth));
            }
        }
        case RASTER_POINT_WINNER: {
            let f = point_fragment(at);
            if f.kept && bitcast<u32>(f.depth) == held {
                atomicMax(&nearest_point[p], ~(compaction.first + node));
            }
        }
        default: {
            let f = point_fragment(at);
            if f.kept && bitcast<u32>(f.depth) == held
                && atomicLoad(&nearest_point[p]) == ~(compaction.first + node) {
                write_point(p, f);
            }
        }
    }
}

// Adds `value` (0 to 2) to channel `c` of pixel `p`, in fixed point, carrying into the
// high word when the low one wraps.
fn add_fixed(c: u32, p: u32, value: f32) {
    let q = u32(round(clamp(value, 0.0, 2.0) * FIXED_ONE));
    if q == 0u {
        return;
    }
    let i = c * pixel_count() + p;
    let before = atomicAdd(&sums[i], q);
    if before > 0xffffffffu - q {
        atomicAdd(&carries[i], 1u);
    }
}

// A pass 2 fragment's sums (accumulate.wgsl's channels), against pass 1's depth `held`.
fn accumulate(p: u32, f: Fragment, held: f32) {
    let w = f.color.w;
    add_fixed(SUM_COLOR, p, f.color.r);
    add_fixed(SUM_COLOR + 1u, p, f.color.g);
    add_fixed(SUM_COLOR + 2u, p, f.color.b);
    add_fixed(SUM_WEIGHT, p, w);
    add_fixed(SUM_NORMAL, p, f.normal.x + w);
    add_fixed(SUM_NORMAL + 1u, p, f.normal.y + w);
    add_fixed(SUM_NORMAL + 2u, p, f.normal.z + w);
    // The fragment's reversed-Z depth is near / z, pass 1's near / z₁: z / z₁ = held / depth.
    add_fixed(SUM_DEPTH, p, held / f.depth * w);
    let bits = coverage_bits(f.coverage);
    if bits != 0u {
        atomicOr(&covered[p], bits);
    }
}

// accumulate.wgsl's two bits per coverage sample: 3 for 1, 1 for less, 0 for none.
fn coverage_bits(c: vec4<f32>) -> u32 {
    var bits = 0u;
    for (var k = 0u; k < 4u; k++) {
        let sample = select(select(0u, 1u, c[k] > 0.0), 3u, c[k] >= 1.0);
        bits |= sample << (2u * k);
    }
    return bits;
}

// The winning point's attributes, stored as one fragment of weight 1 at pass 1's depth.
fn write_point(p: u32, f: Fragment) {
    let n = pixel_count();
    let one = u32(FIXED_ONE);
    atomicStore(&sums[SUM_COLOR * n + p], u32(round(f.color.r * FIXED_ONE)));
    atomicStore(&sums[(SUM_COLOR + 1u) * n + p], u32(round(f.color.g * FIXED_ONE)));
    atomicStore(&sums[(SUM_COLOR + 2u) * n + p], u32(round(f.color.b * FIXED_ONE)));
    atomicStore(&sums[SUM_WEIGHT * n + p], one);
    atomicStore(&sums[SUM_NORMAL * n + p], u32(round((f.normal.x + 1.0) * FIXED_ONE)));
    atomicStore(&sums[(SUM_NORMAL + 1u) * n + p], u32(round((f.normal.y + 1.0) * FIXED_ONE)));
    atomicStore(&sums[(SUM_NORMAL + 2u) * n + p], u32(round((f.normal.z + 1.0) * FIXED_ONE)));
    atomicStore(&sums[SUM_DEPTH * n + p], one);
    atomicStore(&covered[p], 0xffu);
}
