//! Which properties of a PLY file the engine uses ([`Plan`]), as the fields of the
//! format-neutral row model ([`crate::io::rows`]): a fixed-layout binary element is read
//! in place ([`fixed_rows`], no copy), anything else is first decoded into columns.

use super::error::Problem;
use super::header::{Element, Header, PropertyKind};
use crate::io::rows::{Field, FixedRows, VertexFields};

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
        for (axis, names) in [X, Y].iter().enumerate() {
            let f = scalar_field(v, names)?.ok_or_else(|| {
                Problem::file(format!(
                    "element 'vertex' has no property '{}'",
                    ["x", "y"][axis]
                ))
            })?;
            fields.push(f);
        }
        // Points without z lie in the plane z = 0 (`Flat` rows).
        let z = scalar_field(v, Z)?;
        let z_absent = z.is_none();
        fields.push(z.unwrap_or(fields[0]));
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
                z_absent,
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

/// The vertex rows of binary element `e` (every property a scalar) in `data`, read in
/// place: each used field's byte offset within the row, from the properties' sizes.
pub fn fixed_rows<'a>(
    data: &'a [u8],
    e: &Element,
    used: &VertexFields,
    big_endian: bool,
) -> FixedRows<'a> {
    let mut offsets = Vec::with_capacity(e.properties.len());
    let mut at = 0;
    for p in &e.properties {
        offsets.push(at);
        if let PropertyKind::Scalar(s) = p.kind {
            at += s.size();
        }
    }
    let fields = used
        .fields
        .iter()
        .map(|f| (offsets[f.property], f.scalar))
        .collect();
    FixedRows::new(data, at, fields, big_endian)
}
