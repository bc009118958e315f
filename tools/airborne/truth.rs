//! The scene's true surfaces as one coloured triangle mesh: the ground on a 1 m grid,
//! every solid's faces, the trunks' and posts' sides, the crowns as spheres. Renders
//! of a simulated scan are measured against it.

use glam::DVec3;
use spt::io::ply::{FaceList, PolyMesh};

use crate::classes::UNDER;
use crate::scene::{Convex, Kind, Scene, ground};

/// A mesh being built, vertices with their colours.
#[derive(Default)]
struct Builder {
    positions: Vec<[f64; 3]>,
    colors: Vec<[u8; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn vertex(&mut self, p: DVec3, kind: Kind) -> u32 {
        self.coloured(p, kind.color())
    }

    fn coloured(&mut self, p: DVec3, color: [u8; 3]) -> u32 {
        self.positions.push(p.to_array());
        self.colors.push(color);
        (self.positions.len() - 1) as u32
    }

    /// The convex polygon `ring` (counter-clockwise seen from outside) as a fan.
    fn polygon(&mut self, ring: &[DVec3], kind: Kind) {
        self.polygon_coloured(ring, kind.color());
    }

    fn polygon_coloured(&mut self, ring: &[DVec3], color: [u8; 3]) {
        let ids: Vec<u32> = ring.iter().map(|p| self.coloured(*p, color)).collect();
        for k in 1..ids.len() - 1 {
            self.triangles.push([ids[0], ids[k], ids[k + 1]]);
        }
    }
}

/// The truth mesh of `scene`, in its own coordinates plus `offset`; with `regions`, also
/// the open space under each crown (a column as wide as the crown, from the ground to
/// its centre), the deck and the carport's roof, as closed solids in their [`UNDER`]
/// colours.
pub fn truth_mesh(scene: &Scene, offset: DVec3, regions: bool) -> PolyMesh {
    let mut b = Builder::default();
    ground_grid(&mut b, scene.half);
    if regions {
        open_space(&mut b, scene);
    }
    for (solid, kind) in &scene.solids {
        for face in solid_faces(solid) {
            b.polygon(face, *kind);
        }
    }
    for (c, kind) in &scene.cylinders {
        column(&mut b, (c.base, c.radius, c.height), kind.color(), false);
    }
    for crown in &scene.crowns {
        sphere(&mut b, crown.centre, crown.radius);
    }
    PolyMesh {
        positions: b
            .positions
            .iter()
            .map(|p| (DVec3::from(*p) + offset).to_array())
            .collect(),
        normals: None,
        colors: Some(b.colors),
        faces: FaceList::triangles(&b.triangles),
    }
}

/// The open space of [`truth_mesh`]'s regions.
fn open_space(b: &mut Builder, scene: &Scene) {
    for crown in &scene.crowns {
        let c = crown.centre;
        let base = DVec3::new(c.x, c.y, ground(c.x, c.y) - 1.0);
        column(b, (base, crown.radius, c.z - base.z), UNDER[0].1, true);
    }
    // The deck's, then the carport's.
    for ((lo, hi), (_, color)) in scene.under.iter().zip(&UNDER[1..]) {
        for face in Convex::cuboid(*lo, *hi).faces() {
            b.polygon_coloured(face, *color);
        }
    }
}

/// A vertical column of 12 sides: (base, radius, height), closed on top when `capped`.
fn column(
    b: &mut Builder,
    (base, radius, height): (DVec3, f64, f64),
    color: [u8; 3],
    capped: bool,
) {
    const SIDES: usize = 12;
    let at = |k: usize, z: f64| {
        let a = std::f64::consts::TAU * k as f64 / SIDES as f64;
        base + DVec3::new(radius * a.cos(), radius * a.sin(), z)
    };
    for k in 0..SIDES {
        let quad = [at(k, 0.0), at(k + 1, 0.0), at(k + 1, height), at(k, height)];
        b.polygon_coloured(&quad, color);
    }
    if capped {
        let top: Vec<DVec3> = (0..SIDES).map(|k| at(k, height)).collect();
        b.polygon_coloured(&top, color);
    }
}

fn solid_faces(solid: &Convex) -> impl Iterator<Item = &[DVec3]> {
    solid.faces().iter().map(Vec::as_slice)
}

/// The ground over the square of half side `half`, on a 1 m grid.
fn ground_grid(b: &mut Builder, half: f64) {
    let n = (2.0 * half) as u32;
    let first = b.positions.len() as u32;
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 - half, j as f64 - half);
            b.vertex(DVec3::new(x, y, ground(x, y)), Kind::Ground);
        }
    }
    let id = |i: u32, j: u32| first + j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            b.triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            b.triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
}

/// A sphere of 24 × 12 quads.
fn sphere(b: &mut Builder, centre: DVec3, radius: f64) {
    let (around, down) = (24usize, 12usize);
    let at = |i: usize, j: usize| {
        let (a, p) = (
            std::f64::consts::TAU * i as f64 / around as f64,
            std::f64::consts::PI * j as f64 / down as f64,
        );
        centre + radius * DVec3::new(p.sin() * a.cos(), p.sin() * a.sin(), p.cos())
    };
    for j in 0..down {
        for i in 0..around {
            let quad = [at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)];
            b.polygon(&quad, Kind::Vegetation);
        }
    }
}
