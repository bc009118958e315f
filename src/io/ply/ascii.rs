//! ASCII payloads: whitespace-separated numbers, one row per line, read as a token
//! stream with line numbers kept for error messages. A row whose line holds fewer or
//! more values than the header declares is an error naming its element, row and line:
//! read on as one stream, every later row would shift silently.

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

    /// Whether the rest of the current line holds nothing but blanks (and a CR).
    fn line_ends(&self) -> bool {
        self.data[self.pos..]
            .iter()
            .take_while(|&&b| b != b'\n')
            .all(|b| b.is_ascii_whitespace())
    }

    /// The next token as a value of type `s`, on the row's line `row_line` (the line of
    /// the row's first value when `None`), or an error naming the row.
    fn value(
        &mut self,
        e: &Element,
        row: u64,
        s: Scalar,
        row_line: Option<usize>,
    ) -> Result<f64, Problem> {
        let next = self.next();
        if let Some(line) = row_line.filter(|l| next.is_some() && self.line != *l) {
            return Err(Problem::row(
                &e.name,
                row,
                format!(
                    "the line ends before the row does: it holds fewer values than the \
                     header declares ({})",
                    declared(e)
                ),
            )
            .at_line(line));
        }
        let Some(tok) = next else {
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
        let mut row_line = None;
        for (pi, p) in e.properties.iter().enumerate() {
            values.clear();
            match p.kind {
                PropertyKind::Scalar(s) => values.push(self.value(e, row, s, row_line)?),
                PropertyKind::List { count, item } => {
                    let n = self.value(e, row, count, row_line)?;
                    if n < 0.0 {
                        return Err(Problem::row(
                            &e.name,
                            row,
                            format!("list '{}' has a negative length {n}", p.name),
                        )
                        .at_line(self.line));
                    }
                    let line = row_line.unwrap_or(self.line);
                    for _ in 0..n as u64 {
                        values.push(self.value(e, row, item, Some(line))?);
                    }
                }
            }
            row_line.get_or_insert(self.line);
            visit(pi, values).map_err(|p| p.at_line(self.line))?;
        }
        if !self.line_ends() {
            return Err(Problem::row(
                &e.name,
                row,
                format!(
                    "the line holds more values than the header declares for a row ({})",
                    declared(e)
                ),
            )
            .at_line(self.line));
        }
        Ok(())
    }
}

/// What the header declares for a row of `e`: its properties' names, lists marked.
fn declared(e: &Element) -> String {
    let names: Vec<String> = e
        .properties
        .iter()
        .map(|p| match p.kind {
            PropertyKind::Scalar(_) => p.name.clone(),
            PropertyKind::List { .. } => format!("a list '{}'", p.name),
        })
        .collect();
    names.join(" ")
}

/// Rows between two tellings of the bytes decoded.
const TOLD_ROWS: u64 = 1 << 14;

/// The decoded parts of an ASCII payload.
pub struct Decoded {
    pub vertices: ColumnRows,
    pub faces: Option<Faces>,
}

/// Decodes the vertex and face elements of an ASCII payload; skips the others. Tells
/// `told` the payload's bytes decoded, every [`TOLD_ROWS`] rows and at each element's end.
pub fn decode(
    data: &[u8],
    (header, plan): (&Header, &Plan),
    first_line: usize,
    told: &dyn Fn(u64),
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
    let mut reported = 0;
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
            if row % TOLD_ROWS == 0 {
                told((tokens.pos - reported) as u64);
                reported = tokens.pos;
            }
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
        told((tokens.pos - reported) as u64);
        reported = tokens.pos;
        if element_faces.is_some() {
            faces = element_faces;
        }
    }
    Ok(Decoded {
        vertices: ColumnRows { columns },
        faces,
    })
}
