//! WGSL modules with explicit imports. A file of `shaders/` names what it uses on lines
//! `#import NAME` at its top; [`compose`] returns the module's source preceded by those
//! of its imports (recursively, each once, imports first), the `#import` lines turned
//! into comments so that line numbers stay those of the file. Constants that Rust and
//! WGSL share are written once in Rust and given to WGSL as the module `constants`
//! ([`constants_wgsl`]).
//!
//! A preprocessor of this size, rather than `naga_oil`: our shaders import whole files
//! and need no name mangling, conditional compilation or per-item imports, and
//! `naga_oil` pins a `naga` version that must match wgpu's, which would hold back wgpu
//! upgrades. The test below parses and validates every composed module with naga, so a
//! broken shader fails `cargo test` without a GPU.

use super::settings::Mode;
use crate::surfel::clip::{NO_CLIP, WEDGE_ANGLE_BITS, WEDGE_MARGIN, WEDGE_TAG};
use crate::tree::instances::groups::GROUP;
use crate::tree::instances::lod::{STEPS, STEPS_PER_OCTAVE};

/// Threads per workgroup of the compute passes (`@workgroup_size(WORKGROUP_SIZE)`).
pub const WORKGROUP_SIZE: u32 = 256;

/// Threads per workgroup of the raster passes (`RASTER_WORKGROUP` in WGSL): the
/// workgroup that shares a large footprint's pixels.
pub const RASTER_WORKGROUP: u32 = 64;
/// Threads per workgroup of `cull_far` (cull.wgsl): one far instance's nodes.
pub const FAR_WORKGROUP: u32 = 64;
/// Workgroups a dispatch's x may count on any adapter (WebGPU's least
/// `maxComputeWorkgroupsPerDimension`): the GPU's own dispatches (cull.wgsl) stay
/// within it.
pub const MAX_GROUPS_X: u32 = 65535;
/// The per-pixel compute passes (the resolve, shading) run in workgroups of tiles of
/// this many pixels a side.
pub const PIXEL_TILE: u32 = 8;
/// Channels of the fixed-point sums (`SUM_*` in accumulate.wgsl).
pub const SUM_CHANNELS: u32 = 8;
/// Which pass a raster pipeline runs (WGSL override `RASTER_PASS`; its values are given
/// to WGSL as constants).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RasterPass {
    Visibility = 0,
    Attributes = 1,
    PointDepth = 2,
    PointWinner = 3,
    PointWrite = 4,
}

/// Every WGSL file of `shaders/`, by the name `#import` uses.
const FILES: &[(&str, &str)] = &[
    ("accumulate", include_str!("../../shaders/accumulate.wgsl")),
    ("common", include_str!("../../shaders/common.wgsl")),
    ("cull", include_str!("../../shaders/cull.wgsl")),
    ("ewa", include_str!("../../shaders/ewa.wgsl")),
    ("far", include_str!("../../shaders/far.wgsl")),
    ("fullscreen", include_str!("../../shaders/fullscreen.wgsl")),
    ("mesh", include_str!("../../shaders/mesh.wgsl")),
    ("place", include_str!("../../shaders/place.wgsl")),
    ("present", include_str!("../../shaders/present.wgsl")),
    ("raster", include_str!("../../shaders/raster.wgsl")),
    ("resolve", include_str!("../../shaders/resolve.wgsl")),
    ("shade", include_str!("../../shaders/shade.wgsl")),
    ("shape", include_str!("../../shaders/shape.wgsl")),
    ("splat", include_str!("../../shaders/splat.wgsl")),
    ("surrounded", include_str!("../../shaders/surrounded.wgsl")),
];

/// Which splats a pipeline draws (the WGSL override `SPLAT_CLASS`; its values are
/// given to WGSL as constants).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SplatClass {
    All = 0,
    /// Those whose rim may lie on an outline (`on_outline` in `shaders/shape.wgsl`).
    Outline = 1,
    Inner = 2,
}

/// How far beyond a splat's patch its quad reaches (the WGSL override `QUAD_REACH`; its
/// values are given to WGSL as constants).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum QuadReach {
    /// Fragments whose centre the patch covers.
    Patch = 0,
    /// And those whose coverage samples it covers.
    Samples = 1,
    /// And the prefilter's band.
    Band = 2,
}

/// Where a splat's colour comes from (the WGSL override `COLOR_SOURCE`; its values are
/// given to WGSL as constants).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ColorSource {
    /// The node's own colour (grey without colours).
    Node = 0,
    Levels = 1,
    Radius = 2,
    Elevation = 3,
    /// The node's LiDAR attributes, as `frame.mode` picks.
    Attributes = 4,
}

impl ColorSource {
    pub const COUNT: usize = 5;

    pub fn of(mode: Mode) -> ColorSource {
        match mode {
            Mode::Levels => ColorSource::Levels,
            Mode::Radius => ColorSource::Radius,
            Mode::Elevation => ColorSource::Elevation,
            Mode::Classification | Mode::Intensity | Mode::Returns => ColorSource::Attributes,
            Mode::Shaded | Mode::Normals | Mode::Points | Mode::Mesh | Mode::Edl => {
                ColorSource::Node
            }
        }
    }
}

/// The WGSL of the shared constants, generated from their Rust definitions.
pub fn constants_wgsl() -> String {
    let mut out = format!(
        "// Generated from Rust (src/render/shaders.rs): constants shared with the CPU.\n\
         const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\n\
         const RASTER_WORKGROUP: u32 = {RASTER_WORKGROUP}u;\n\
         const PIXEL_TILE: u32 = {PIXEL_TILE}u;\n\
         const SUM_CHANNELS: u32 = {SUM_CHANNELS}u;\n\
         const WEDGE_MARGIN: f32 = {WEDGE_MARGIN:?};\n\
         const WEDGE_ANGLE_BITS: u32 = {WEDGE_ANGLE_BITS}u;\n\
         const WEDGE_TAG: u32 = {WEDGE_TAG}u;\n\
         const NO_CLIP: u32 = {NO_CLIP}u;\n\
         const FAR_WORKGROUP: u32 = {FAR_WORKGROUP}u;\n\
         const MAX_GROUPS_X: u32 = {MAX_GROUPS_X}u;\n\
         const GROUP: u32 = {GROUP}u;\n\
         const STEPS: i32 = {STEPS}i;\n\
         const STEPS_PER_OCTAVE: f32 = {STEPS_PER_OCTAVE:?};\n"
    );
    let values = [
        ("ALL_SPLATS", SplatClass::All as u32),
        ("OUTLINE_SPLATS", SplatClass::Outline as u32),
        ("INNER_SPLATS", SplatClass::Inner as u32),
        ("REACH_PATCH", QuadReach::Patch as u32),
        ("REACH_SAMPLES", QuadReach::Samples as u32),
        ("REACH_BAND", QuadReach::Band as u32),
        ("COLOR_NODE", ColorSource::Node as u32),
        ("COLOR_LEVELS", ColorSource::Levels as u32),
        ("COLOR_RADIUS", ColorSource::Radius as u32),
        ("COLOR_ELEVATION", ColorSource::Elevation as u32),
        ("COLOR_ATTRIBUTES", ColorSource::Attributes as u32),
        ("RASTER_VISIBILITY", RasterPass::Visibility as u32),
        ("RASTER_ATTRIBUTES", RasterPass::Attributes as u32),
        ("RASTER_POINT_DEPTH", RasterPass::PointDepth as u32),
        ("RASTER_POINT_WINNER", RasterPass::PointWinner as u32),
        ("RASTER_POINT_WRITE", RasterPass::PointWrite as u32),
    ];
    for (name, value) in values {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    out.push_str(&Mode::wgsl_constants());
    out
}

fn source(name: &str) -> Option<String> {
    if name == "constants" {
        return Some(constants_wgsl());
    }
    FILES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, s)| s.to_string())
}

/// The names a module imports, in order.
fn imports_of(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("#import "))
        .map(str::trim)
}

fn add(name: &str, done: &mut Vec<String>, out: &mut String) {
    if done.iter().any(|d| d == name) {
        return;
    }
    done.push(name.to_owned());
    let text = source(name).unwrap_or_else(|| panic!("no WGSL module named '{name}'"));
    for dep in imports_of(&text) {
        add(dep, done, out);
    }
    for line in text.lines() {
        match line.trim().strip_prefix("#import ") {
            Some(dep) => out.push_str(&format!("// (imported above: {dep})\n")),
            None => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
}

/// The full source of module `name`: its imports first, then itself.
pub fn compose(name: &str) -> String {
    let mut out = String::new();
    add(name, &mut Vec::new(), &mut out);
    out
}

/// The attribute by which a fragment shader that writes its depth promises to write
/// none nearer than its quad's (reversed-Z: no greater), so that the GPU may test the
/// quad's depth before running it. Needs `Features::SHADER_EARLY_DEPTH_TEST`.
pub const CONSERVATIVE_DEPTH: &str = "@early_depth_test(less_equal)";

/// `source` for a device with the `features` given: without early depth tests, the
/// [`CONSERVATIVE_DEPTH`] attributes are left out (the shaders are correct either way).
fn for_features(source: String, features: wgpu::Features) -> String {
    match features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST) {
        true => source,
        false => source.replace(CONSERVATIVE_DEPTH, ""),
    }
}

/// The shader module `name`, composed, on `device`.
pub fn module(device: &wgpu::Device, name: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(for_features(compose(name), device.features()).into()),
    })
}

/// Asserts that `T` has the size WGSL gives struct `name` in module `module`'s
/// composition: for the tests of the Rust Pod types that mirror WGSL structs.
#[cfg(test)]
pub(super) fn assert_wgsl_size<T>(module: &str, name: &str) {
    let m = naga::front::wgsl::parse_str(&compose(module)).expect("parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(m.to_ctx()).expect("lays out");
    let (handle, _) = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in {module}"));
    let wgsl = layouter[handle].size as usize;
    assert_eq!(wgsl, std::mem::size_of::<T>(), "{name}: WGSL {wgsl} bytes");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The modules that pipelines are made of (the others are only imported).
    const ENTRY_MODULES: &[&str] = &[
        "cull", "mesh", "present", "raster", "resolve", "shade", "splat",
    ];

    /// Parses and validates `source` as naga does inside wgpu on a device with the
    /// optional `features` given and full downlevel support (wgpu-naga-bridge's
    /// mapping: `SHADER_F16_IN_F32` always, for `unpack2x16float`).
    fn validate(name: &str, source: &str, features: wgpu::Features) -> Result<(), String> {
        let source = for_features(source.to_owned(), features);
        let module = naga::front::wgsl::parse_str(&source)
            .map_err(|e| format!("{name}: {}", e.emit_to_string(&source)))?;
        let mut capabilities = naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32;
        if features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST) {
            capabilities |= naga::valid::Capabilities::EARLY_DEPTH_TEST;
        }
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
            .validate(&module)
            .map_err(|e| format!("{name}: {}", e.emit_to_string(&source)))?;
        Ok(())
    }

    /// Every module validates on a device with early depth tests and on one without.
    #[test]
    fn every_shader_module_parses_and_validates() {
        for features in [
            wgpu::Features::empty(),
            wgpu::Features::SHADER_EARLY_DEPTH_TEST,
        ] {
            for name in ENTRY_MODULES {
                validate(name, &compose(name), features).unwrap_or_else(|e| panic!("{e}"));
            }
        }
    }

    #[test]
    fn conservative_depth_needs_the_feature() {
        let splat = compose("splat");
        assert!(splat.contains(CONSERVATIVE_DEPTH));
        let no_feature = naga::front::wgsl::parse_str(&splat).expect("parses");
        let without = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32,
        )
        .validate(&no_feature);
        assert!(without.is_err(), "the attribute needs EARLY_DEPTH_TEST");
    }

    #[test]
    fn imports_come_first_and_once() {
        let splat = compose("splat");
        let common = splat.find("struct Frame").expect("common imported");
        let own = splat.find("fn vs_splat").expect("splat itself");
        assert!(common < own);
        assert_eq!(splat.matches("struct Frame").count(), 1);
        assert!(compose("cull").contains(&format!("WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u")));
    }

    #[test]
    fn a_broken_shader_is_caught() {
        let broken = compose("cull").replace("atomicAdd", "atomic_add_misspelled");
        assert!(validate("broken cull", &broken, wgpu::Features::empty()).is_err());
    }
}
