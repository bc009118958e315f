//! The covering ellipse's axes (the module doc's **axes**): the ring of nearest
//! neighbours in [`SECTORS`] angular sectors, taken in the metric of the previous
//! estimate, up to [`AXIS_ROUNDS`] times (until a ring repeats the one before).
//!
//! The offsets are held in columns ([`Columns`]) and each metric maps them all in one
//! pass of plain lane-wise arithmetic that the compiler turns into vector instructions
//! (x, y, squared length and sector of eight offsets at a time); only the choice of
//! each sector's nearest is a scalar pass. Each lane computes exactly what the scalar
//! map of one offset did, in the same order: the same ring, the same axes.

use glam::{DVec2, Vec2, Vec3};

use super::{AXIS_ROUNDS, MAX_NEIGHBOURS, MIN_RING, ROUND_ENOUGH, SECTORS};
use crate::surfel::shape::{Fit, MIN_RATIO};

const _: () = assert!(SECTORS == 6, "sector() splits by the lines at ±60°");

/// Offsets mapped per vector step: [`Columns::map`] runs over whole groups of these.
const LANES: usize = 8;
/// Groups of lanes held: [`MAX_NEIGHBOURS`] rounded up.
const GROUPS: usize = MAX_NEIGHBOURS.div_ceil(LANES);

/// One column: a value per lane, in groups.
type Column<T> = [[T; LANES]; GROUPS];

/// The ellipse's metric: offsets in (major, minor / ratio, normal) coordinates.
#[derive(Debug, Clone, Copy)]
pub(super) struct Metric {
    pub u: Vec3,
    pub v: Vec3,
    pub n: Vec3,
    pub ratio: f32,
}

impl Metric {
    pub fn circle(n: Vec3) -> Metric {
        let (u, v) = n.any_orthonormal_pair();
        Metric {
            u,
            v,
            n,
            ratio: 1.0,
        }
    }

    /// The unit tangent direction at `angle` in the metric's plane coordinates.
    pub fn direction(&self, angle: f32) -> Vec3 {
        (self.u * angle.cos() + self.v * (self.ratio * angle.sin())).normalize_or(self.u)
    }
}

/// A neighbourhood's offsets (at most [`MAX_NEIGHBOURS`]) in columns, zero past the
/// last.
pub(super) struct Columns {
    x: Column<f32>,
    y: Column<f32>,
    z: Column<f32>,
    len: usize,
}

/// The offsets as a metric sees them, in columns: plane coordinates (the minor one
/// stretched by 1 / ratio), squared metric length and sector ([`sector`]).
pub(super) struct Mapped {
    x: Column<f32>,
    y: Column<f32>,
    d2: Column<f32>,
    sector: Column<u32>,
    pub len: usize,
}

impl Columns {
    pub fn of(offsets: &[Vec3]) -> Columns {
        let mut columns = Columns {
            x: [[0.0; LANES]; GROUPS],
            y: [[0.0; LANES]; GROUPS],
            z: [[0.0; LANES]; GROUPS],
            len: offsets.len().min(MAX_NEIGHBOURS),
        };
        for (k, o) in offsets.iter().take(MAX_NEIGHBOURS).enumerate() {
            let (g, l) = (k / LANES, k % LANES);
            (columns.x[g][l], columns.y[g][l], columns.z[g][l]) = (o.x, o.y, o.z);
        }
        columns
    }

    /// Every offset o in the metric `m`: (o·u, o·v / ratio), and its squared length
    /// (o·u)² + (o·v / ratio)² + (o·n)², each dot product summed x, y, z in turn.
    pub fn map(&self, m: &Metric) -> Mapped {
        let mut out = Mapped {
            x: [[0.0; LANES]; GROUPS],
            y: [[0.0; LANES]; GROUPS],
            d2: [[0.0; LANES]; GROUPS],
            sector: [[0; LANES]; GROUPS],
            len: self.len,
        };
        let groups = self.len.div_ceil(LANES);
        let columns = self.x.iter().zip(&self.y).zip(&self.z).take(groups);
        for (g, ((xs, ys), zs)) in columns.enumerate() {
            let dot = |w: Vec3, l: usize| xs[l] * w.x + ys[l] * w.y + zs[l] * w.z;
            let x: [f32; LANES] = std::array::from_fn(|l| dot(m.u, l));
            let y: [f32; LANES] = std::array::from_fn(|l| dot(m.v, l) / m.ratio);
            let z: [f32; LANES] = std::array::from_fn(|l| dot(m.n, l));
            out.d2[g] = std::array::from_fn(|l| x[l] * x[l] + y[l] * y[l] + z[l] * z[l]);
            out.sector[g] = std::array::from_fn(|l| sector(x[l], y[l]));
            (out.x[g], out.y[g]) = (x, y);
        }
        out
    }
}

impl Mapped {
    /// Offset `k`'s squared metric length and plane coordinates.
    pub fn get(&self, k: usize) -> (f32, Vec2) {
        let (g, l) = (k / LANES, k % LANES);
        (self.d2[g][l], Vec2::new(self.x[g][l], self.y[g][l]))
    }

    /// Each sector's nearest offset (the first of equals), by index.
    ///
    /// In lane-wise integer minima, without a branch on the lengths (one per offset
    /// was mispredicted about 16 times a point): a squared length's bits order as it
    /// does, and an offset outside the sector (or past the last) counts as the largest
    /// integer. The sector's least key is its nearest's; the least index among the
    /// offsets at that key, its first.
    fn ring(&self) -> [Option<usize>; SECTORS] {
        let groups = self.len.div_ceil(LANES);
        // Lane l of group g's key in sector s; all ones outside it.
        let key = |g: usize, l: usize, s: usize| {
            let out = (self.sector[g][l] != s as u32) | (LANE_INDEX[g][l] >= self.len as u32);
            self.d2[g][l].to_bits() | u32::from(out).wrapping_neg()
        };
        let mut lanes = [[u32::MAX; LANES]; SECTORS];
        for g in 0..groups {
            for (s, least) in lanes.iter_mut().enumerate() {
                for (l, least) in least.iter_mut().enumerate() {
                    *least = (*least).min(key(g, l, s));
                }
            }
        }
        let least = lanes.map(|lanes| lanes.into_iter().fold(u32::MAX, u32::min));
        let mut lanes = [[u32::MAX; LANES]; SECTORS];
        for (g, index) in LANE_INDEX.iter().enumerate().take(groups) {
            for (s, first) in lanes.iter_mut().enumerate() {
                for (l, first) in first.iter_mut().enumerate() {
                    let other = u32::from(key(g, l, s) != least[s]).wrapping_neg();
                    *first = (*first).min(index[l] | other);
                }
            }
        }
        let first = lanes.map(|lanes| lanes.into_iter().fold(u32::MAX, u32::min));
        std::array::from_fn(|s| (least[s] != u32::MAX).then_some(first[s] as usize))
    }
}

/// Each lane's offset index.
const LANE_INDEX: Column<u32> = {
    let mut index = [[0; LANES]; GROUPS];
    let mut k = 0;
    while k < LANES * GROUPS {
        index[k / LANES][k % LANES] = k as u32;
        k += 1;
    }
    index
};

/// The ellipse's axes from at most [`AXIS_ROUNDS`] rings of `offsets` (their
/// `columns`), starting from `circle`; a ring found round ([`ROUND_ENOUGH`]) or
/// spanning no plane ends the search.
///
/// So does a ring whose members are those of the ring before: its second moment is
/// the same sum, so its axes are the metric it was found in (a fixed point, up to the
/// rounding of another tangent frame), and every later round would find it again. On
/// the Lucy-size cloud the second ring is the first's for 94.5 % of the points.
/// Returns the axes and the offsets mapped by them (most often the last round's map).
pub(super) fn axes(offsets: &[Vec3], columns: &Columns, circle: Metric) -> (Metric, Mapped) {
    let mut m = circle;
    let mut last_members = None;
    for round in 0..AXIS_ROUNDS {
        let mapped = columns.map(&m);
        let ring = mapped.ring();
        let members = Some(members(&ring));
        if members == last_members {
            return (m, mapped);
        }
        last_members = members;
        match ring_axes(offsets, &ring, m) {
            Some(next) if next.ratio < ROUND_ENOUGH => m = next,
            // The first round's map is the circle's.
            Some(_) if round == 0 => return (circle, mapped),
            Some(_) => return (circle, columns.map(&circle)),
            None => return (m, mapped),
        }
    }
    (m, columns.map(&m))
}

/// The ring's members as a set: bit k for offset k.
fn members(ring: &[Option<usize>; SECTORS]) -> u64 {
    const _: () = assert!(MAX_NEIGHBOURS <= 64, "one bit per offset");
    ring.iter().flatten().fold(0, |set, &k| set | 1 << k)
}

/// The axes of `ring` (each sector's nearest of `offsets`, found in the metric `m`;
/// module doc); `None` when the ring spans no plane or fills fewer than [`MIN_RING`]
/// sectors.
fn ring_axes(offsets: &[Vec3], ring: &[Option<usize>; SECTORS], m: Metric) -> Option<Metric> {
    let (t1, t2) = (m.u, m.n.cross(m.u));
    let mut fit = Fit::default();
    for &k in ring.iter().flatten() {
        let o = offsets[k];
        let d = DVec2::new(o.dot(t1) as f64, o.dot(t2) as f64);
        fit.add(d, DVec2::ZERO);
    }
    let (dir, l1, l2) = fit.axes();
    if l1 <= 0.0 || l2 <= 0.0 || ring.iter().flatten().count() < MIN_RING {
        return None;
    }
    let u = (t1 * dir.x as f32 + t2 * dir.y as f32).normalize_or(t1);
    Some(Metric {
        u,
        v: m.n.cross(u),
        n: m.n,
        ratio: ((l2 / l1).sqrt() as f32).clamp(MIN_RATIO as f32, 1.0),
    })
}

/// Which of the [`SECTORS`] = 6 sectors of 60° around the origin holds (x, y): 0–2
/// above the x axis counter-clockwise from it, 3–5 below, by the lines at ±60° (y = ±√3
/// x). Without branches: |y| < √3 x is sector 0 of its half, |y| < −√3 x the 2nd, any
/// other the 1st.
fn sector(x: f32, y: f32) -> u32 {
    let s = 3f32.sqrt() * x;
    let ay = y.abs();
    let past_first = 1 - (ay < s) as u32;
    let side = past_first * (1 + (ay < -s) as u32);
    side + 3 * (1 - (y >= 0.0) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sectors_are_sixty_degrees_wide() {
        for k in 0..360 {
            let t = (k as f32 + 0.5).to_radians();
            let expected = if k < 180 {
                k / 60
            } else {
                3 + (360 - k - 1) / 60
            };
            assert_eq!(sector(t.cos(), t.sin()), expected, "{k}°");
        }
    }

    #[test]
    fn the_ring_is_each_sectors_first_nearest() {
        // Offsets on a few rings of equal lengths (ties within and across sectors), in
        // every count of lanes: the branch-free choice is the scalar one's.
        let offsets: Vec<Vec3> = (0..MAX_NEIGHBOURS)
            .map(|k| {
                let t = (k * 7 % 12) as f32 * std::f32::consts::TAU / 12.0;
                Vec3::new(t.cos(), t.sin(), 0.0) * (1 + k % 3) as f32
            })
            .collect();
        for len in 0..=MAX_NEIGHBOURS {
            let mapped = Columns::of(&offsets[..len]).map(&Metric::circle(Vec3::Z));
            let mut expected = [None::<usize>; SECTORS];
            for k in 0..len {
                let (d2, xy) = mapped.get(k);
                let s = sector(xy.x, xy.y) as usize;
                if expected[s].is_none_or(|j| d2 < mapped.get(j).0) {
                    expected[s] = Some(k);
                }
            }
            assert_eq!(mapped.ring(), expected, "{len} offsets");
        }
    }

    #[test]
    fn the_column_map_is_the_scalar_one() {
        // Offsets of every direction and size, mapped by tilted, stretched metrics:
        // each lane equals the map of one offset, bit for bit.
        let offsets: Vec<Vec3> = (0..MAX_NEIGHBOURS)
            .map(|k| {
                let t = k as f32 * 0.7;
                Vec3::new(t.cos(), t.sin(), 0.1 * (3.0 * t).sin()) * (1.0 + k as f32 * 0.37)
            })
            .collect();
        let n = Vec3::new(0.2, -0.3, 0.9).normalize();
        for (len, ratio) in [(1, 1.0), (7, 0.8), (23, 0.31), (MAX_NEIGHBOURS, 0.05)] {
            let m = Metric {
                ratio,
                ..Metric::circle(n)
            };
            let mapped = Columns::of(&offsets[..len]).map(&m);
            for (k, o) in offsets[..len].iter().enumerate() {
                let xy = Vec2::new(o.dot(m.u), o.dot(m.v) / m.ratio);
                let d2 = xy.length_squared() + o.dot(m.n).powi(2);
                assert_eq!(mapped.get(k), (d2, xy));
            }
        }
    }
}
