//! ASCII payloads: whitespace-separated numbers, read as a token stream with line
//! numbers kept for error messages. Rows are not required to end at line breaks.

use super::error::Problem;
use super::faces::Faces;
use super::fields::Plan;
use super::header::{Element, Header, PropertyKind};
use crate::io::rows::ColumnRows;
use crate::io::scalar::Scalar;

pub(super) struct Tokens<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    /// Line of the last token returned, counted from 1 in the whole file.
    pub(super) line: usize,
}

impl<'a> Tokens<'a> {
    fn next(&mut self) -> Option<&'a [u8]> {
        while let Some(&b) = self.data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| &self.data[start..self.pos])
    }

    /// The next token as a value of type `s`, or an error naming the row.
    fn value(&mut self, e: &Element, row: u64, s: Scalar) -> Result<f64, Problem> {
        let Some(tok) = self.next() else {
            return Err(Problem::row(
                &e.name,
                row,
                format!(
                    "the file ends inside this row (the header declares {} rows)",
                    e.count
                ),
            )
            .at_line(self.line));
        };
        let text = std::str::from_utf8(tok).unwrap_or("");
        // Integer properties must hold whole numbers ("3" or "3.0").
        let parsed = text
            .parse::<f64>()
            .ok()
            .filter(|v| s.is_float() || (v.is_finite() && v.fract() == 0.0));
        parsed.ok_or_else(|| {
            Problem::row(
                &e.name,
                row,
                format!(
                    "expected a {} value, found '{}'",
                    s.name(),
                    String::from_utf8_lossy(&tok[..tok.len().min(40)])
                ),
            )
            .at_line(self.line)
        })
    }

    /// Reads one row; calls `visit(property, values)` with the row's values of each property.
    pub(super) fn row(
        &mut self,
        e: &Element,
        row: u64,
        values: &mut Vec<f64>,
        mut visit: impl FnMut(usize, &[f64]) -> Result<(), Problem>,
    ) -> Result<(), Problem> {
        for (pi, p) in e.properties.iter().enumerate() {
            values.clear();
            match p.kind {
                PropertyKind::Scalar(s) => values.push(self.value(e, row, s)?),
                PropertyKind::List { count, item } => {
                    let n = self.value(e, row, count)?;
                    if n < 0.0 {
                        return Err(Problem::row(
                            &e.name,
                            row,
                            format!("list '{}' has a negative length {n}", p.name),
                        )
                        .at_line(self.line));
                    }
                    for _ in 0..n as u64 {
                        values.push(self.value(e, row, item)?);
                    }
                }
            }
            visit(pi, values).map_err(|p| p.at_line(self.line))?;
        }
        Ok(())
    }
}

/// The decoded parts of an ASCII payload.
pub struct Decoded {
    pub vertices: ColumnRows,
    pub faces: Option<Faces>,
}

/// Decodes the vertex and face elements of an ASCII payload; skips the others.
pub fn decode(
    data: &[u8],
    header: &Header,
    plan: &Plan,
    first_line: usize,
) -> Result<Decoded, Problem> {
    let mut tokens = Tokens {
        data,
        pos: 0,
        line: first_line,
    };
    let fields = &plan.vertex_fields.fields;
    let vertex_count = header.elements[plan.vertex_element].count;
    // Each value takes at least two bytes ("0 "): no buffer larger than the file allows.
    let bound = |count: u64| (count as usize).min(data.len() / 2 + 1);
    let mut columns = vec![Vec::with_capacity(bound(vertex_count)); fields.len()];
    let mut faces = None;
    let mut values = Vec::new();
    let needed = plan
        .faces
        .map_or(plan.vertex_element, |(f, _)| f.max(plan.vertex_element));
    for (ei, e) in header.elements.iter().enumerate().take(needed + 1) {
        // A row of an element without properties holds no token: its rows cost
        // nothing to skip, whatever count the header declares.
        if e.properties.is_empty() {
            continue;
        }
        let face_list = plan.faces.filter(|(f, _)| *f == ei).map(|(_, l)| l);
        let mut element_faces = face_list.map(|_| Faces::with_capacity(bound(e.count)));
        let mut indices = Vec::new();
        for row in 0..e.count {
            tokens.row(e, row, &mut values, |pi, v| {
                if ei == plan.vertex_element {
                    for (f, field) in fields.iter().enumerate() {
                        if field.property == pi {
                            columns[f].push(v[0]);
                        }
                    }
                } else if face_list == Some(pi) {
                    indices.clear();
                    for &x in v {
                        if x.fract() != 0.0 {
                            return Err(Problem::row(
                                "face",
                                row,
                                format!("vertex index {x} is not an integer"),
                            ));
                        }
                        indices.push(x as i64);
                    }
                }
                Ok(())
            })?;
            if let Some(f) = element_faces.as_mut() {
                f.push_row(plan.strips, &indices, vertex_count, row)
                    .map_err(|p| p.at_line(tokens.line))?;
            }
        }
        if element_faces.is_some() {
            faces = element_faces;
        }
    }
    Ok(Decoded {
        vertices: ColumnRows { columns },
        faces,
    })
}
