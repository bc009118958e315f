//! LiDAR attributes of internal nodes (docs/design.md §3's aggregation, for what a LAS point
//! carries): each child weighs by the area of its splat, π r² · ratio (r the major
//! semi-axis), so that a node shows what covers most of the surface it stands for.
//!
//! * class: the class whose children cover the largest area (ties: the lower code);
//! * intensity: the area-weighted mean, rounded;
//! * returns: those of the child of largest area.

use crate::io::PointAttributes;

/// The attributes of a node whose children have `children` (attributes, splat area).
pub fn parent_attributes(children: &[(PointAttributes, f64)]) -> PointAttributes {
    let total: f64 = children.iter().map(|(_, a)| a).sum();
    let mut by_class: [(u8, f64); 4] = [(0, 0.0); 4];
    let mut classes = 0;
    for (attr, area) in children {
        match by_class[..classes]
            .iter_mut()
            .find(|(c, _)| *c == attr.class)
        {
            Some(slot) => slot.1 += area,
            None => {
                by_class[classes] = (attr.class, *area);
                classes += 1;
            }
        }
    }
    let class = by_class[..classes]
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
        .map_or(0, |(c, _)| *c);
    let intensity = if total > 0.0 {
        let sum: f64 = children.iter().map(|(a, w)| a.intensity as f64 * w).sum();
        (sum / total).round().clamp(0.0, u16::MAX as f64) as u16
    } else {
        children.first().map_or(0, |(a, _)| a.intensity)
    };
    let largest = children
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(a, _)| a.returns);
    PointAttributes {
        intensity,
        class,
        returns: largest,
    }
}

/// The 1st and 99th percentiles of the intensities of `leaves` (what the intensity mode
/// draws black and white, robust to a few stray returns); [0, 0] for none.
pub fn intensity_range(leaves: &[PointAttributes]) -> [u16; 2] {
    let mut histogram = vec![0u64; 1 << 16];
    for a in leaves {
        histogram[a.intensity as usize] += 1;
    }
    let n = leaves.len() as u64;
    let at = |rank: u64| {
        let mut seen = 0;
        for (value, count) in histogram.iter().enumerate() {
            seen += count;
            if seen > rank {
                return value as u16;
            }
        }
        0
    };
    if n == 0 {
        [0, 0]
    } else {
        [at(n / 100), at(n - 1 - n / 100)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_intensity_range_leaves_out_a_few_strays() {
        let mut leaves: Vec<PointAttributes> = (0..1000)
            .map(|i| PointAttributes::new(100 + (i % 200) as u16, 1, 1, 1))
            .collect();
        leaves.extend((0..5).map(|_| PointAttributes::new(65535, 1, 1, 1)));
        let [lo, hi] = intensity_range(&leaves);
        assert!(
            (100..110).contains(&lo) && (290..300).contains(&hi),
            "{lo} {hi}"
        );
    }

    #[test]
    fn the_class_of_most_area_wins_and_intensity_is_the_area_mean() {
        let ground = PointAttributes::new(100, 2, 1, 1);
        let tree = PointAttributes::new(300, 5, 2, 3);
        // Two small ground splats against one large vegetation splat.
        let p = parent_attributes(&[(ground, 1.0), (ground, 1.0), (tree, 3.0)]);
        assert_eq!(p.class, 5);
        assert_eq!(p.intensity, 220);
        assert_eq!((p.return_number(), p.number_of_returns()), (2, 3));
        let p = parent_attributes(&[(ground, 2.0), (ground, 2.0), (tree, 3.0)]);
        assert_eq!(p.class, 2);
    }
}
