//! Which properties of a PLY file the engine uses, and random access to them.
//!
//! The decoders hand the vertex rows to the geometry stage through [`VertexRows`]: a
//! fixed-layout binary element is read in place ([`FixedRows`], no copy), anything else
//! is first decoded into columns ([`ColumnRows`]).

use super::error::Problem;
use super::header::{Element, Header, PropertyKind};
use super::scalar::Scalar;

const X: &[&str] = &["x"];
const Y: &[&str] = &["y"];
const Z: &[&str] = &["z"];
const NX: &[&str] = &["nx", "normal_x"];
const NY: &[&str] = &["ny", "normal_y"];
const NZ: &[&str] = &["nz", "normal_z"];
const RED: &[&str] = &["red", "diffuse_red", "r"];
const GREEN: &[&str] = &["green", "diffuse_green", "g"];
const BLUE: &[&str] = &["blue", "diffuse_blue", "b"];
const ALPHA: &[&str] = &["alpha", "diffuse_alpha", "a"];
const FACE_INDICES: &[&str] = &["vertex_indices", "vertex_index"];

/// A vertex property the engine reads: its index among the element's properties and type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    pub property: usize,
    pub scalar: Scalar,
}

/// The vertex fields used, in a fixed order: x y z, then nx ny nz if all three are
/// present, then red green blue \[alpha\] if the three colours are present.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VertexFields {
    pub fields: Vec<Field>,
    pub has_normals: bool,
    /// 0, 3 or 4 colour channels.
    pub color_channels: usize,
}

impl VertexFields {
    pub const NORMAL: usize = 3;
    pub fn color_start(&self) -> usize {
        if self.has_normals { 6 } else { 3 }
    }
}

/// What the decoders must extract: element indices and fields.
#[derive(Debug, Clone)]
pub struct Plan {
    pub vertex_element: usize,
    pub vertex_fields: VertexFields,
    /// The face element and the index of its vertex-index list property.
    pub faces: Option<(usize, usize)>,
    /// Whether that element holds triangle strips (`tristrips`, −1 restarts a strip)
    /// rather than polygons (`face`).
    pub strips: bool,
}

fn scalar_field(e: &Element, names: &[&str]) -> Result<Option<Field>, Problem> {
    match e.property(names) {
        None => Ok(None),
        Some((i, p)) => match p.kind {
            PropertyKind::Scalar(scalar) => Ok(Some(Field {
                property: i,
                scalar,
            })),
            PropertyKind::List { .. } => Err(Problem::file(format!(
                "element '{}': property '{}' is a list, expected a scalar",
                e.name, p.name
            ))),
        },
    }
}

fn all_fields(e: &Element, names: &[&[&str]]) -> Result<Option<Vec<Field>>, Problem> {
    let found = names
        .iter()
        .map(|n| scalar_field(e, n))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(found.into_iter().collect())
}

impl Plan {
    pub fn new(header: &Header) -> Result<Plan, Problem> {
        let vertex_element = header
            .elements
            .iter()
            .position(|e| e.name == "vertex")
            .ok_or_else(|| Problem::file("the file has no 'vertex' element: no model to read"))?;
        let v = &header.elements[vertex_element];
        let mut fields = Vec::new();
        for (axis, names) in [X, Y, Z].iter().enumerate() {
            let f = scalar_field(v, names)?.ok_or_else(|| {
                Problem::file(format!(
                    "element 'vertex' has no property '{}'",
                    ["x", "y", "z"][axis]
                ))
            })?;
            fields.push(f);
        }
        let normals = all_fields(v, &[NX, NY, NZ])?;
        let has_normals = normals.is_some();
        fields.extend(normals.unwrap_or_default());
        let mut color_channels = 0;
        if let Some(rgb) = all_fields(v, &[RED, GREEN, BLUE])? {
            fields.extend(rgb);
            color_channels = 3;
            if let Some(a) = scalar_field(v, ALPHA)? {
                fields.push(a);
                color_channels = 4;
            }
        }
        let face_element = header.elements.iter().position(|e| e.name == "face");
        let strip_element = header.elements.iter().position(|e| e.name == "tristrips");
        let strips = face_element.is_none() && strip_element.is_some();
        let faces = match face_element.or(strip_element) {
            None => None,
            Some(fi) => index_list(&header.elements[fi])?.map(|pi| (fi, pi)),
        };
        Ok(Plan {
            vertex_element,
            vertex_fields: VertexFields {
                fields,
                has_normals,
                color_channels,
            },
            faces,
            strips,
        })
    }
}

/// The vertex-index list property of a face or strip element `e`; `None` for an empty
/// element without one.
fn index_list(e: &Element) -> Result<Option<usize>, Problem> {
    match e.property(FACE_INDICES) {
        Some((pi, p)) => match p.kind {
            PropertyKind::List { item, .. } if !item.is_float() => Ok(Some(pi)),
            _ => Err(Problem::file(format!(
                "element '{}': property '{}' must be a list of integers, found {}",
                e.name,
                p.name,
                p.declaration()
            ))),
        },
        None if e.count == 0 => Ok(None),
        None => Err(Problem::file(format!(
            "element '{}' has no list property 'vertex_indices' or 'vertex_index'",
            e.name
        ))),
    }
}

/// Random access to the used fields of the vertex rows, whatever the encoding.
pub trait VertexRows: Sync {
    fn len(&self) -> usize;
    /// Field `f` (an index into [`VertexFields::fields`]) of row `i`, as f64.
    fn get(&self, i: usize, f: usize) -> f64;

    /// x y z of row `i`.
    #[inline(always)]
    fn position(&self, i: usize) -> [f64; 3] {
        [self.get(i, 0), self.get(i, 1), self.get(i, 2)]
    }
}

/// Vertex rows of a binary element whose rows all have the same size, read in place.
pub struct FixedRows<'a> {
    pub data: &'a [u8],
    pub stride: usize,
    /// Byte offset within the row and type of each used field.
    pub fields: Vec<(usize, Scalar)>,
    pub big_endian: bool,
    /// Offset of x when x y z are consecutive little-endian floats (the common layout,
    /// read without per-value dispatch).
    xyz_f32_le: Option<usize>,
}

impl<'a> FixedRows<'a> {
    pub fn new(data: &'a [u8], e: &Element, used: &VertexFields, big_endian: bool) -> Self {
        let mut offsets = Vec::with_capacity(e.properties.len());
        let mut at = 0;
        for p in &e.properties {
            offsets.push(at);
            if let PropertyKind::Scalar(s) = p.kind {
                at += s.size();
            }
        }
        let fields: Vec<(usize, Scalar)> = used
            .fields
            .iter()
            .map(|f| (offsets[f.property], f.scalar))
            .collect();
        let x = fields[0].0;
        let packed = fields[..3]
            .iter()
            .enumerate()
            .all(|(k, &(off, s))| s == Scalar::F32 && off == x + 4 * k);
        FixedRows {
            data,
            stride: at,
            fields,
            big_endian,
            xyz_f32_le: (packed && !big_endian).then_some(x),
        }
    }
}

impl VertexRows for FixedRows<'_> {
    fn len(&self) -> usize {
        self.data.len().checked_div(self.stride).unwrap_or(0)
    }

    #[inline(always)]
    fn get(&self, i: usize, f: usize) -> f64 {
        let (off, s) = self.fields[f];
        s.read(&self.data[i * self.stride + off..], self.big_endian)
    }

    #[inline(always)]
    fn position(&self, i: usize) -> [f64; 3] {
        match self.xyz_f32_le {
            Some(x) => {
                let r: &[u8; 12] = self.data[i * self.stride + x..][..12].try_into().unwrap();
                let f = |k: usize| f32::from_le_bytes([r[k], r[k + 1], r[k + 2], r[k + 3]]) as f64;
                [f(0), f(4), f(8)]
            }
            None => [self.get(i, 0), self.get(i, 1), self.get(i, 2)],
        }
    }
}

/// Vertex fields decoded into one column per field.
pub struct ColumnRows {
    pub columns: Vec<Vec<f64>>,
}

impl VertexRows for ColumnRows {
    fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    #[inline(always)]
    fn get(&self, i: usize, f: usize) -> f64 {
        self.columns[f][i]
    }
}
