//! Leaf surfels: one disk per sample, ready for the tree builder (docs/design.md §2).
//!
//! Every surfel leaving this module has a finite position, a unit normal and a finite
//! radius > 0, on any input. All geometric work is done on positions multiplied by a
//! power of two that brings the extent of the model's core (its box without the
//! outliers, [`crate::io::rebase`]) into [0.5, 1): the scaling is exact, so a model
//! scaled by 10⁻⁷ or 10⁷ gets the same surfels up to that scale, no threshold depends
//! on the model's units, and a stray sample far away changes neither.

pub(crate) mod clip;
pub(crate) mod cloud;
mod corners;
pub(crate) mod covering;
pub(crate) mod field;
pub(crate) mod footprint;
pub(crate) mod free_roofs;
pub mod grid;
pub(crate) mod isolated;
pub(crate) mod layers;
pub(crate) mod levels;
pub mod long_triangles;
pub(crate) mod mesh;
pub mod octahedral;
pub mod outward;
pub(crate) mod pca;
pub mod progress;
#[cfg(test)]
mod progress_tests;
pub(crate) mod ring;
pub(crate) mod sets;
pub mod shape;
pub mod terrain;
pub(crate) mod triangle;
pub(crate) mod vegetation;
pub(crate) mod walls;

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::io::delaunay::delaunay_xy;
use crate::io::{Geometry, PointAttributes};
use layers::Layer;
use progress::{Fitted, Progress, Stages};
use shape::SplatShape;

/// One integer that orders (squared distance, index) pairs, for the neighbour searches'
/// selections and sorts: the distance's bits above the index (below 2³²). The bits of
/// floats from +0 to +∞ order as the floats do, so ranks sort by distance, equal
/// distances by index, and no two are equal.
pub(crate) fn distance_rank(squared: f32, index: usize) -> u64 {
    (u64::from(squared.to_bits()) << 32) | index as u64
}

/// The squared distance and the index that [`distance_rank`] packed.
pub(crate) fn rank_parts(rank: u64) -> (f32, usize) {
    (f32::from_bits((rank >> 32) as u32), rank as u32 as usize)
}

/// A splat: centre, unit normal, radius (the major semi-axis), colour, its ellipse and
/// normal field ([`shape`]), and its LiDAR attributes (zero for other models). 52 bytes.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct Surfel {
    /// Centre, relative to the model's `origin`.
    pub position: Vec3,
    pub radius: f32,
    pub normal: Vec3,
    /// RGBA8; mid grey when the model has no colours.
    pub color: [u8; 4],
    pub shape: SplatShape,
    pub attributes: PointAttributes,
}

/// Colour of surfels of a model without colours.
pub const DEFAULT_COLOR: [u8; 4] = [180, 180, 180, 255];

impl Surfel {
    /// A surfel at `position` with [`DEFAULT_COLOR`], not yet sized (radius 0, zero
    /// normal and shape, no attributes).
    pub fn unsized_at(position: Vec3) -> Surfel {
        Surfel {
            position,
            radius: 0.0,
            normal: Vec3::ZERO,
            color: DEFAULT_COLOR,
            shape: SplatShape::zeroed(),
            attributes: PointAttributes::default(),
        }
    }
}

/// How the leaf surfels were made.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct SurfelStats {
    /// Triangles with (numerically) zero area: they add nothing to normals, and half
    /// their longest edge to radii.
    pub degenerate_triangles: u64,
    /// Vertices of a mesh that no triangle uses: normal and radius from neighbours.
    pub isolated_vertices: u64,
    /// Isolated vertices within reach of a held vertex's splat ([`isolated`]): left
    /// out of the tree, as the triangles already draw their place.
    pub redundant_vertices: u64,
    /// Vertices whose area-weighted face normals cancel (e.g. two faces back to back):
    /// normal of their largest face.
    pub cancelled_normals: u64,
    /// Normals given by the file and used as they are.
    pub given_normals: u64,
    /// Surfels whose neighbours all coincide with them: radius from the other surfels.
    pub fallback_radii: u64,
    /// Cloud surfels that close no gap (a boundary, a stray sample) whose radius was
    /// capped at a few neighbourhood spacings ([`covering::MAX_SPACINGS`]).
    pub capped_radii: u64,
    /// Cloud surfels on a boundary of their sampling, clipped where it ends
    /// ([`cloud::BOUNDARY_CLIP_OFFSET`]); a terrain's are left whole.
    pub clipped_boundaries: u64,
    /// Which of a mesh's pieces were turned to face outward (their triangles wound
    /// inward, or their given normals pointing in), which faced out, and which are
    /// open and keep the file's winding ([`outward`]).
    pub sides: outward::Sides,
    /// A terrain's wall surfels, under the edges where its height drops steeply
    /// ([`walls`]): surfels that no sample of the file is.
    pub wall_splats: u64,
    /// A sensor frame's splats of its long triangles ([`long_triangles`]): surfels that
    /// no sample of the file is.
    pub triangle_splats: u64,
    /// A quantised sensor frame's samples whose neighbourhood lies on one depth step:
    /// normal from the neighbours' fits that span steps ([`levels`]).
    pub step_treads: u64,
    /// A sensor frame's splats shrunk to span at most a few of its pixels seen from
    /// the sensor ([`footprint`]).
    pub footprint_capped: u64,
    /// A terrain's splats whose axes were held within a few of its tile's spacings
    /// ([`cloud::TILE_SPACINGS`]).
    pub tile_capped: u64,
    /// A terrain's vegetation (by class or geometry) and lone returns
    /// ([`free_roofs`]), drawn apart from its TIN ([`vegetation`]).
    pub vegetation: u64,
    /// A terrain's samples drawn as a TIN of their own over the ground's ([`layers`]):
    /// bridge decks (by class) and roofs that stand free ([`free_roofs`]).
    pub decks: u64,
    /// The pixel grid a sensor frame's samples lie on in their file's order
    /// ([`grid`]): its surfels are then those of the grid's triangulation, as a mesh's,
    /// and the rules for frames without one (depth steps, footprint) do not run.
    pub pixel_grid: Option<grid::PixelGrid>,
}

#[cfg(test)]
impl Surfel {
    /// Whether its clipped ellipse covers `p` (in its plane, to first order).
    pub(crate) fn covers(&self, p: Vec3) -> bool {
        let n = self.normal.as_dvec3();
        let shape = self.shape.unpack(n);
        let d = (p - self.position).as_dvec3() / self.radius as f64;
        let xy = shape.along_axes(n, d);
        let inside = xy.x * xy.x + (xy.y / shape.ratio).powi(2) < 1.0;
        inside && shape.clip.is_none_or(|c| c.keeps(xy))
    }
}

impl SurfelStats {
    /// The surfels that are no sample of the file: a terrain's walls and the long
    /// triangles' splats of a frame or a terrain.
    pub fn added_splats(&self) -> u64 {
        self.wall_splats + self.triangle_splats
    }
}

/// The leaf surfels of a model.
#[derive(Debug, Clone)]
pub struct LeafSurfels {
    pub surfels: Vec<Surfel>,
    /// Model origin in the file's coordinates: surfel positions are relative to it.
    pub origin: DVec3,
    pub has_colors: bool,
    /// Whether the surfels' LiDAR attributes came from the file.
    pub has_attributes: bool,
    /// False for normals estimated from neighbours, whose sign is arbitrary: such
    /// surfels must be drawn two-sided.
    pub oriented_normals: bool,
    /// Oriented normals whose front is not known: a mesh mostly of open pieces, kept
    /// as wound ([`outward`]); drawn two-sided.
    pub two_sided: bool,
    /// Which way estimated normals were turned: up on a terrain, toward the sensor on
    /// a sensor frame ([`cloud::Orientation`]); not oriented out of a surface, but
    /// consistent. [`NormalsTurned::No`] when `oriented_normals`.
    pub normals_turned: NormalsTurned,
    pub stats: SurfelStats,
    /// A mesh's vertex normals, which its triangles interpolate (the surfels' normals
    /// and colours are the centres of their fitted normal and colour fields, [`field`];
    /// the vertex colours are the file's); empty for a cloud.
    pub vertex_normals: Vec<Vec3>,
    /// Surfels (ascending indices) that [`LeafSurfels::drop_redundant`] leaves out of
    /// the tree: a mesh's redundant isolated vertices ([`isolated`]).
    pub redundant: Vec<u32>,
}

impl LeafSurfels {
    /// Removes the `redundant` surfels (the tree is built without them).
    pub fn drop_redundant(&mut self) {
        let mut next = self.redundant.iter().peekable();
        let mut index = 0u32;
        self.surfels.retain(|_| {
            let drop = next.next_if_eq(&&index).is_some();
            index += 1;
            !drop
        });
        self.redundant.clear();
    }

    /// The promise of this module: every surfel has a finite position, a finite
    /// radius > 0 and a unit normal. The first surfel that breaks it is named.
    pub fn check(&self) -> Result<(), String> {
        let good = |s: &Surfel| {
            s.position.is_finite()
                && s.radius.is_finite()
                && s.radius > 0.0
                && s.normal.is_finite()
                && (s.normal.length() - 1.0).abs() <= 1e-5
        };
        let bad = |s: &Surfel| !good(s);
        match self.surfels.par_iter().position_first(bad) {
            None => Ok(()),
            Some(i) => Err(format!("surfel {i}: {:?}", self.surfels[i])),
        }
    }

    /// (min, median, max) of the radii, in model units.
    pub fn radius_range(&self) -> Option<(f32, f32, f32)> {
        let mut r: Vec<f32> = self.surfels.par_iter().map(|s| s.radius).collect();
        if r.is_empty() {
            return None;
        }
        let mid = r.len() / 2;
        let (lo, median, hi) = r.select_nth_unstable_by(mid, f32::total_cmp);
        let min = lo.iter().copied().fold(*median, f32::min);
        let max = hi.iter().copied().fold(*median, f32::max);
        Some((min, *median, max))
    }
}

/// Largest scaled coordinate: squares and cross products of scaled coordinates (about
/// 2¹²⁰) then fit an f32, with room for sums.
pub const SCALED_REACH: f64 = (1u64 << 60) as f64;

/// The power of two `s` with `extent · s` in [0.5, 1) (1 for a model without extent),
/// lowered where needed so that `reach · s` ≤ [`SCALED_REACH`]: `extent` is the size of
/// the model's core, `reach` the largest offset of any of its positions (outliers
/// included) from the origin.
pub fn unit_scale(extent: f64, reach: f64) -> f32 {
    let mut e = if extent > 0.0 && extent.is_finite() {
        -extent.log2().floor() - 1.0
    } else {
        0.0
    };
    if reach > 0.0 && reach.is_finite() {
        e = e.min((SCALED_REACH / reach).log2().floor());
    }
    (e.clamp(-120.0, 120.0) as f32).exp2()
}

/// Builds the leaf surfels of a model: per vertex from its faces for a mesh, from its
/// nearest neighbours for a point cloud (or a mesh's isolated vertices).
pub fn leaf_surfels(g: &Geometry) -> LeafSurfels {
    leaf_surfels_of(g, g.positions.len())
}

/// [`leaf_surfels`], telling `progress` how many samples have their surfel: the counts
/// add up to the model's samples, most of them told as the fits go (the rest when
/// done; [`progress`]).
pub fn leaf_surfels_with_progress(g: &Geometry, progress: Progress) -> LeafSurfels {
    leaf_surfels_among(g, g.positions.len(), Outward::Vote, progress).0
}

pub use cloud::NormalsTurned;
pub use mesh::Outward;

/// The leaf surfels of the first `own` points of a point cloud (no triangles), whose
/// neighbourhoods see all of its points: a piece of a larger cloud followed by the
/// points around it (its halo, [`crate::tree::out_of_core`]). The halo's own surfels
/// are not kept; a terrain's walls follow the own ones ([`walls`]).
pub fn leaf_surfels_of(g: &Geometry, own: usize) -> LeafSurfels {
    leaf_surfels_among(g, own, Outward::Vote, Progress::NONE).0
}

/// The leaf surfels of the first `own` vertices of a piece of a mesh, whose one-rings
/// and their vertices' one-rings are all among its triangles (the rest of its vertices
/// and triangles are its halo, [`crate::tree::out_of_core`]), their normals negated
/// when `turn` (the whole model's orientation), and their terms of the model's
/// orientation vote about its mean vertex `mean` ([`mesh::Outward::Piece`]). Only the
/// own vertices' surfels (and, on a piece without triangles that is a terrain, their
/// walls) and redundant vertices are kept; no vertex normals.
pub fn mesh_surfels_of(
    g: &Geometry,
    own: usize,
    (turn, mean): (bool, DVec3),
) -> (LeafSurfels, outward::Vote) {
    let outward = Outward::Piece { turn, own, mean };
    let (mut leaves, vote) = leaf_surfels_among(g, own, outward, Progress::NONE);
    leaves.vertex_normals = Vec::new();
    leaves.redundant.retain(|&v| (v as usize) < own);
    (leaves, vote.unwrap_or_default())
}

/// The terms of a mesh's orientation vote ([`outward::Vote`]) over the first `own`
/// vertices of a piece of it (as [`mesh_surfels_of`] takes it), about the model's mean
/// vertex `c`: the pieces' terms add up to the whole model's vote.
pub fn mesh_flux_of(g: &Geometry, own: usize, c: DVec3) -> outward::Vote {
    let mut surfels = initial_surfels(g);
    let given = g.normals.as_deref();
    let scale = model_scale(g);
    let mut stats = SurfelStats::default();
    mesh::face_disks(
        &g.positions,
        scale,
        &g.triangles,
        given,
        &mut surfels,
        &mut stats,
    );
    outward::Vote::over(&g.positions[..own], &surfels[..own], c)
}

/// The unit scale of `g` ([`unit_scale`] of its core's extent and its reach).
fn model_scale(g: &Geometry) -> f32 {
    let reach = (DVec3::from(g.bounds.min) - g.origin)
        .abs()
        .max((DVec3::from(g.bounds.max) - g.origin).abs())
        .max_element();
    unit_scale(g.core.extent().max_element(), reach)
}

/// A surfel per vertex with its position, colour and attributes, not yet sized.
fn initial_surfels(g: &Geometry) -> Vec<Surfel> {
    g.positions
        .par_iter()
        .enumerate()
        .map(|(i, &position)| Surfel {
            color: g.colors.as_ref().map_or(DEFAULT_COLOR, |c| c[i]),
            attributes: g
                .attributes
                .as_ref()
                .map_or_else(PointAttributes::default, |a| a[i]),
            ..Surfel::unsized_at(position)
        })
        .collect()
}

/// A terrain's splats from its TIN ([`terrain::terrain_disks`]), its layers apart
/// ([`layers`]); None for any other model, for a terrain whose ground makes no
/// triangle, and for one whose file gives every normal (kept as given, by the cloud's
/// rules). Its stages are told to `progress` ([`layers::Weights`]).
fn terrain_path(
    g: &Geometry,
    (own, scale): (usize, f32),
    orientation: cloud::Orientation,
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> Option<Vec<Surfel>> {
    if !g.triangles.is_empty() || orientation != cloud::Orientation::Up {
        return None;
    }
    let given = g.normals.as_deref();
    if given.is_some_and(|n| n.iter().all(|v| *v != Vec3::ZERO)) {
        return None;
    }
    let tested = layers::tests_scatter(g, own);
    let stages = Stages::new(own, layers::WEIGHTS.running(tested), progress);
    let (labels, first) = layers::labels(g, (own, scale), (&stages, tested));
    let layers = layers::Layers::of(&labels, own);
    let ground_layer = layers.get(Layer::Ground);
    if layers.all_ground() {
        // Every sample, the halo's too, in one TIN: the first, where it holds them all.
        let delaunay = match ground_layer.0.len() == g.positions.len() {
            true => first.ground(g, &labels, ground_layer.0),
            false => delaunay_xy(&g.positions),
        };
        stages.ended(layers::WEIGHTS.ground_tin);
        let share = stages.share(layers::WEIGHTS.layers);
        let progress = Progress::to(&share);
        let look = (given, (g.colors.as_deref(), g.attributes.as_deref()));
        let all = (own, &terrain::Cover::none());
        let at = (&g.positions[..], delaunay, scale);
        let tin = terrain::terrain_disks(at, all, look, surfels, stats, progress);
        return tin.map(|tin| tin.splats);
    }
    // The ground first, under the cover of the decks and the vegetation.
    let (decks, decks_own) = layers.get(Layer::Deck);
    let mut plants = layers.get(Layer::Plants).0.to_vec();
    let over = decks.iter().chain(&plants);
    let cover = terrain::Cover::of(over.map(|&i| g.positions[i as usize]));
    let ground_tin = (Some(first.ground(g, &labels, ground_layer.0)), &cover);
    drop(labels);
    stages.ended(layers::WEIGHTS.ground_tin);
    let share = stages.share(layers::WEIGHTS.layers);
    let progress = Progress::to(&share);
    let ground = layers::tin_among(
        (g, scale),
        ground_layer,
        ground_tin,
        surfels,
        stats,
        progress,
    )?;
    let mut splats = ground.splats;
    if decks_own > 0 {
        let none = terrain::Cover::none();
        match layers::tin_among(
            (g, scale),
            (decks, decks_own),
            (None, &none),
            surfels,
            stats,
            progress,
        ) {
            Some(deck) => {
                stats.decks = decks_own as u64;
                splats.extend(deck.splats);
            }
            // Too few to make a triangle: drawn as plants are, among themselves (own
            // samples first, as every layer lists them).
            None => {
                plants.extend(&decks[..decks_own]);
                plants.sort_unstable_by_key(|&i| ((i as usize) >= own, i));
            }
        }
    }
    let plants_own = plants.iter().filter(|&&i| (i as usize) < own).count();
    let scales = (&g.positions[..], scale, ground.spacing);
    vegetation::plant_disks(
        scales,
        (&plants, plants_own),
        given,
        surfels,
        stats,
        progress,
    );
    stats.triangle_splats = splats.len() as u64;
    Some(splats)
}

/// What a path makes besides the surfels.
struct Made {
    /// Whether its normals are estimated and turned by the cloud's orientation (not a
    /// mesh's, oriented by its vote).
    estimated: bool,
    /// A terrain's walls and the splats of a frame's or a terrain's long triangles.
    walls: Vec<Surfel>,
    /// The isolated vertices that are redundant, ascending.
    redundant: Vec<u32>,
    /// A mesh's vertex normals.
    vertex_normals: Vec<Vec3>,
    /// A mesh piece's terms of the orientation vote.
    vote: Option<outward::Vote>,
}

impl Made {
    /// A cloud's path's, with its `walls`.
    fn cloud(walls: Vec<Surfel>) -> Made {
        Made {
            estimated: true,
            walls,
            redundant: Vec::new(),
            vertex_normals: Vec::new(),
            vote: None,
        }
    }
}

/// A sensor frame's splats from its pixel grid ([`grid::frame_disks`]): for a whole
/// model (not a job's piece) seen from a sensor, whose samples lie on a grid; None for
/// any other. The shaped samples are told to `progress`.
fn frame_path(
    g: &Geometry,
    ((own, scale), orientation): ((usize, f32), cloud::Orientation),
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> Option<Made> {
    let cloud::Orientation::Toward(sensor) = orientation else {
        return None;
    };
    if own != g.positions.len() {
        return None;
    }
    let mesh = match g.triangles.is_empty() {
        true => grid::frame_triangles(g, sensor),
        false => grid::meshed_frame(g, sensor),
    }?;
    let given = g.normals.as_deref();
    let at = (&mesh, sensor, scale);
    let (redundant, walls) = grid::frame_disks(g, at, given, surfels, stats, progress);
    stats.pixel_grid = Some(mesh.grid);
    let vertex_normals = match g.triangles.is_empty() {
        true => Vec::new(),
        false => grid::vertex_normals(&g.positions, &mesh.triangles, given),
    };
    Some(Made {
        redundant,
        vertex_normals,
        ..Made::cloud(walls)
    })
}

/// The leaf surfels of the first `own` samples, and a mesh piece's terms of the
/// orientation vote; `own` told to `progress` in all.
fn leaf_surfels_among(
    g: &Geometry,
    own: usize,
    outward: Outward,
    progress: Progress,
) -> (LeafSurfels, Option<outward::Vote>) {
    let fitted = Fitted::new(own, progress);
    let progress = Progress::to(&fitted);
    let scale = model_scale(g);
    let given = g.normals.as_deref();
    let mut stats = SurfelStats {
        given_normals: given.map_or(0, |n| {
            n[..own].par_iter().filter(|v| **v != Vec3::ZERO).count() as u64
        }),
        ..SurfelStats::default()
    };
    let mut surfels = initial_surfels(g);
    let orientation = cloud::Orientation::of(&g.core, &g.bounds, g.origin);
    let how = ((own, scale), orientation, outward);
    let made = made_by_path(g, how, &mut surfels, &mut stats, progress);
    // A cloud's normals are oriented where the file gives every one; its estimated ones
    // were turned by the orientation. A mesh's follow its pieces' vote.
    let oriented = !made.estimated || (given.is_some() && stats.given_normals == own as u64);
    let normals_turned = match oriented {
        true => NormalsTurned::No,
        false => NormalsTurned::of(orientation),
    };
    fitted.finish();
    // The halo's surfels go; a terrain's walls under the own samples' edges join them.
    surfels.truncate(own);
    surfels.extend(made.walls);
    let leaves = LeafSurfels {
        surfels,
        origin: g.origin,
        has_colors: g.colors.is_some(),
        has_attributes: g.attributes.is_some(),
        oriented_normals: oriented,
        two_sided: stats.sides.two_sided,
        normals_turned,
        stats,
        redundant: made.redundant,
        vertex_normals: made.vertex_normals,
    };
    (leaves, made.vote)
}

/// The surfels of the first `own` samples by the first path that takes the model: a
/// sensor frame's grid, a terrain's TIN, a cloud's neighbourhoods, a mesh's rings.
fn made_by_path(
    g: &Geometry,
    (at, orientation, outward): ((usize, f32), cloud::Orientation, Outward),
    surfels: &mut [Surfel],
    stats: &mut SurfelStats,
    progress: Progress,
) -> Made {
    let ((own, scale), given) = (at, g.normals.as_deref());
    if let Some(frame) = frame_path(g, (at, orientation), surfels, stats, progress) {
        return frame;
    }
    if let Some(walls) = terrain_path(g, at, orientation, surfels, stats, progress) {
        return Made::cloud(walls);
    }
    if g.triangles.is_empty() {
        let all: Vec<u32> = (0..own as u32).collect();
        let how = (covering::RadiusRule::Surrounding, orientation, progress);
        let walls = cloud::neighbour_disks(&g.positions, scale, &all, how, given, surfels, stats);
        return Made::cloud(walls);
    }
    let look = (given, g.colors.is_some(), outward);
    let (points, triangles) = (&g.positions, &g.triangles);
    let disks = mesh::vertex_disks(points, scale, triangles, look, surfels, stats, progress);
    Made {
        estimated: false,
        walls: Vec::new(),
        redundant: disks.redundant,
        vertex_normals: disks.normals,
        vote: disks.vote,
    }
}
