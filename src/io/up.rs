//! Which way is up in a model's coordinates. Scanned meshes (the Stanford models,
//! photogrammetry, most PLY samples) are y-up; LiDAR (LAS, LAZ) and terrain are z-up.
//! A file says so itself when it can: LAS and LAZ always (z), a PLY header through a
//! comment such as `comment up_axis z`, `comment z-up` or `comment Up: -Y`
//! ([`UpAxis::from_comments`]). The tree builder decides the rest from the model's
//! shape (docs/how-it-works.md, "Up axis").

use glam::DVec3;
use serde::Serialize;

/// A signed coordinate axis taken as up (serialized by its [`UpAxis::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
pub enum UpAxis {
    #[serde(rename = "x")]
    X,
    #[serde(rename = "y")]
    Y,
    #[serde(rename = "z")]
    Z,
    #[serde(rename = "-x")]
    NegX,
    #[serde(rename = "-y")]
    NegY,
    #[serde(rename = "-z")]
    NegZ,
}

impl UpAxis {
    /// Every axis, in the order the viewer's key steps through them.
    pub const ALL: [UpAxis; 6] = [
        UpAxis::Z,
        UpAxis::Y,
        UpAxis::X,
        UpAxis::NegZ,
        UpAxis::NegY,
        UpAxis::NegX,
    ];

    /// `x`, `-z`…: what `--up` takes and `spt info` prints.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::X => "x",
            UpAxis::Y => "y",
            UpAxis::Z => "z",
            UpAxis::NegX => "-x",
            UpAxis::NegY => "-y",
            UpAxis::NegZ => "-z",
        }
    }

    /// The axis named `s` (`x`, `+y`, `-Z`…).
    pub fn parse(s: &str) -> Option<UpAxis> {
        let s = s.trim().to_ascii_lowercase();
        let (negative, axis) = match s.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, s.strip_prefix('+').unwrap_or(&s)),
        };
        let k = ["x", "y", "z"].iter().position(|a| *a == axis)?;
        Some(UpAxis::ALL[[2, 1, 0][k] + if negative { 3 } else { 0 }])
    }

    /// The unit vector of the axis.
    pub fn vector(self) -> DVec3 {
        match self {
            UpAxis::X => DVec3::X,
            UpAxis::Y => DVec3::Y,
            UpAxis::Z => DVec3::Z,
            UpAxis::NegX => DVec3::NEG_X,
            UpAxis::NegY => DVec3::NEG_Y,
            UpAxis::NegZ => DVec3::NEG_Z,
        }
    }

    /// The next axis of [`UpAxis::ALL`], round.
    pub fn next(self) -> UpAxis {
        let k = UpAxis::ALL.iter().position(|a| *a == self).unwrap_or(0);
        UpAxis::ALL[(k + 1) % UpAxis::ALL.len()]
    }

    /// The axis a header's comments name, the first that names one: a comment whose
    /// words (split at blanks, `:`, `=` and `_`) hold `up` beside an axis (`up_axis z`,
    /// `up: -y`, `z-up`, `Y_UP`, `up is +z`). A comment that names no axis beside `up`
    /// says nothing.
    pub fn from_comments<'a>(comments: impl IntoIterator<Item = &'a String>) -> Option<UpAxis> {
        comments.into_iter().find_map(|c| {
            let lower = c.to_ascii_lowercase();
            let words: Vec<&str> = lower
                .split(|ch: char| ch.is_whitespace() || ":=_,;".contains(ch))
                .filter(|w| !w.is_empty())
                .collect();
            words.iter().enumerate().find_map(|(k, w)| {
                // `z-up`, `-y-up`: one word.
                if let Some(axis) = w.strip_suffix("-up") {
                    return UpAxis::parse(axis);
                }
                if *w != "up" {
                    return None;
                }
                let after = words[k + 1..]
                    .iter()
                    .filter(|w| !["axis", "is", "vector", "direction"].contains(w));
                let before = words[..k].iter().rev().take(1);
                after.take(1).chain(before).find_map(|w| UpAxis::parse(w))
            })
        })
    }

    /// The axis's code in an `.spt` header's flags (1–6; 0 is none).
    pub fn code(self) -> u32 {
        UpAxis::ALL.iter().position(|a| *a == self).unwrap_or(0) as u32 + 1
    }

    /// The axis of `code` ([`UpAxis::code`]); `None` for 0 or a code no axis has.
    pub fn from_code(code: u32) -> Option<UpAxis> {
        UpAxis::ALL.get((code as usize).checked_sub(1)?).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_codes_round_trip() {
        for a in UpAxis::ALL {
            assert_eq!(UpAxis::parse(a.name()), Some(a));
            assert_eq!(UpAxis::from_code(a.code()), Some(a));
            assert_eq!(a.vector().length(), 1.0);
        }
        assert_eq!(UpAxis::parse("+Y"), Some(UpAxis::Y));
        assert_eq!(UpAxis::parse("w"), None);
        assert_eq!(UpAxis::from_code(0), None);
        assert_eq!(UpAxis::from_code(7), None);
    }

    #[test]
    fn comments_that_name_an_up_axis_are_read() {
        let says = |c: &str| UpAxis::from_comments(&[c.to_owned()]);
        assert_eq!(says("up_axis z"), Some(UpAxis::Z));
        assert_eq!(says("Up: -Y"), Some(UpAxis::NegY));
        assert_eq!(says("exported Z-up from Blender"), Some(UpAxis::Z));
        assert_eq!(says("Y_UP"), Some(UpAxis::Y));
        assert_eq!(says("up is +x"), Some(UpAxis::X));
        assert_eq!(says("made by Greg Turk"), None);
        assert_eq!(says("picked up 3 scans"), None);
        assert_eq!(says("zipper output"), None);
    }
}
