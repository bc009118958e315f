//! The up axis a tree is shown with ([`TreeMeta::up`]): the file's word when it gives
//! one ([`crate::io::model::Summary::up`]: LAS and LAZ z, a PLY comment), else the
//! model's shape's ([`up_of_shape`]). `spt render`, `view` and `bench` take `--up` to
//! override it; the viewer steps through the axes.

use glam::DVec3;

use super::TreeMeta;
use crate::io::Bounds;
use crate::io::up::UpAxis;
use crate::surfel::NormalsTurned;
use crate::surfel::cloud::Orientation;

/// The up axis of a model whose file gives none, from its leaf box, origin and how its
/// estimated normals were turned: `None` for a sensor frame (shown as its sensor saw
/// it, [`crate::render::camera::OrbitAxes::of`]); z for a terrain (normals turned up,
/// or a box less than a quarter as high in z as it is wide); y otherwise, as scanned
/// meshes and the PLY files of most tools are.
pub fn up_of_shape(
    normals_turned: NormalsTurned,
    leaf_box: &Bounds,
    origin: DVec3,
) -> Option<UpAxis> {
    match normals_turned {
        NormalsTurned::TowardOrigin => None,
        NormalsTurned::Up => Some(UpAxis::Z),
        NormalsTurned::No if Orientation::of(leaf_box, leaf_box, origin) == Orientation::Up => {
            Some(UpAxis::Z)
        }
        NormalsTurned::No => Some(UpAxis::Y),
    }
}

impl TreeMeta {
    /// [`up_of_shape`] of this tree.
    pub fn up_of_shape(&self) -> Option<UpAxis> {
        up_of_shape(self.normals_turned, &self.bounds, DVec3::from(self.origin))
    }

    /// The tree with `file_up` (the file's word) as its up axis when given, else its
    /// shape's.
    pub fn with_file_up(mut self, file_up: Option<UpAxis>) -> TreeMeta {
        self.up = file_up.or_else(|| self.up_of_shape());
        self
    }
}
