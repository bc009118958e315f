//! How faithfully a face-less cloud's splats draw what was scanned: against
//! a triangulation of the same points that needs no normals ([`crate::io::triangulate`]),
//! rendered by the mesh pass at 4×4 the size and averaged in linear light. Per orbit view
//! (elevation 20°): FLIP and SSIM of the splats (leaves only) over the pixels either
//! image covers, FLIP of the triangulation itself at 1×, and the hole rate of the splats
//! against the triangulation at 1× (its covered pixels the splats leave empty).

use std::path::Path;

use anyhow::Context;

use crate::eval::metrics::compare;
use crate::eval::perceptual::{downsample, flip_mean, ssim_mean};
use crate::io::Geometry;
use crate::io::formats::read_model;
use crate::io::triangulate::{sensor_grid, terrain};
use crate::render::{Camera, Image, OrbitAxes, Renderer, Settings};
use crate::surfel::leaf_surfels;
use crate::tree::scene::Scene;

/// How a cloud is triangulated for its reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Triangulation {
    /// An organised cloud on a sensor grid of this many pixels (an RGB-D frame).
    Grid { width: u32, height: u32 },
    /// A height field (an airborne tile): 2.5D Delaunay.
    Terrain,
}

/// The reference's supersampling factor per axis.
pub const SUPERSAMPLE: u32 = 4;

/// A cloud read from `path` (faces, if any, dropped) and the same points triangulated;
/// for a sensor frame, also the same triangles over the points moved within their
/// depth step ([`requantize`]).
pub struct CloudAndReference {
    pub cloud: Scene,
    pub reference: Scene,
    pub requantized: Option<Scene>,
    /// The same triangles shaded with the cloud's own estimated normals (the leaf
    /// surfels' normals), when opened [`CloudAndReference::with_bounds`].
    pub cloud_normals: Option<Scene>,
}

impl CloudAndReference {
    /// The cloud, its triangulation and, for a sensor frame, the requantized one.
    pub fn open(path: &Path, triangulation: Triangulation) -> anyhow::Result<Self> {
        Self::build(path, triangulation, false)
    }

    /// As [`CloudAndReference::open`], with the scene that separates the normals'
    /// share of the splats' error from the rest ([`ViewFigures::cloud_normals_flip`]).
    pub fn with_bounds(path: &Path, triangulation: Triangulation) -> anyhow::Result<Self> {
        Self::build(path, triangulation, true)
    }

    fn build(path: &Path, triangulation: Triangulation, bounds: bool) -> anyhow::Result<Self> {
        let meshed = triangulated(path, triangulation)?;
        let mut geometry = meshed.clone();
        geometry.triangles.clear();
        let requantized = matches!(triangulation, Triangulation::Grid { .. }).then(|| {
            let mut moved = meshed.clone();
            requantize(&mut moved);
            Scene::from_geometry(moved)
        });
        let cloud_normals = bounds.then(|| {
            let mut shaded = meshed.clone();
            shaded.normals = Some(
                leaf_surfels(&geometry)
                    .surfels
                    .iter()
                    .map(|s| s.normal)
                    .collect(),
            );
            Scene::from_geometry(shaded)
        });
        Ok(CloudAndReference {
            cloud: Scene::from_geometry(geometry),
            reference: Scene::from_geometry(meshed),
            requantized,
            cloud_normals,
        })
    }
}

/// The cloud read from `path` (faces, if any, dropped), triangulated.
pub fn triangulated(path: &Path, triangulation: Triangulation) -> anyhow::Result<Geometry> {
    let mut geometry: Geometry = read_model(path)?.drawable(path)?.geometry;
    geometry.triangles = match triangulation {
        Triangulation::Grid { width, height } => sensor_grid(&geometry, width, height)
            .map_err(anyhow::Error::msg)
            .with_context(|| format!("{}: not a sensor grid", path.display()))?,
        Triangulation::Terrain => terrain(&geometry),
    };
    Ok(geometry)
}

/// Moves each point of a sensor frame along its ray (toward the file's origin, where
/// the sensor is) to a depth drawn uniformly within ±½ of the depth step there (the gap
/// between consecutive distinct depths z the file holds; RGB-D sensors quantise depth):
/// a surface as faithful to the scan as the stored one, within what the sensor
/// resolves. Deterministic (a fixed xorshift sequence).
pub fn requantize(g: &mut Geometry) {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let depth = |p: &glam::Vec3| g.origin.z + p.z as f64;
    let mut depths: Vec<f64> = g.positions.iter().map(depth).collect();
    depths.sort_by(f64::total_cmp);
    depths.dedup();
    let step = |z: f64| {
        let i = depths.partition_point(|d| *d < z);
        match (i.checked_sub(1).map(|k| depths[k]), depths.get(i + 1)) {
            (_, Some(next)) => next - depths[i.min(depths.len() - 1)],
            (Some(prev), None) => z - prev,
            (None, None) => 0.0,
        }
    };
    let origin = g.origin;
    for p in g.positions.iter_mut() {
        let z = origin.z + p.z as f64;
        if z == 0.0 {
            continue;
        }
        let scale = (z + uniform() * step(z)) / z;
        *p = ((origin + p.as_dvec3()) * scale - origin).as_vec3();
    }
}

/// The figures of one view.
#[derive(Debug, Clone, Copy)]
pub struct ViewFigures {
    pub splat_flip: f64,
    pub splat_ssim: f64,
    /// The triangulation at 1× against itself supersampled: the aliasing floor.
    pub mesh_flip: f64,
    /// The requantized triangulation at 1× against the reference (sensor frames).
    pub requantized_flip: Option<f64>,
    /// The triangulation's own splats (the mesh pipeline: one-ring ellipses, normal
    /// fields, clips) against the reference: what the splats score where the
    /// reference's triangles themselves are known ([`CloudAndReference::with_bounds`]).
    pub mesh_splat_flip: Option<f64>,
    /// The triangulation at 1× shaded with the cloud's estimated normals against the
    /// reference: the share of the splats' error that their normals alone make.
    pub cloud_normals_flip: Option<f64>,
    /// The triangulation's own splats against the cloud's splats: how alike the same
    /// samples draw as a mesh and as a cloud.
    pub mesh_splats_against_cloud: Option<f64>,
    pub hole_rate: f64,
}

/// The images of one view: the splats, the triangulation at 1× and the reference.
pub struct ViewImages {
    pub splats: Image,
    pub mesh: Image,
    pub reference: Image,
}

/// Renders `views` orbit views (azimuth every 360°/views, elevation 20°, `distance`
/// bounding-sphere radii, `size`²) of the cloud's splats drawn with `settings`, and
/// measures them; `keep` is given each view's images.
pub fn measure(
    renderer: &Renderer,
    models: &CloudAndReference,
    (views, distance, size): (u32, f64, u32),
    settings: &Settings,
    keep: &mut dyn FnMut(u32, &ViewImages),
) -> anyhow::Result<Vec<ViewFigures>> {
    let cloud_gpu = renderer.upload(&models.cloud);
    let mesh_gpu = renderer.upload(&models.reference);
    let requantized_gpu = models.requantized.as_ref().map(|s| (s, renderer.upload(s)));
    let cloud_normals_gpu = models
        .cloud_normals
        .as_ref()
        .map(|s| (s, renderer.upload(s)));
    let fov = 45f64.to_radians();
    let mut out = Vec::new();
    for k in 0..views {
        let azimuth = 360.0 * k as f64 / views as f64;
        // About z, as docs/point-clouds.md measures them (a sensor frame's own axes would look
        // from its sensor).
        let orbit = [azimuth, 20.0, distance];
        let camera = Camera::orbit_about(OrbitAxes::Z_UP, models.cloud.meta(), orbit, fov);
        let mesh = |s: u32| {
            renderer.render(
                &models.reference,
                &mesh_gpu,
                &camera,
                &Settings::mesh(),
                s,
                s,
            )
        };
        let images = ViewImages {
            splats: renderer
                .render(&models.cloud, &cloud_gpu, &camera, settings, size, size)?
                .0,
            mesh: mesh(size)?.0,
            reference: downsample(&mesh(size * SUPERSAMPLE)?.0, SUPERSAMPLE),
        };
        let requantized_flip = match &requantized_gpu {
            Some((scene, gpu)) => {
                let mesh = renderer.render(scene, gpu, &camera, &Settings::mesh(), size, size)?;
                Some(flip_mean(&mesh.0, &images.reference))
            }
            None => None,
        };
        let (mesh_splat_flip, cloud_normals_flip, mesh_splats_against_cloud) =
            match &cloud_normals_gpu {
                Some((scene, gpu)) => {
                    let splats = renderer.render(
                        &models.reference,
                        &mesh_gpu,
                        &camera,
                        settings,
                        size,
                        size,
                    )?;
                    let shaded =
                        renderer.render(scene, gpu, &camera, &Settings::mesh(), size, size)?;
                    (
                        Some(flip_mean(&splats.0, &images.reference)),
                        Some(flip_mean(&shaded.0, &images.reference)),
                        Some(flip_mean(&splats.0, &images.splats)),
                    )
                }
                None => (None, None, None),
            };
        out.push(ViewFigures {
            mesh_splat_flip,
            cloud_normals_flip,
            mesh_splats_against_cloud,
            splat_flip: flip_mean(&images.splats, &images.reference),
            splat_ssim: ssim_mean(&images.splats, &images.reference),
            mesh_flip: flip_mean(&images.mesh, &images.reference),
            requantized_flip,
            hole_rate: compare(&images.splats, &images.mesh).hole_rate,
        });
        keep(k, &images);
    }
    Ok(out)
}
