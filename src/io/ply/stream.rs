//! A PLY file read a window of rows at a time, for builders that never hold a whole
//! file ([`crate::tree::out_of_core`]).
//!
//! The header, the plan and every check are [`super::read_ply`]'s, but the file is
//! mapped without being read in, its rows are decoded [`WINDOW`] at a time, and each
//! window's pages are handed back to the kernel once decoded (`MADV_DONTNEED` on a
//! read-only map: they stay in the page cache, outside the process). The resident
//! memory is so a window's, whatever the size of the file. Any encoding, any layout
//! [`super::read_ply`] reads: fixed-size binary vertex rows are read in place, other
//! rows walked one by one.

use std::path::{Path, PathBuf};

use glam::Vec3;
use memmap2::{Advice, Mmap, UncheckedAdvice};

use super::PlyError;
use super::ascii::Tokens;
use super::binary::{truncated, walk_row};
use super::error::Problem;
use super::faces::Faces;
use super::fields::{Plan, fixed_rows};
use super::header::{self, Element, Encoding, Header, PropertyKind};
use crate::io::geometry::{row_color, row_normal};
use crate::io::rows::{ColumnRows, VertexRows};

/// Rows decoded per window.
pub const WINDOW: usize = 1 << 16;

/// One window of vertex rows, in file order.
#[derive(Debug, Default, Clone)]
pub struct VertexBatch {
    /// Positions as the file gives them.
    pub xyz: Vec<[f64; 3]>,
    /// Unit normals, zero where the file's is zero or not finite; empty when the file
    /// has none.
    pub normals: Vec<Vec3>,
    /// RGBA8 colours, converted as the whole-file reader converts them; empty when
    /// the file has none.
    pub colors: Vec<[u8; 4]>,
}

impl VertexBatch {
    fn clear(&mut self) {
        self.xyz.clear();
        self.normals.clear();
        self.colors.clear();
    }

    fn extend<R: VertexRows>(&mut self, rows: &R, plan: &Plan) {
        let fields = &plan.vertex_fields;
        for i in 0..rows.len() {
            let [x, y, z] = rows.position(i);
            self.xyz.push([x, y, if fields.z_absent { 0.0 } else { z }]);
            if fields.has_normals {
                self.normals.push(row_normal(rows, i));
            }
            if fields.color_channels > 0 {
                self.colors.push(row_color(rows, fields, i));
            }
        }
    }
}

/// A PLY file open for reading a window at a time.
pub struct PlyStream {
    path: PathBuf,
    map: Mmap,
    header: Header,
    plan: Plan,
    window: usize,
}

/// Where a walk through the payload stands: a byte offset (binary) or a token
/// stream (ASCII).
enum Cursor<'a> {
    Binary {
        data: &'a [u8],
        pos: usize,
        big: bool,
    },
    Ascii(Tokens<'a>),
}

impl Cursor<'_> {
    /// The offset in the payload of the next byte to read.
    fn pos(&self) -> usize {
        match self {
            Cursor::Binary { pos, .. } => *pos,
            Cursor::Ascii(t) => t.pos,
        }
    }

    /// Reads row `row` of `e`; `visit(property, values)` sees each property's values.
    fn row(
        &mut self,
        e: &Element,
        row: u64,
        values: &mut Vec<f64>,
        mut visit: impl FnMut(usize, &[f64]) -> Result<(), Problem>,
    ) -> Result<(), Problem> {
        match self {
            Cursor::Ascii(t) => t.row(e, row, values, visit),
            Cursor::Binary { data, pos, big } => {
                let big = *big;
                *pos = walk_row(data, *pos, e, row, big, |pi, b, n| {
                    values.clear();
                    match (e.properties[pi].kind, n) {
                        (PropertyKind::List { item, .. }, Some(n)) => {
                            values.extend((0..n).map(|k| item.read(&b[k * item.size()..], big)))
                        }
                        (PropertyKind::Scalar(s), _) => values.push(s.read(b, big)),
                        (PropertyKind::List { .. }, None) => {}
                    }
                    visit(pi, values)
                })?;
                Ok(())
            }
        }
    }

    /// The next `rows` rows of `e` when they are binary and of a fixed size.
    fn fixed_rows(
        &mut self,
        e: &Element,
        first: u64,
        rows: usize,
    ) -> Option<Result<&[u8], Problem>> {
        let Cursor::Binary { data, pos, .. } = self else {
            return None;
        };
        let stride = e.fixed_row_size()?;
        let start = *pos;
        let end = rows
            .checked_mul(stride)
            .and_then(|n| n.checked_add(start))
            .filter(|&end| end <= data.len());
        Some(match end {
            Some(end) => {
                *pos = end;
                Ok(&data[start..end])
            }
            None => Err(truncated(
                e,
                first + ((data.len() - start) / stride.max(1)) as u64,
            )),
        })
    }

    /// Skips every row of `e`.
    fn skip(&mut self, e: &Element) -> Result<(), Problem> {
        if e.properties.is_empty() {
            return Ok(());
        }
        if e.count <= usize::MAX as u64
            && let Some(rows) = self.fixed_rows(e, 0, e.count as usize)
        {
            return rows.map(|_| ());
        }
        let mut values = Vec::new();
        for row in 0..e.count {
            self.row(e, row, &mut values, |_, _| Ok(()))?;
        }
        Ok(())
    }
}

impl PlyStream {
    /// Opens `path` and reads its header; errors name the file.
    pub fn open(path: &Path) -> Result<PlyStream, PlyError> {
        let io_err = |e: std::io::Error| Problem::file(format!("cannot read: {e}")).in_file(path);
        let file = std::fs::File::open(path).map_err(io_err)?;
        if file.metadata().map_err(io_err)?.len() == 0 {
            return Err(Problem::file("the file is empty").in_file(path));
        }
        // SAFETY: the map is only read; a file that another process truncates
        // meanwhile is outside what a reader can guard against.
        let map = unsafe { Mmap::map(&file) }.map_err(io_err)?;
        // Readahead: windows are read in order.
        let _ = map.advise(Advice::Sequential);
        let header = header::parse_header(&map).map_err(|p| p.in_file(path))?;
        let plan = Plan::new(&header).map_err(|p| p.in_file(path))?;
        Ok(PlyStream {
            path: path.to_owned(),
            map,
            header,
            plan,
            window: WINDOW,
        })
    }

    /// Decodes `rows` rows per window instead of [`WINDOW`].
    pub fn with_window(mut self, rows: usize) -> Self {
        self.window = rows.max(1);
        self
    }

    /// The file's header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    pub fn vertex_count(&self) -> u64 {
        self.header.elements[self.plan.vertex_element].count
    }

    /// Whether the file declares faces (or strips) with rows.
    pub fn has_faces(&self) -> bool {
        self.plan
            .faces
            .is_some_and(|(f, _)| self.header.elements[f].count > 0)
    }

    pub fn has_normals(&self) -> bool {
        self.plan.vertex_fields.has_normals
    }

    fn cursor(&self) -> Cursor<'_> {
        let data = &self.map[self.header.payload_offset..];
        match self.header.encoding {
            Encoding::Ascii => {
                let line = self.map[..self.header.payload_offset]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count()
                    + 1;
                Cursor::Ascii(Tokens { data, pos: 0, line })
            }
            e => Cursor::Binary {
                data,
                pos: 0,
                big: e == Encoding::BinaryBigEndian,
            },
        }
    }

    /// Hands the pages of the payload's bytes `from..to` back to the kernel.
    fn release(&self, from: usize, to: usize) {
        let at = self.header.payload_offset + from;
        // SAFETY: the map is read-only and file-backed, so its dropped pages read
        // back the same bytes from the file if touched again; no reference into them
        // outlives the window that was decoded from them.
        let _ = unsafe {
            self.map
                .unchecked_advise_range(UncheckedAdvice::DontNeed, at, to.saturating_sub(from))
        };
    }

    /// A cursor at the first row of element `target`.
    fn cursor_at(&self, target: usize) -> Result<Cursor<'_>, PlyError> {
        let mut cursor = self.cursor();
        for e in &self.header.elements[..target] {
            cursor.skip(e).map_err(|p| p.in_file(&self.path))?;
        }
        self.release(0, cursor.pos());
        Ok(cursor)
    }

    /// Calls `f` on the vertex rows, a window at a time, in file order.
    pub fn vertices(&self, mut f: impl FnMut(&VertexBatch)) -> Result<(), PlyError> {
        let ve = self.plan.vertex_element;
        let e = &self.header.elements[ve];
        let mut cursor = self.cursor_at(ve)?;
        let fields = &self.plan.vertex_fields.fields;
        let (mut batch, mut values) = (VertexBatch::default(), Vec::new());
        let mut columns = ColumnRows {
            columns: vec![Vec::new(); fields.len()],
        };
        let mut row = 0u64;
        while row < e.count {
            let (start, n) = (
                cursor.pos(),
                (e.count - row).min(self.window as u64) as usize,
            );
            batch.clear();
            let big = self.header.encoding == Encoding::BinaryBigEndian;
            match cursor.fixed_rows(e, row, n) {
                Some(rows) => {
                    let rows = rows.map_err(|p| p.in_file(&self.path))?;
                    let rows = fixed_rows(rows, e, &self.plan.vertex_fields, big);
                    batch.extend(&rows, &self.plan);
                }
                None => {
                    columns.columns.iter_mut().for_each(Vec::clear);
                    for r in row..row + n as u64 {
                        cursor
                            .row(e, r, &mut values, |pi, v| {
                                for (k, field) in fields.iter().enumerate() {
                                    if field.property == pi {
                                        columns.columns[k].push(v[0]);
                                    }
                                }
                                Ok(())
                            })
                            .map_err(|p| p.in_file(&self.path))?;
                    }
                    batch.extend(&columns, &self.plan);
                }
            }
            f(&batch);
            self.release(start, cursor.pos());
            row += n as u64;
        }
        Ok(())
    }

    /// Calls `f` on the triangles of the face (or strip) element, a window of rows at
    /// a time, in file order: polygons fan-triangulated, indices checked against the
    /// vertex count, as [`super::read_ply`] makes them.
    pub fn triangles(&self, mut f: impl FnMut(&[[u32; 3]])) -> Result<(), PlyError> {
        let Some((fe, list)) = self.plan.faces else {
            return Ok(());
        };
        let e = &self.header.elements[fe];
        let mut cursor = self.cursor_at(fe)?;
        let vertex_count = self.vertex_count();
        let (mut faces, mut values, mut indices) = (Faces::default(), Vec::new(), Vec::new());
        let mut start = cursor.pos();
        for row in 0..e.count {
            let read = cursor.row(e, row, &mut values, |pi, v| {
                if pi == list {
                    indices.clear();
                    for &x in v {
                        if x.fract() != 0.0 {
                            let m = format!("vertex index {x} is not an integer");
                            return Err(Problem::row(&e.name, row, m));
                        }
                        indices.push(x as i64);
                    }
                }
                Ok(())
            });
            read.and_then(|()| faces.push_row(self.plan.strips, &indices, vertex_count, row))
                .map_err(|p| p.in_file(&self.path))?;
            if faces.triangles.len() >= self.window || row + 1 == e.count {
                f(&faces.triangles);
                faces.triangles.clear();
                self.release(start, cursor.pos());
                start = cursor.pos();
            }
        }
        Ok(())
    }
}
