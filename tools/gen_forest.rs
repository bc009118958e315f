//! The forest test scene (docs/scenes.md): a procedural tree of about 10⁶ samples
//! (trunk and branches as a tapered-cylinder mesh, leaves as small coloured quads), and
//! a scene of many of them scattered over a terrain.
//!
//! ```sh
//! cargo run --release --example gen_forest -- --out DIR          # 10⁵ trees on terrain_utm
//! cargo run --release --example gen_forest -- --out DIR --trees 16 --leaves 20000
//! ```
//!
//! Writes DIR/tree.ply and DIR/tree.spt (the tree, z up, its foot at the origin),
//! DIR/terrain.spt (the terrain converted), DIR/forest.json and
//! DIR/forest.instances.ply (`spt scatter`'s). The same arguments give the same files.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Parser;
use glam::DVec3;

use spt::io::ply::{Encoding, FaceList, PlyLayout, PolyMesh, write_ply};
use spt::tree::instances::scatter::SplitMix;

#[derive(Parser)]
#[command(about = "Writes a procedural tree and a forest scene of it over a terrain")]
struct Args {
    /// Folder to write into.
    #[arg(long)]
    out: PathBuf,
    /// Trees in the forest.
    #[arg(long, default_value_t = 100_000)]
    trees: usize,
    /// Leaves of the tree (4 vertices each): 240,000 make about 10⁶ samples.
    #[arg(long, default_value_t = 240_000)]
    leaves: usize,
    /// The terrain (default: terrain_utm.ply of the shared data, through SPT_DATA).
    #[arg(long)]
    terrain: Option<PathBuf>,
    /// Seed of the tree's shape and of the scattering.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Uniform numbers in a range.
struct Rng(SplitMix);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0.uniform()
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}

/// A mesh being built: positions, colours, triangles.
#[derive(Default)]
struct Builder {
    positions: Vec<[f64; 3]>,
    colors: Vec<[u8; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    /// A tapered cylinder from `a` (radius `ra`) to `b` (radius `rb`), `around` × `along`
    /// vertices, closed at neither end.
    fn limb(
        &mut self,
        (a, ra): (DVec3, f64),
        (b, rb): (DVec3, f64),
        (around, along): (u32, u32),
        color: [u8; 3],
    ) {
        let axis = (b - a).normalize();
        let side = axis.any_orthonormal_vector();
        let other = axis.cross(side);
        let first = self.positions.len() as u32;
        for j in 0..along {
            let t = j as f64 / (along - 1) as f64;
            let centre = a.lerp(b, t);
            let r = ra + (rb - ra) * t;
            for i in 0..around {
                let angle = TAU * i as f64 / around as f64;
                let p = centre + r * (angle.cos() * side + angle.sin() * other);
                self.positions.push(p.to_array());
                self.colors.push(color);
            }
        }
        for j in 0..along - 1 {
            for i in 0..around {
                let (i1, row, next) = (
                    (i + 1) % around,
                    first + j * around,
                    first + (j + 1) * around,
                );
                self.triangles.push([row + i, row + i1, next + i1]);
                self.triangles.push([row + i, next + i1, next + i]);
            }
        }
    }

    /// A leaf: a quad of `size` at `at`, facing `normal`.
    fn leaf(&mut self, at: DVec3, normal: DVec3, size: f64, color: [u8; 3]) {
        let u = normal.any_orthonormal_vector() * size;
        let v = normal.cross(u) * 0.6;
        let first = self.positions.len() as u32;
        for p in [at - u - v, at + u - v, at + u + v, at - u + v] {
            self.positions.push(p.to_array());
            self.colors.push(color);
        }
        self.triangles.push([first, first + 1, first + 2]);
        self.triangles.push([first, first + 2, first + 3]);
    }
}

/// The tree: an 8 m trunk, branches from 2.5 m up, leaves about the branches' outer
/// halves. z up, its foot at the origin.
fn tree(leaves: usize, rng: &mut Rng) -> PolyMesh {
    let mut b = Builder::default();
    let bark = [92, 64, 40];
    let height = 8.0;
    b.limb(
        (DVec3::ZERO, 0.28),
        (DVec3::new(0.0, 0.0, height), 0.06),
        (32, 64),
        bark,
    );
    let branches = 48;
    let mut tips = Vec::new();
    for k in 0..branches {
        let h = rng.range(2.5, 7.6);
        let yaw = TAU * (k as f64 * 0.618_034).fract();
        let length = 3.2 * (1.0 - (h - 2.5) / 6.0) + 0.6;
        let dir = DVec3::new(yaw.cos(), yaw.sin(), rng.range(0.3, 0.9)).normalize();
        let start = DVec3::new(0.0, 0.0, h);
        let end = start + dir * length;
        b.limb((start, 0.07), (end, 0.015), (10, 16), bark);
        tips.push((start, end));
    }
    for _ in 0..leaves {
        let (start, end) = tips[(rng.uniform() * tips.len() as f64) as usize % tips.len()];
        let along = start.lerp(end, rng.range(0.35, 1.0));
        let offset = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-0.7, 1.0),
        ) * 0.7;
        let normal = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 1.0).normalize();
        let shade = rng.uniform();
        let green = [
            (40.0 + 50.0 * shade) as u8,
            (95.0 + 80.0 * shade) as u8,
            (25.0 + 30.0 * shade) as u8,
        ];
        b.leaf(along + offset, normal, 0.09, green);
    }
    PolyMesh {
        positions: b.positions,
        normals: None,
        colors: Some(b.colors),
        faces: FaceList::triangles(&b.triangles),
    }
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let terrain = match &args.terrain {
        Some(t) => t.clone(),
        None => Path::new(&std::env::var("SPT_DATA").unwrap_or_else(|_| "../shared/data".into()))
            .join("terrain_utm.ply"),
    };
    let mut rng = Rng(SplitMix(args.seed));
    let mesh = tree(args.leaves, &mut rng);
    let tree_ply = args.out.join("tree.ply");
    write_ply(
        &tree_ply,
        &mesh,
        &PlyLayout::standard(Encoding::BinaryLittleEndian, &mesh),
    )?;
    println!(
        "tree      {} vertices, {} triangles: {}",
        mesh.positions.len(),
        mesh.faces.sizes.len(),
        tree_ply.display()
    );
    let tree_spt = args.out.join("tree.spt");
    spt::apps::convert::run(&tree_ply, &tree_spt)?;
    let terrain_spt = args.out.join("terrain.spt");
    spt::apps::convert::run(&terrain, &terrain_spt)?;
    let scatter = spt::apps::scatter::ScatterArgs {
        base: terrain,
        models: vec![tree_spt],
        output: args.out.join("forest.json"),
        density: 0.01,
        count: Some(args.trees),
        draw_base: Some(terrain_spt),
        yaw: vec![0.0, 360.0],
        scale: vec![0.8, 1.25],
        max_slope: 35.0,
        seed: args.seed,
    };
    spt::apps::scatter::run(&scatter)
}
