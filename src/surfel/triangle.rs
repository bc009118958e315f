//! One triangle's terms, shared by the mesh rule and the splats of its ring and of long
//! triangles: its cross product, covering radius and whether it is degenerate (docs/design.md
//! §2), computed in f64, and the margin that keeps f32 radii covering.

use glam::DVec3;

/// Relative growth of every radius, above f32 rounding (2⁻²⁴).
pub const RADIUS_MARGIN: f64 = 1e-6;
/// A triangle is degenerate when |(b−a)×(c−a)| ≤ DEGENERATE · L², L its longest edge:
/// its smallest angle is below about 10⁻⁶ rad, below what f32 positions resolve.
pub const DEGENERATE: f64 = 1e-6;
/// Cross product (b − a) × (c − a), covering radius and degeneracy of one triangle,
/// in f64. With squared edge lengths l₀ l₁ l₂ and L² their maximum: acute iff
/// l₀ + l₁ + l₂ > 2 L² (a² + b² > c² for the longest edge c), and then
/// R² = l₀ l₁ l₂ / (4 |cross|²); otherwise R = L / 2.
#[inline]
pub fn triangle_terms(a: DVec3, b: DVec3, c: DVec3) -> (DVec3, f64, bool) {
    let (ab, bc, ca) = (b - a, c - b, a - c);
    let cross = ab.cross(-ca);
    let l = [
        ab.length_squared(),
        bc.length_squared(),
        ca.length_squared(),
    ];
    let longest = l[0].max(l[1]).max(l[2]);
    let cross2 = cross.length_squared();
    let degenerate = cross2 <= (DEGENERATE * longest).powi(2);
    let acute = !degenerate && l[0] + l[1] + l[2] > 2.0 * longest;
    let radius = if acute {
        (l[0] * l[1] * l[2] / (4.0 * cross2)).sqrt()
    } else {
        0.5 * longest.sqrt()
    };
    (cross, radius, degenerate)
}
