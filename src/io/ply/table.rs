//! A PLY element read as a table of numbers: each row's values of the scalar properties
//! asked for, by name. For small record files (a scene's instances, one vertex each)
//! rather than models. The row count the header declares is checked against the bytes
//! the file holds before any row is read, and nothing is allocated from it alone.

use std::path::Path;

use super::error::Problem;
use super::header::{Element, Encoding, PropertyKind, parse_header};
use super::{Location, PlyError};

/// One column asked for: the names it may have in the file, and whether the file must
/// have it (a missing optional column reads as None).
#[derive(Debug, Clone, Copy)]
pub struct Column<'a> {
    pub names: &'a [&'a str],
    pub required: bool,
}

/// Calls `row(i, values)` for each row of `element` in `path`, `values[k]` holding
/// column k's value (None where the file lacks an optional column). Lists, and elements
/// before `element` in a binary file that hold lists, are refused.
pub fn read_table(
    path: &Path,
    element: &str,
    columns: &[Column],
    mut row: impl FnMut(u64, &[Option<f64>]) -> Result<(), String>,
) -> Result<(), PlyError> {
    let regular = std::fs::metadata(path).map(|m| m.is_file());
    if !regular.map_err(|e| Problem::file(e.to_string()).in_file(path))? {
        return Err(Problem::file("not a regular file").in_file(path));
    }
    let bytes = std::fs::read(path).map_err(|e| Problem::file(e.to_string()).in_file(path))?;
    let at_row = |i: u64, message: String| Problem::row(element, i, message).in_file(path);
    let header = parse_header(&bytes).map_err(|p| p.in_file(path))?;
    let Some(index) = header.elements.iter().position(|e| e.name == element) else {
        return Err(Problem::file(format!("no element '{element}'")).in_file(path));
    };
    let target = &header.elements[index];
    let found = find_columns(target, columns).map_err(|m| Problem::file(m).in_file(path))?;
    let mut values = vec![None; columns.len()];
    let payload = &bytes[header.payload_offset..];
    let mut visit = |i: u64, read: &dyn Fn(usize) -> Option<f64>| {
        for (v, f) in values.iter_mut().zip(&found) {
            *v = f.and_then(read);
        }
        row(i, &values).map_err(|m| at_row(i, m))
    };
    match header.encoding {
        Encoding::Ascii => {
            let text = std::str::from_utf8(payload)
                .map_err(|_| Problem::file("the ASCII payload is not text").in_file(path))?;
            let mut lines = text.lines().filter(|l| !l.trim().is_empty());
            let before: u64 = header.elements[..index].iter().map(|e| e.count).sum();
            // The rows of the elements before, as far as the file holds them.
            for _ in 0..before {
                if lines.next().is_none() {
                    break;
                }
            }
            for i in 0..target.count {
                let Some(line) = lines.next() else {
                    let m = format!("the header says {} rows; the file ends here", target.count);
                    return Err(at_row(i, m));
                };
                let tokens: Vec<&str> = line.split_ascii_whitespace().collect();
                if tokens.len() != target.properties.len() {
                    let m = format!(
                        "{} values, the header declares {}",
                        tokens.len(),
                        target.properties.len()
                    );
                    return Err(at_row(i, m));
                }
                let parsed: Vec<Option<f64>> = tokens.iter().map(|t| t.parse().ok()).collect();
                if let Some(k) = parsed.iter().position(Option::is_none) {
                    return Err(at_row(i, format!("'{}' is not a number", tokens[k])));
                }
                visit(i, &|p| parsed[p])?;
            }
        }
        encoding => {
            let big = encoding == Encoding::BinaryBigEndian;
            let (start, size) =
                binary_rows(&header.elements, index).map_err(|m| Problem::file(m).in_file(path))?;
            let held = (payload.len().saturating_sub(start) / size.max(1)) as u64;
            if held < target.count {
                let m = format!(
                    "the header says {} rows of '{element}'; the file holds {held}",
                    target.count
                );
                return Err(PlyError {
                    path: path.to_owned(),
                    location: Location::File,
                    message: m,
                });
            }
            let offsets = property_offsets(target);
            for i in 0..target.count {
                let at = start + i as usize * size;
                let rowbytes = &payload[at..at + size];
                visit(i, &|p| {
                    let (offset, scalar) = offsets[p];
                    Some(scalar.read(&rowbytes[offset..], big))
                })?;
            }
        }
    }
    Ok(())
}

/// The property index of each column in `element` (None for a missing optional one).
fn find_columns(element: &Element, columns: &[Column]) -> Result<Vec<Option<usize>>, String> {
    columns
        .iter()
        .map(|c| match element.property(c.names) {
            Some((_, p)) if !matches!(p.kind, PropertyKind::Scalar(_)) => Err(format!(
                "property '{}' is a list; a number is needed",
                p.name
            )),
            Some((k, _)) => Ok(Some(k)),
            None if c.required => Err(format!(
                "element '{}' has no property '{}'",
                element.name,
                c.names.join("' or '")
            )),
            None => Ok(None),
        })
        .collect()
}

/// Where element `index`'s rows start in a binary payload, and their size.
fn binary_rows(elements: &[Element], index: usize) -> Result<(usize, usize), String> {
    let fixed = |e: &Element| {
        e.fixed_row_size()
            .ok_or_else(|| format!("element '{}' holds lists", e.name))
    };
    let mut start = 0usize;
    for e in &elements[..index] {
        let bytes = (e.count as usize).checked_mul(fixed(e)?);
        start = bytes
            .and_then(|b| start.checked_add(b))
            .ok_or_else(|| format!("element '{}' is larger than any file", e.name))?;
    }
    Ok((start, fixed(&elements[index])?))
}

/// Each property's byte offset in a binary row, and its type.
fn property_offsets(element: &Element) -> Vec<(usize, crate::io::scalar::Scalar)> {
    let mut at = 0;
    element
        .properties
        .iter()
        .map(|p| {
            let PropertyKind::Scalar(s) = p.kind else {
                unreachable!("binary_rows refused lists")
            };
            at += s.size();
            (at - s.size(), s)
        })
        .collect()
}
