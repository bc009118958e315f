//! PLY files whose faces are triangle strips (`element tristrips`, one list of vertex
//! indices per row with −1 restarting a strip, as the Stanford and Cyberware archives
//! write them) load with their triangles, all wound alike; `spt info` says so and names
//! the elements it skips.

use crate::common;

use glam::Vec3;
use spt::io::ply::read_ply;

/// A 4 × 2 grid of vertices in z = 0 (row 0: 0–3, row 1: 4–7) as two strips in one row
/// of the element, joined by −1: [0 4 1 5] and [1 5 2 6 3 7] (2 + 4 triangles); a
/// `camera` element the reader skips.
const HEADER: &str = "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
                      element tristrips 1\nproperty list int int vertex_indices\n\
                      element camera 1\nproperty float view_px\nend_header\n";
const STRIP: [i32; 11] = [0, 4, 1, 5, -1, 1, 5, 2, 6, 3, 7];

fn vertex(i: usize) -> [f32; 3] {
    [(i % 4) as f32, (i / 4) as f32, 0.0]
}

fn ascii() -> Vec<u8> {
    let mut s = format!("ply\nformat ascii 1.0\n{HEADER}");
    for i in 0..8 {
        let [x, y, z] = vertex(i);
        s += &format!("{x} {y} {z}\n");
    }
    let list: Vec<String> = STRIP.iter().map(|i| i.to_string()).collect();
    s += &format!("{} {}\n0.5\n", STRIP.len(), list.join(" "));
    s.into_bytes()
}

fn binary() -> Vec<u8> {
    let mut b = format!("ply\nformat binary_little_endian 1.0\n{HEADER}").into_bytes();
    for i in 0..8 {
        b.extend(vertex(i).iter().flat_map(|v| v.to_le_bytes()));
    }
    b.extend((STRIP.len() as i32).to_le_bytes());
    b.extend(STRIP.iter().flat_map(|i| i.to_le_bytes()));
    b.extend(0.5f32.to_le_bytes());
    b
}

#[test]
fn strips_become_triangles_wound_alike() {
    let dir = common::temp_dir();
    for (name, bytes) in [("strips_ascii.ply", ascii()), ("strips_le.ply", binary())] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let model = read_ply(&path).unwrap();
        let g = &model.geometry;
        assert_eq!(g.triangles.len(), 6, "{name}");
        assert_eq!(model.stats.triangle_strips, 1, "{name}");
        let p = |i: u32| g.positions[i as usize];
        let first = (p(g.triangles[0][1]) - p(g.triangles[0][0]))
            .cross(p(g.triangles[0][2]) - p(g.triangles[0][0]));
        for t in &g.triangles {
            let n: Vec3 = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            assert!(n.dot(first) > 0.0, "{name}: {t:?} wound the other way");
        }
        let (code, text, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
        assert_eq!(code, Some(0), "{name}: {stderr}");
        assert!(
            text.contains("1 rows of triangle strips (tristrips) read → 6 triangles"),
            "{text}"
        );
        assert!(text.contains("skipped       elements camera"), "{text}");
    }
}
