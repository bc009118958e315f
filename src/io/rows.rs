//! The format-neutral row model: what every reader (PLY, LAS, LAZ) hands the geometry
//! stage. A model's vertices are rows; the fields used are x y z, then optionally
//! nx ny nz and red green blue \[alpha\] ([`VertexFields`]), each of a [`Scalar`] type,
//! read through [`VertexRows`] as f64: in place from fixed-size binary rows
//! ([`FixedRows`], no copy), or from columns a decoder filled ([`ColumnRows`]).

use super::scalar::Scalar;

/// A field the engine reads: its index among the format's properties (a PLY element's
/// property, a LAS point's attribute) and its type.
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
    /// The file has x and y but no z (a plan's or a map's points): the z field reads
    /// x's property, and [`Flat`] rows give 0 in its place.
    pub z_absent: bool,
}

impl VertexFields {
    pub const NORMAL: usize = 3;
    pub fn color_start(&self) -> usize {
        if self.has_normals { 6 } else { 3 }
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

/// Rows without z: field 2 reads 0 ([`VertexFields::z_absent`]).
pub struct Flat<'a, R>(pub &'a R);

impl<R: VertexRows> VertexRows for Flat<'_, R> {
    fn len(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn get(&self, i: usize, f: usize) -> f64 {
        if f == 2 { 0.0 } else { self.0.get(i, f) }
    }

    #[inline(always)]
    fn position(&self, i: usize) -> [f64; 3] {
        let [x, y, _] = self.0.position(i);
        [x, y, 0.0]
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
    /// Rows of `stride` bytes in `data`; `fields` gives each used field's byte offset
    /// within a row and its type, x y z first.
    pub fn new(
        data: &'a [u8],
        stride: usize,
        fields: Vec<(usize, Scalar)>,
        big_endian: bool,
    ) -> Self {
        let x = fields[0].0;
        let packed = fields[..3]
            .iter()
            .enumerate()
            .all(|(k, &(off, s))| s == Scalar::F32 && off == x + 4 * k);
        FixedRows {
            data,
            stride,
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
