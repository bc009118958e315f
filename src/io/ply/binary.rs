//! Binary payloads, both byte orders.
//!
//! Elements whose rows have a fixed size are handled in bulk: vertex rows are read in
//! place through [`FixedRows`], and a face element whose polygons are all triangles
//! (the common case) is decoded in parallel at a fixed stride. Anything else is walked
//! row by row. Every read is bounds-checked against the payload, and no buffer is
//! sized by a header count beyond what the remaining bytes can hold.

use rayon::prelude::*;

use super::error::Problem;
use super::faces::{Faces, check_index};
use super::fields::{Plan, fixed_rows};
use super::header::{Element, Header, PropertyKind};
use crate::io::rows::{ColumnRows, FixedRows};
use crate::io::scalar::Scalar;

/// Vertex rows of a binary payload: in place when their size is fixed, else decoded.
pub enum VertexSource<'a> {
    Fixed(FixedRows<'a>),
    Columns(ColumnRows),
}

/// The decoded parts of a binary payload.
pub struct Decoded<'a> {
    pub vertices: VertexSource<'a>,
    pub faces: Option<Faces>,
}

pub(super) fn truncated(e: &Element, row: u64) -> Problem {
    Problem::row(
        &e.name,
        row,
        format!(
            "the file ends inside this row (the header declares {} rows)",
            e.count
        ),
    )
}

/// Walks one row of `e` starting at `pos`; calls `visit(property, bytes, list_len)` for
/// each property (`list_len` is `None` for scalars) and returns the position after it.
pub(super) fn walk_row(
    data: &[u8],
    mut pos: usize,
    e: &Element,
    row: u64,
    big: bool,
    mut visit: impl FnMut(usize, &[u8], Option<usize>) -> Result<(), Problem>,
) -> Result<usize, Problem> {
    for (pi, p) in e.properties.iter().enumerate() {
        match p.kind {
            PropertyKind::Scalar(s) => {
                let b = data
                    .get(pos..pos + s.size())
                    .ok_or_else(|| truncated(e, row))?;
                visit(pi, b, None)?;
                pos += s.size();
            }
            PropertyKind::List { count, item } => {
                let cb = data
                    .get(pos..pos + count.size())
                    .ok_or_else(|| truncated(e, row))?;
                let n = count.read_int(cb, big).unwrap_or(0);
                if n < 0 {
                    return Err(Problem::row(
                        &e.name,
                        row,
                        format!("list '{}' has a negative length {n}", p.name),
                    ));
                }
                pos += count.size();
                let len = (n as usize)
                    .checked_mul(item.size())
                    .filter(|l| pos + l <= data.len())
                    .ok_or_else(|| truncated(e, row))?;
                visit(pi, &data[pos..pos + len], Some(n as usize))?;
                pos += len;
            }
        }
    }
    Ok(pos)
}

/// Decodes a vertex element with list properties, row by row, into columns.
fn vertex_columns(
    data: &[u8],
    pos: &mut usize,
    e: &Element,
    plan: &Plan,
    big: bool,
) -> Result<ColumnRows, Problem> {
    let fields = &plan.vertex_fields.fields;
    let capacity = (e.count as usize).min(data.len() / e.min_row_size().max(1));
    let mut columns = vec![Vec::with_capacity(capacity); fields.len()];
    for row in 0..e.count {
        *pos = walk_row(data, *pos, e, row, big, |pi, b, _| {
            for (f, field) in fields.iter().enumerate() {
                if field.property == pi {
                    columns[f].push(field.scalar.read(b, big));
                }
            }
            Ok(())
        })?;
    }
    Ok(ColumnRows { columns })
}

/// The rows of a face element whose polygons are all triangles, at a fixed stride; the
/// vertex-index list starts `prefix` bytes into each row.
struct TriangleRows<'a> {
    body: &'a [u8],
    stride: usize,
    prefix: usize,
    count: Scalar,
    item: Scalar,
    big: bool,
    vertex_count: u64,
}

/// A row that is not a triangle (`None`: fall back to row by row), or a bad index.
type RowFault = Option<Problem>;

impl TriangleRows<'_> {
    /// Row `row` with a uchar count and int or uint indices.
    #[inline]
    fn common(&self, row: usize) -> Result<[u32; 3], RowFault> {
        let r: &[u8; 13] = self.body[row * self.stride + self.prefix..][..13]
            .try_into()
            .unwrap();
        if r[0] != 3 {
            return Err(None);
        }
        let get = |j: usize| {
            let b = [r[1 + 4 * j], r[2 + 4 * j], r[3 + 4 * j], r[4 + 4 * j]];
            let v = if self.big {
                u32::from_be_bytes(b)
            } else {
                u32::from_le_bytes(b)
            };
            if self.item == Scalar::I32 {
                v as i32 as i64
            } else {
                v as i64
            }
        };
        let tri = [get(0), get(1), get(2)];
        match tri
            .into_iter()
            .find(|&i| i < 0 || i as u64 >= self.vertex_count)
        {
            None => Ok(tri.map(|i| i as u32)),
            Some(bad) => Err(check_index(bad, self.vertex_count, row as u64).err()),
        }
    }

    /// Row `row` with any count and index types.
    #[inline]
    fn any(&self, row: usize) -> Result<[u32; 3], RowFault> {
        let r = &self.body[row * self.stride + self.prefix..];
        if self.count.read_int(r, self.big) != Some(3) {
            return Err(None);
        }
        let mut tri = [0u32; 3];
        for (j, t) in tri.iter_mut().enumerate() {
            let at = self.count.size() + j * self.item.size();
            let i = self.item.read_int(&r[at..], self.big).unwrap_or(-1);
            check_index(i, self.vertex_count, row as u64).map_err(Some)?;
            *t = i as u32;
        }
        Ok(tri)
    }
}

/// Fills `triangles` (one per row) in parallel with `decode`; the first row that
/// fails, if any, with its fault.
fn decode_triangles(
    triangles: &mut [[u32; 3]],
    decode: impl Fn(usize) -> Result<[u32; 3], RowFault> + Sync,
) -> Option<(usize, RowFault)> {
    const CHUNK: usize = 1 << 16;
    triangles
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(c, out)| {
            for (k, tri) in out.iter_mut().enumerate() {
                let row = c * CHUNK + k;
                match decode(row) {
                    Ok(t) => *tri = t,
                    Err(fault) => return Some((row, fault)),
                }
            }
            None
        })
        .find_first(Option::is_some)
        .flatten()
}

/// Faces when every polygon is a triangle: rows have a fixed stride, decoded in
/// parallel. Returns `Ok(None)` when some row is not a triangle (or the rows cannot all
/// be triangles), so that the caller falls back to [`faces_by_row`].
fn faces_fixed_triangles(
    data: &[u8],
    pos: usize,
    e: &Element,
    list: usize,
    vertex_count: u64,
    big: bool,
) -> Result<Option<(Faces, usize)>, Problem> {
    let PropertyKind::List { count, item } = e.properties[list].kind else {
        return Ok(None);
    };
    let mut prefix = 0;
    let mut suffix = 0;
    for (pi, p) in e.properties.iter().enumerate() {
        match p.kind {
            PropertyKind::Scalar(s) if pi < list => prefix += s.size(),
            PropertyKind::Scalar(s) => suffix += s.size(),
            PropertyKind::List { .. } if pi == list => {}
            PropertyKind::List { .. } => return Ok(None),
        }
    }
    let stride = prefix + count.size() + 3 * item.size() + suffix;
    let rows = e.count as usize;
    let Some(end) = rows.checked_mul(stride).and_then(|n| n.checked_add(pos)) else {
        return Ok(None);
    };
    if end > data.len() {
        return Ok(None);
    }
    let t = TriangleRows {
        body: &data[pos..end],
        stride,
        prefix,
        count,
        item,
        big,
        vertex_count,
    };
    // The layout most tools write (uchar count, int or uint indices) gets its own loop.
    let common = count == Scalar::U8 && matches!(item, Scalar::I32 | Scalar::U32);
    let mut triangles = vec![[0u32; 3]; rows];
    let first_bad = if common {
        decode_triangles(&mut triangles, |row| t.common(row))
    } else {
        decode_triangles(&mut triangles, |row| t.any(row))
    };
    match first_bad {
        None => Ok(Some((
            Faces {
                triangles,
                polygons: rows as u64,
                ..Faces::default()
            },
            end,
        ))),
        Some((_, Some(problem))) => Err(problem),
        Some((_, None)) => Ok(None),
    }
}

/// Faces of any shape, row by row.
fn faces_by_row(
    data: &[u8],
    pos: &mut usize,
    e: &Element,
    list: usize,
    (vertex_count, strips): (u64, bool),
    big: bool,
) -> Result<Faces, Problem> {
    let PropertyKind::List { item, .. } = e.properties[list].kind else {
        unreachable!("the plan checked that the face indices are a list")
    };
    let capacity = (e.count as usize).min(data.len() / e.min_row_size().max(1));
    let mut faces = Faces::with_capacity(capacity);
    let mut indices = Vec::new();
    for row in 0..e.count {
        *pos = walk_row(data, *pos, e, row, big, |pi, b, n| {
            if pi == list {
                indices.clear();
                indices.extend(
                    (0..n.unwrap_or(0))
                        .map(|k| item.read_int(&b[k * item.size()..], big).unwrap_or(-1)),
                );
            }
            Ok(())
        })?;
        faces.push_row(strips, &indices, vertex_count, row)?;
    }
    Ok(faces)
}

/// Decodes the vertex and face elements of a binary payload; skips the others.
pub fn decode<'a>(data: &'a [u8], header: &Header, plan: &Plan) -> Result<Decoded<'a>, Problem> {
    let big = matches!(header.encoding, super::header::Encoding::BinaryBigEndian);
    let vertex_count = header.elements[plan.vertex_element].count;
    let mut vertices = None;
    let mut faces = None;
    let mut pos = 0usize;
    let needed = plan
        .faces
        .map_or(plan.vertex_element, |(f, _)| f.max(plan.vertex_element));
    for (ei, e) in header.elements.iter().enumerate().take(needed + 1) {
        let face_list = plan.faces.filter(|(f, _)| *f == ei).map(|(_, l)| l);
        if let Some(stride) = e.fixed_row_size() {
            let len = (e.count as usize)
                .checked_mul(stride)
                .filter(|&n| pos.checked_add(n).is_some_and(|end| end <= data.len()))
                .ok_or_else(|| truncated(e, ((data.len() - pos) / stride.max(1)) as u64))?;
            if ei == plan.vertex_element {
                let rows = &data[pos..pos + len];
                vertices = Some(VertexSource::Fixed(fixed_rows(
                    rows,
                    e,
                    &plan.vertex_fields,
                    big,
                )));
            }
            pos += len;
        } else if ei == plan.vertex_element {
            vertices = Some(VertexSource::Columns(vertex_columns(
                data, &mut pos, e, plan, big,
            )?));
        } else if let Some(list) = face_list {
            let fixed = if plan.strips {
                None
            } else {
                faces_fixed_triangles(data, pos, e, list, vertex_count, big)?
            };
            match fixed {
                Some((f, end)) => {
                    faces = Some(f);
                    pos = end;
                }
                None => {
                    let what = (vertex_count, plan.strips);
                    faces = Some(faces_by_row(data, &mut pos, e, list, what, big)?);
                }
            }
        } else {
            for row in 0..e.count {
                pos = walk_row(data, pos, e, row, big, |_, _, _| Ok(()))?;
            }
        }
    }
    Ok(Decoded {
        vertices: vertices.expect("the vertex element is among the decoded ones"),
        faces,
    })
}
