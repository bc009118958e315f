//! Numbers as the commands print them.

/// 1234567 → "1,234,567".
pub fn count(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// How many of a model's leaves are no sample of its file (a terrain's walls, long
/// triangles' splats: `SurfelStats::added_splats`), as a clause to append: ", 1,234
/// splats of walls and long triangles" ("" where there are none).
pub fn walls(n: u64) -> String {
    match n {
        0 => String::new(),
        n => format!(", {} splats of walls and long triangles", count(n)),
    }
}

/// A byte count in B, KiB, MiB or GiB.
pub fn bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 30 => format!("{:.2} GiB", n as f64 / (1u64 << 30) as f64),
        n if n >= 1 << 20 => format!("{:.1} MiB", n as f64 / (1u64 << 20) as f64),
        n if n >= 1 << 10 => format!("{:.1} KiB", n as f64 / 1024.0),
        n => format!("{n} B"),
    }
}

/// The shortest decimal that reads back to the same double (`{}`), in scientific
/// notation (`{:e}`, also shortest) when the plain form is longer than 24 characters:
/// 1e300 is printed as such, not as 301 digits.
pub fn readable(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 24 {
        plain
    } else {
        format!("{x:e}")
    }
}
