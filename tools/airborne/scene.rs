//! The known 3D scene an airborne scan is simulated over: rolling ground with a gully,
//! buildings with flat and gabled roofs, trees (a trunk and a round, porous crown), a
//! bridge deck on pillars over the gully and a carport roof on posts. Every part is
//! analytic, so that a ray finds its first hit exactly ([`Scene::first_hit`]) and the
//! truth mesh is the parts' own surfaces ([`Scene::truth_mesh`]).

use glam::DVec3;

pub use crate::classes::Kind;

/// A convex solid: the points on the inner side of every plane (n · p ≤ d).
#[derive(Debug, Clone)]
pub struct Convex {
    planes: Vec<(DVec3, f64)>,
    /// Its faces as polygons (counter-clockwise seen from outside), for the mesh.
    faces: Vec<Vec<DVec3>>,
}

impl Convex {
    /// The box `lo`–`hi`.
    pub fn cuboid(lo: DVec3, hi: DVec3) -> Convex {
        let c = |x: bool, y: bool, z: bool| {
            DVec3::new(
                if x { hi.x } else { lo.x },
                if y { hi.y } else { lo.y },
                if z { hi.z } else { lo.z },
            )
        };
        let (f, t) = (false, true);
        let faces = vec![
            vec![c(f, f, f), c(f, t, f), c(t, t, f), c(t, f, f)],
            vec![c(f, f, t), c(t, f, t), c(t, t, t), c(f, t, t)],
            vec![c(f, f, f), c(t, f, f), c(t, f, t), c(f, f, t)],
            vec![c(f, t, f), c(f, t, t), c(t, t, t), c(t, t, f)],
            vec![c(f, f, f), c(f, f, t), c(f, t, t), c(f, t, f)],
            vec![c(t, f, f), c(t, t, f), c(t, t, t), c(t, f, t)],
        ];
        Convex::of_faces(faces)
    }

    /// A gabled roof over the rectangle `lo`–`hi` (x, y) from `eave` up to `ridge`,
    /// its ridge along x.
    pub fn gable(lo: DVec3, hi: DVec3, eave: f64, ridge: f64) -> Convex {
        let ym = 0.5 * (lo.y + hi.y);
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let faces = vec![
            vec![
                p(lo.x, lo.y, eave),
                p(lo.x, hi.y, eave),
                p(hi.x, hi.y, eave),
                p(hi.x, lo.y, eave),
            ],
            vec![
                p(lo.x, lo.y, eave),
                p(hi.x, lo.y, eave),
                p(hi.x, ym, ridge),
                p(lo.x, ym, ridge),
            ],
            vec![
                p(lo.x, hi.y, eave),
                p(lo.x, ym, ridge),
                p(hi.x, ym, ridge),
                p(hi.x, hi.y, eave),
            ],
            vec![p(lo.x, lo.y, eave), p(lo.x, ym, ridge), p(lo.x, hi.y, eave)],
            vec![p(hi.x, lo.y, eave), p(hi.x, hi.y, eave), p(hi.x, ym, ridge)],
        ];
        Convex::of_faces(faces)
    }

    fn of_faces(faces: Vec<Vec<DVec3>>) -> Convex {
        let planes = faces
            .iter()
            .map(|f| {
                let n = (f[1] - f[0]).cross(f[2] - f[0]).normalize();
                (n, n.dot(f[0]))
            })
            .collect();
        Convex { planes, faces }
    }

    /// Its faces, counter-clockwise seen from outside.
    pub fn faces(&self) -> &[Vec<DVec3>] {
        &self.faces
    }

    /// Where the ray `o + t d` enters the solid, for t in `(0, t_max)` (Cyrus–Beck).
    fn entry(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
        let (mut t0, mut t1) = (0.0f64, t_max);
        for &(n, dist) in &self.planes {
            let (denom, num) = (n.dot(d), dist - n.dot(o));
            if denom.abs() < 1e-12 {
                if num < 0.0 {
                    return None;
                }
            } else if denom < 0.0 {
                t0 = t0.max(num / denom);
            } else {
                t1 = t1.min(num / denom);
            }
            if t0 > t1 {
                return None;
            }
        }
        (t0 > 0.0).then_some(t0)
    }
}

/// A vertical cylinder (a trunk, a post).
#[derive(Debug, Clone, Copy)]
pub struct Cylinder {
    pub base: DVec3,
    pub radius: f64,
    pub height: f64,
}

impl Cylinder {
    /// Where the ray enters its side (its caps are hidden: under a crown, on the ground).
    fn entry(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
        let (p, q) = (o - self.base, d);
        let a = q.x * q.x + q.y * q.y;
        let b = 2.0 * (p.x * q.x + p.y * q.y);
        let c = p.x * p.x + p.y * p.y - self.radius * self.radius;
        let disc = b * b - 4.0 * a * c;
        if a < 1e-12 || disc < 0.0 {
            return None;
        }
        let t = (-b - disc.sqrt()) / (2.0 * a);
        let z = p.z + t * q.z;
        (t > 0.0 && t < t_max && (0.0..=self.height).contains(&z)).then_some(t)
    }
}

/// A round crown: a sphere of foliage that a pulse enters and may pass through.
#[derive(Debug, Clone, Copy)]
pub struct Crown {
    pub centre: DVec3,
    pub radius: f64,
}

impl Crown {
    /// The ray's chord through the crown, (enter, leave), within `(0, t_max)`.
    fn chord(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, f64)> {
        let p = o - self.centre;
        let b = p.dot(d);
        let disc = b * b - (p.length_squared() - self.radius * self.radius);
        if disc < 0.0 {
            return None;
        }
        let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
        (t1 > 0.0 && t0 < t_max).then_some((t0.max(0.0), t1.min(t_max)))
    }
}

/// The ground's height at (x, y): gentle rolling, and a gully 6 m deep along y under the
/// bridge (x near [`GULLY_X`]).
pub fn ground(x: f64, y: f64) -> f64 {
    let rolling = 1.5 * (x / 37.0).sin() * (y / 53.0).cos() + 0.8 * (x / 19.0 + y / 23.0).sin();
    let across = (x - GULLY_X) / GULLY_HALF_WIDTH;
    rolling - 6.0 * (1.0 - across * across).max(0.0)
}

/// Where the gully runs (x), and its half width.
pub const GULLY_X: f64 = 60.0;
pub const GULLY_HALF_WIDTH: f64 = 12.0;

/// The whole scene.
pub struct Scene {
    /// Half the side of the square it covers, centred on the origin.
    pub half: f64,
    pub solids: Vec<(Convex, Kind)>,
    pub cylinders: Vec<(Cylinder, Kind)>,
    pub crowns: Vec<Crown>,
    /// The open space under the bridge's deck and the carport's roof, as boxes from
    /// below the ground up to their undersides.
    pub under: Vec<(DVec3, DVec3)>,
}

/// A first return: where, and off what.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    pub t: f64,
    pub kind: Kind,
}

/// Foliage density of a crown: a pulse travels an exponential free path of this mean
/// inside it (metres) before it returns; about one in six passes through a crown 7 m
/// across to what lies below.
const FREE_PATH: f64 = 4.0;

impl Scene {
    /// The scene over a square of side 200 m centred on the origin: the gully and its
    /// bridge east, six buildings south-west (flat and gabled roofs), a carport and 60
    /// trees north.
    pub fn new() -> Scene {
        let mut solids = Vec::new();
        let mut cylinders = Vec::new();
        // The bridge: a deck 0.8 m thick across the gully, on three pillars.
        let deck_top = 3.0;
        let deck = Convex::cuboid(
            DVec3::new(GULLY_X - 16.0, -4.0, deck_top - 0.8),
            DVec3::new(GULLY_X + 16.0, 4.0, deck_top),
        );
        solids.push((deck, Kind::Bridge));
        let mut under = vec![(
            DVec3::new(GULLY_X - 16.0, -4.0, ground(GULLY_X, 0.0) - 1.0),
            DVec3::new(GULLY_X + 16.0, 4.0, deck_top - 0.8),
        )];
        for x in [GULLY_X - 8.0, GULLY_X, GULLY_X + 8.0] {
            let lo = DVec3::new(x - 0.5, -0.5, ground(x, 0.0) - 1.0);
            let hi = DVec3::new(x + 0.5, 0.5, deck_top - 0.8);
            solids.push((Convex::cuboid(lo, hi), Kind::Bridge));
        }
        // Buildings on a 3 × 2 grid, every other one gabled.
        for (k, (i, j)) in (0..3).flat_map(|i| (0..2).map(move |j| (i, j))).enumerate() {
            let (x0, y0) = (-85.0 + 30.0 * i as f64, -85.0 + 35.0 * j as f64);
            let (lo, hi) = (
                DVec3::new(x0, y0, 0.0),
                DVec3::new(x0 + 18.0, y0 + 14.0, 0.0),
            );
            let base = lowest_ground(lo, hi) - 1.0;
            let eave = base + 1.0 + 6.0 + 3.0 * k as f64;
            let walls = Convex::cuboid(DVec3::new(lo.x, lo.y, base), DVec3::new(hi.x, hi.y, eave));
            solids.push((walls, Kind::Building));
            if k % 2 == 1 {
                solids.push((Convex::gable(lo, hi, eave, eave + 4.0), Kind::Building));
            }
        }
        // A carport: a roof 0.2 m thick, 2.6 m up, on four posts.
        let (lo, hi) = (DVec3::new(-20.0, 20.0, 0.0), DVec3::new(-14.0, 26.0, 0.0));
        let top = ground(-17.0, 23.0) + 2.8;
        solids.push((
            Convex::cuboid(
                DVec3::new(lo.x, lo.y, top - 0.2),
                DVec3::new(hi.x, hi.y, top),
            ),
            Kind::Building,
        ));
        under.push((
            DVec3::new(lo.x, lo.y, lowest_ground(lo, hi) - 0.5),
            DVec3::new(hi.x, hi.y, top - 0.2),
        ));
        for (x, y) in [(lo.x, lo.y), (hi.x, lo.y), (lo.x, hi.y), (hi.x, hi.y)] {
            let base = DVec3::new(x, y, ground(x, y) - 0.5);
            let height = top - 0.2 - base.z;
            cylinders.push((
                Cylinder {
                    base,
                    radius: 0.1,
                    height,
                },
                Kind::Building,
            ));
        }
        let crowns = trees(&mut cylinders);
        Scene {
            half: 100.0,
            solids,
            cylinders,
            crowns,
            under,
        }
    }

    /// The first return of the pulse from `o` along the unit `d`: the nearest surface,
    /// or a point inside a crown at the end of a free path drawn from `uniform` (0–1).
    pub fn first_hit(&self, o: DVec3, d: DVec3, uniform: &mut dyn FnMut() -> f64) -> Hit {
        let mut best = Hit {
            t: ground_hit(o, d),
            kind: Kind::Ground,
        };
        for (solid, kind) in &self.solids {
            if let Some(t) = solid.entry(o, d, best.t) {
                best = Hit { t, kind: *kind };
            }
        }
        for (c, kind) in &self.cylinders {
            if let Some(t) = c.entry(o, d, best.t) {
                best = Hit { t, kind: *kind };
            }
        }
        let mut chords: Vec<(f64, f64)> = self
            .crowns
            .iter()
            .filter_map(|c| c.chord(o, d, best.t))
            .collect();
        chords.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (t0, t1) in chords {
            let t = t0 - FREE_PATH * uniform().max(1e-12).ln();
            if t < t1.min(best.t) {
                return Hit {
                    t,
                    kind: Kind::Vegetation,
                };
            }
        }
        best
    }
}

/// The lowest ground under the rectangle `lo`–`hi` (x, y), on a 1 m grid.
fn lowest_ground(lo: DVec3, hi: DVec3) -> f64 {
    let mut low = f64::INFINITY;
    let (nx, ny) = ((hi.x - lo.x) as usize, (hi.y - lo.y) as usize);
    for i in 0..=nx {
        for j in 0..=ny {
            low = low.min(ground(lo.x + i as f64, lo.y + j as f64));
        }
    }
    low
}

/// Sixty trees north of the buildings, clear of the carport and the gully, on a jittered
/// grid: a trunk 0.25 m in radius up into a crown 2.5–4 m in radius.
fn trees(cylinders: &mut Vec<(Cylinder, Kind)>) -> Vec<Crown> {
    let mut crowns = Vec::new();
    let mut k = 0u32;
    while crowns.len() < 60 {
        let n = k;
        k += 1;
        // A hash of (tree, salt) in [0, 1).
        let h = |s: u32| {
            (n.wrapping_mul(2_654_435_761) ^ s).wrapping_mul(2_246_822_519) >> 8
        } as f64
            / (1u32 << 24) as f64;
        let (i, j) = ((n % 10) as f64, (n / 10) as f64);
        let (x, y) = (-88.0 + 12.0 * i + 4.0 * h(1), 12.0 + 12.0 * j + 4.0 * h(2));
        let near_carport = (-26.0..-8.0).contains(&x) && (14.0..32.0).contains(&y);
        if near_carport || (x - GULLY_X).abs() < GULLY_HALF_WIDTH + 5.0 || y > 95.0 {
            continue;
        }
        let radius = 2.5 + 1.5 * h(3);
        let ground_z = ground(x, y);
        let centre = DVec3::new(x, y, ground_z + 3.5 + radius);
        let base = DVec3::new(x, y, ground_z - 0.5);
        cylinders.push((
            Cylinder {
                base,
                radius: 0.25,
                height: centre.z - base.z,
            },
            Kind::Vegetation,
        ));
        crowns.push(Crown { centre, radius });
    }
    crowns
}

/// Where the ray `o + t d` (going down) meets the ground: marched in steps of 0.25 m
/// from 20 m above the highest ground, then bisected.
fn ground_hit(o: DVec3, d: DVec3) -> f64 {
    let above = |t: f64| {
        let p = o + d * t;
        p.z - ground(p.x, p.y)
    };
    let mut t = ((o.z - 20.0) / -d.z).max(0.0);
    while above(t + 0.25) > 0.0 {
        t += 0.25;
    }
    let (mut lo, mut hi) = (t, t + 0.25);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if above(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}
