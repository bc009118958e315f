//! PLY as one of the engine's formats ([`crate::io::format`]): the whole file
//! ([`super::read_ply`]) or a window of rows at a time ([`PlyStream`]).

use std::path::Path;

use super::fields::Plan;
use super::{Header, PlyStream, read_ply_telling};
use crate::io::format::PointBatch;
use crate::io::format::{Format, PointStream, Told};
use crate::io::model::{ElementSummary, Model, ModelError, Summary};
use crate::io::up::UpAxis;

/// Stanford PLY: ASCII and binary in either byte order.
pub struct PlyFormat;

impl Format for PlyFormat {
    fn recognises(&self, head: &[u8]) -> bool {
        head.starts_with(b"ply")
    }

    fn read(&self, path: &Path, told: Told) -> Result<Model, ModelError> {
        let m = read_ply_telling(path, told)?;
        Ok(Model {
            summary: summary(&m.header),
            geometry: m.geometry,
            stats: m.stats,
            file_bytes: m.file_bytes,
            load_time: m.load_time,
        })
    }

    fn stream(&self, path: &Path) -> Result<Box<dyn PointStream>, ModelError> {
        Ok(Box::new(PlyStream::open(path)?))
    }
}

/// What a PLY header says: encoding and version, comments, elements, and the elements
/// the reader skips.
fn summary(h: &Header) -> Summary {
    Summary {
        format: format!("PLY {} {}", h.encoding.name(), h.version),
        comments: h.comments.clone(),
        obj_info: h.obj_info.clone(),
        elements: h
            .elements
            .iter()
            .map(|e| ElementSummary {
                name: e.name.clone(),
                count: e.count,
                properties: e.properties.iter().map(|p| p.declaration()).collect(),
            })
            .collect(),
        skipped_elements: skipped_elements(h),
        las: None,
        up: UpAxis::from_comments(h.comments.iter().chain(&h.obj_info)),
    }
}

/// The elements the reader skips: neither the vertices nor the faces or strips it reads.
fn skipped_elements(h: &Header) -> Vec<String> {
    let Ok(plan) = Plan::new(h) else {
        return Vec::new();
    };
    let used = [Some(plan.vertex_element), plan.faces.map(|(f, _)| f)];
    h.elements
        .iter()
        .enumerate()
        .filter(|(i, _)| !used.contains(&Some(*i)))
        .map(|(_, e)| e.name.clone())
        .collect()
}

/// A PLY file's vertex rows as points (8-bit colours widened), its faces as triangles.
impl PointStream for PlyStream {
    fn point_count(&self) -> u64 {
        self.vertex_count()
    }

    fn has_faces(&self) -> bool {
        PlyStream::has_faces(self)
    }

    fn has_normals(&self) -> bool {
        PlyStream::has_normals(self)
    }

    fn has_attributes(&self) -> bool {
        false
    }

    fn up(&self) -> Option<UpAxis> {
        let h = self.header();
        UpAxis::from_comments(h.comments.iter().chain(&h.obj_info))
    }

    fn points(&self, f: &mut dyn FnMut(&PointBatch)) -> Result<(), ModelError> {
        let mut batch = PointBatch::default();
        self.vertices(|v| {
            batch.clear();
            batch.xyz.extend_from_slice(&v.xyz);
            batch.normals.extend_from_slice(&v.normals);
            batch
                .rgb
                .extend(v.colors.iter().map(|c| [c[0], c[1], c[2]].map(u16::from)));
            f(&batch);
        })?;
        Ok(())
    }

    fn triangles(&self, f: &mut dyn FnMut(&[[u32; 3]])) -> Result<(), ModelError> {
        PlyStream::triangles(self, f)?;
        Ok(())
    }
}
