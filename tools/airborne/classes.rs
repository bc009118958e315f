//! The parts of the simulated scene by ASPRS class, and the colour each is drawn in:
//! the truth mesh and the returns share it, so that a render tells them apart.

/// What a part is, as the ASPRS class its returns get.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Ground = 2,
    Vegetation = 5,
    Building = 6,
    /// A bridge deck and its pillars (ASPRS 17).
    Bridge = 17,
}

/// The open space under the crowns, the bridge's deck and the carport's roof, and the
/// colour each fills in the truth mesh of regions: where what the truth shows through
/// must stay visible.
pub const UNDER: [(&str, [u8; 3]); 3] = [
    ("crowns", [200, 40, 200]),
    ("the deck", [30, 210, 210]),
    ("the carport", [180, 200, 0]),
];

impl Kind {
    pub const ALL: [Kind; 4] = [Kind::Ground, Kind::Vegetation, Kind::Building, Kind::Bridge];

    /// The colour the truth mesh and the returns share: hues apart, and none grey (a
    /// specular highlight greys what it lights).
    pub fn color(self) -> [u8; 3] {
        match self {
            Kind::Ground => [150, 130, 95],
            Kind::Vegetation => [70, 140, 60],
            Kind::Building => [200, 50, 50],
            Kind::Bridge => [90, 110, 175],
        }
    }
}
