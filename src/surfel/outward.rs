//! Which side of a mesh faces out, decided for each connected piece of its triangles.
//!
//! For a closed surface S with outward normals, ∫_S (p − c)·n dA = 3·volume > 0 for
//! any point c (the divergence theorem); the sum over a piece's vertices, with dA ≈ r²
//! (the covering radius squared) and c the piece's mean vertex, estimates it. Divided
//! by ∫_S |p − c| dA it is 1 for a sphere, about 4a/L for a closed tube of radius a
//! and length L: normals turn below −[`INWARD`]. The generated knot, wound inward,
//! votes −0.31; bunny 0.61, dragon40k 0.32. Oriented so, the renderer tells a
//! surface's back from its front (`BACK_WEIGHT`, `shaders/ewa.wgsl`).
//!
//! On an open surface the sum means nothing: it closes the surface with the cone from
//! c to its boundary (on which (p − c)·n = 0), and a concave sheet seen from its
//! concave side (a bowl, a room's corner, a valley, a depth frame of a room) votes
//! inward however it is wound. So a piece votes only when it is **closed**: when the
//! vector area of its normals, |Σ r² n|, is at most [`CLOSED_FACING`] of its area
//! Σ r². That is 0 for any closed surface (∮ n dA = 0) and, for an open one, the
//! vector area of its holes: 1/2 for a hemisphere, 1/√3 for a room's corner, 1/√2 for
//! a quarter sphere, 0.60 for the largest piece of the shared kinect frame triangulated
//! on its grid (its three scraps 0.47–0.69). Bunny, open at its base, scores 0.0085;
//! dragon40k 0.0010, the knot 0.
//!
//! An open piece keeps the file's winding. Which side of it is the front is not
//! known, so a model whose open pieces hold more than [`OPEN_AREA`] of its area is
//! drawn two-sided at full weight, as a cloud of unknown orientation is
//! ([`super::LeafSurfels::two_sided`]); its normals stay consistent, and its tree
//! averages them as a closed mesh's. Vertices that no triangle reaches follow the
//! largest piece. Out of core, a model votes as one piece
//! ([`crate::tree::out_of_core`]).

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::Surfel;
use super::sets::Sets;

/// A closed piece's normals face inward when their flux through it is below −INWARD
/// of its spread.
pub const INWARD: f64 = 0.02;

/// Largest |Σ r² n| / Σ r² of a closed piece: holes whose vector area is a tenth of
/// the surface's leave the vote its meaning (bunny's base: 0.0085); the open sheets of
/// the module doc score 0.47 and more.
pub const CLOSED_FACING: f64 = 0.1;

/// Largest share of a model's area Σ r² in open pieces for it to be drawn one-sided:
/// stray open scraps beside a closed body do not make it two-sided.
pub const OPEN_AREA: f64 = 0.01;

/// A piece's terms of the vote, about a centre c: sums over its vertices, which add
/// up over pieces of a model ([`crate::tree::out_of_core`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Vote {
    /// Σ r² (p − c)·n.
    pub flux: f64,
    /// Σ r² |p − c|.
    pub spread: f64,
    /// Σ r² n.
    pub facing: DVec3,
    /// Σ r².
    pub area: f64,
}

impl Vote {
    /// The terms of the surfels `surfels` (at `points`) about `c`.
    pub fn over(points: &[Vec3], surfels: &[Surfel], c: DVec3) -> Vote {
        (points.par_iter().zip(surfels.par_iter()))
            .map(|(p, s)| Vote::of(*p, s, c))
            .reduce(Vote::default, Vote::plus)
    }

    /// One surfel's terms, at `p`, about `c`.
    pub fn of(p: Vec3, s: &Surfel, c: DVec3) -> Vote {
        let (r2, d, n) = (
            (s.radius as f64).powi(2),
            p.as_dvec3() - c,
            s.normal.as_dvec3(),
        );
        Vote {
            flux: r2 * d.dot(n),
            spread: r2 * d.length(),
            facing: r2 * n,
            area: r2,
        }
    }

    pub fn plus(self, o: Vote) -> Vote {
        Vote {
            flux: self.flux + o.flux,
            spread: self.spread + o.spread,
            facing: self.facing + o.facing,
            area: self.area + o.area,
        }
    }

    /// Whether the piece is closed enough for the vote to mean something.
    pub fn closed(&self) -> bool {
        self.facing.length() <= CLOSED_FACING * self.area
    }

    /// Whether a closed piece's normals face inward.
    pub fn turns(&self) -> bool {
        self.closed() && self.flux < -INWARD * self.spread
    }
}

/// What [`orient_pieces`] did, per kind of piece.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Sides {
    /// Closed pieces whose normals were negated to face outward (wound inward).
    pub turned: u64,
    /// Closed pieces that faced outward as they were.
    pub kept: u64,
    /// Open pieces, which keep the file's winding.
    pub open: u64,
    /// Whether open pieces hold more than [`OPEN_AREA`] of the area: the model is
    /// drawn two-sided.
    pub two_sided: bool,
}

/// Negates the normals of each closed piece of the mesh that faces inward, and of the
/// vertices that no triangle reaches when the largest piece does (the module doc).
pub fn orient_pieces(points: &[Vec3], triangles: &[[u32; 3]], surfels: &mut [Surfel]) -> Sides {
    let (piece, count) = pieces(points.len(), triangles);
    let mut centres = vec![(DVec3::ZERO, 0u64); count];
    for (p, &k) in points.iter().zip(&piece) {
        if k != LOOSE {
            let c = &mut centres[k as usize];
            *c = (c.0 + p.as_dvec3(), c.1 + 1);
        }
    }
    let mut votes = vec![Vote::default(); count];
    for ((p, s), &k) in points.iter().zip(surfels.iter()).zip(&piece) {
        if k != LOOSE {
            let (sum, n) = centres[k as usize];
            let vote = &mut votes[k as usize];
            *vote = vote.plus(Vote::of(*p, s, sum / n as f64));
        }
    }
    let turns: Vec<bool> = votes.iter().map(Vote::turns).collect();
    let largest = (0..count).max_by(|&a, &b| votes[a].area.total_cmp(&votes[b].area));
    let loose_turn = largest.is_some_and(|k| turns[k]);
    (surfels.par_iter_mut().zip(piece.par_iter())).for_each(|(s, &k)| {
        let turn = if k == LOOSE {
            loose_turn
        } else {
            turns[k as usize]
        };
        if turn {
            s.normal = -s.normal;
        }
    });
    sides_of(&votes)
}

/// The count of each kind among the pieces' `votes`.
fn sides_of(votes: &[Vote]) -> Sides {
    let open_area: f64 = votes.iter().filter(|v| !v.closed()).map(|v| v.area).sum();
    let area: f64 = votes.iter().map(|v| v.area).sum();
    let count = |f: &dyn Fn(&Vote) -> bool| votes.iter().filter(|v| f(v)).count() as u64;
    Sides {
        turned: count(&|v| v.turns()),
        kept: count(&|v| v.closed() && !v.turns()),
        open: count(&|v| !v.closed()),
        two_sided: open_area > OPEN_AREA * area,
    }
}

/// The piece of a vertex that no triangle reaches.
const LOOSE: u32 = u32::MAX;

/// Each vertex's piece (the triangles that share vertices, numbered from 0 in the
/// order of their least vertex), [`LOOSE`] for a vertex of no triangle; and the count
/// of pieces.
fn pieces(vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let sets = Sets::new(vertices);
    let mut reached = vec![false; vertices];
    for t in triangles {
        sets.join(t[0] as usize, t[1] as usize);
        sets.join(t[0] as usize, t[2] as usize);
        t.iter().for_each(|&v| reached[v as usize] = true);
    }
    let mut piece = vec![LOOSE; vertices];
    let mut count = 0;
    for v in 0..vertices {
        if !reached[v] {
            continue;
        }
        let root = sets.root(v);
        if root == v {
            piece[v] = count;
            count += 1;
        } else {
            piece[v] = piece[root];
        }
    }
    (piece, count as usize)
}
