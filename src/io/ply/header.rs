//! The PLY header: parsed by ply-rs-bw, then turned into the layout the decoders use.
//!
//! The header is found before anything is parsed: the file must start with `ply` and
//! hold `end_header` within its first [`MAX_HEADER_BYTES`], so that bytes that are not
//! PLY are refused without reading them as text.

use std::io::Cursor;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{self, DefaultElement, PropertyType, ScalarType};

use super::error::Problem;
use crate::io::scalar::Scalar;

/// Longest header accepted (comments included).
pub const MAX_HEADER_BYTES: usize = 1 << 20;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

impl Encoding {
    pub const fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropertyKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Property {
    pub name: String,
    pub kind: PropertyKind,
}

impl Property {
    /// The property as a header line would declare it, without the `property` keyword.
    pub fn declaration(&self) -> String {
        match self.kind {
            PropertyKind::Scalar(s) => format!("{} {}", s.name(), self.name),
            PropertyKind::List { count, item } => {
                format!("list {} {} {}", count.name(), item.name(), self.name)
            }
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Element {
    pub name: String,
    pub count: u64,
    pub properties: Vec<Property>,
}

impl Element {
    /// Bytes per row in a binary payload when no property is a list.
    pub fn fixed_row_size(&self) -> Option<usize> {
        self.properties
            .iter()
            .map(|p| match p.kind {
                PropertyKind::Scalar(s) => Some(s.size()),
                PropertyKind::List { .. } => None,
            })
            .sum()
    }

    /// Fewest bytes a binary row can take (lists empty); bounds the row count a file can hold.
    pub fn min_row_size(&self) -> usize {
        self.properties
            .iter()
            .map(|p| match p.kind {
                PropertyKind::Scalar(s) => s.size(),
                PropertyKind::List { count, .. } => count.size(),
            })
            .sum()
    }

    pub fn property(&self, names: &[&str]) -> Option<(usize, &Property)> {
        self.properties
            .iter()
            .enumerate()
            .find(|(_, p)| names.contains(&p.name.as_str()))
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    pub encoding: Encoding,
    pub version: String,
    pub comments: Vec<String>,
    pub obj_info: Vec<String>,
    pub elements: Vec<Element>,
    /// Byte offset of the first payload byte.
    pub payload_offset: usize,
}

impl Header {
    pub fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }
}

/// The first line of `bytes`, its newline (and CR) left out.
fn first_line(bytes: &[u8]) -> &[u8] {
    let line = bytes.split(|&b| b == b'\n').next().unwrap_or(&[]);
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// Whether `bytes` start with the line `ply`, blanks after it allowed (some writers leave
/// one, and other readers take it).
fn starts_with_magic(bytes: &[u8]) -> bool {
    bytes[..bytes.len().min(64)].contains(&b'\n') && first_line(bytes).trim_ascii_end() == b"ply"
}

/// Finds the end of the header: the byte after the newline that ends `end_header`.
fn header_end(bytes: &[u8]) -> Result<usize, Problem> {
    if !starts_with_magic(bytes) {
        return Err(Problem::file(
            "not a PLY file: it does not start with the line 'ply'",
        ));
    }
    let window = &bytes[..bytes.len().min(MAX_HEADER_BYTES)];
    let mut line_start = 0;
    while line_start < window.len() {
        let line_end = window[line_start..]
            .iter()
            .position(|&b| b == b'\n')
            .map(|i| line_start + i);
        let line = &window[line_start..line_end.unwrap_or(window.len())];
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.trim_ascii_end() == b"end_header" {
            // A header that ends the file without a newline has an empty payload.
            return Ok(line_end.map_or(window.len(), |e| e + 1));
        }
        match line_end {
            Some(e) => line_start = e + 1,
            None => break,
        }
    }
    Err(Problem::file(format!(
        "the header has no 'end_header' line within its first {} bytes",
        window.len()
    )))
}

fn scalar(t: &ScalarType) -> Scalar {
    match t {
        ScalarType::Char => Scalar::I8,
        ScalarType::UChar => Scalar::U8,
        ScalarType::Short => Scalar::I16,
        ScalarType::UShort => Scalar::U16,
        ScalarType::Int => Scalar::I32,
        ScalarType::UInt => Scalar::U32,
        ScalarType::Float => Scalar::F32,
        ScalarType::Double => Scalar::F64,
    }
}

/// Parses the header at the start of `bytes`.
pub(crate) fn parse_header(bytes: &[u8]) -> Result<Header, Problem> {
    let end = header_end(bytes)?;
    let text = std::str::from_utf8(&bytes[..end])
        .map_err(|e| Problem::file(format!("the header is not text: {e}")))?;
    // The header parser wants the magic line bare: blanks after `ply` go (lines keep
    // their numbers; the payload offset is `end`, in the file's own bytes).
    let magic = first_line(text.as_bytes()).len();
    let bare;
    let text = if magic > 3 {
        bare = format!("ply{}", &text[magic..]);
        bare.as_str()
    } else {
        text
    };
    let parser = Parser::<DefaultElement>::new();
    let mut reader = Reader::new(Cursor::new(text.as_bytes()));
    let parsed = parser.read_header(&mut reader).map_err(|e| {
        // ply-rs-bw puts the line in its message; keep it as ours and drop its prefix.
        let line = e.line().unwrap_or(0);
        let message = e.to_string();
        let message = message
            .strip_prefix(&format!("Line {line}: "))
            .unwrap_or(&message);
        let message = message.replace("\n\t", "; ");
        Problem::header(line, message)
    })?;
    let encoding = match parsed.encoding {
        ply::Encoding::Ascii => Encoding::Ascii,
        ply::Encoding::BinaryLittleEndian => Encoding::BinaryLittleEndian,
        ply::Encoding::BinaryBigEndian => Encoding::BinaryBigEndian,
    };
    let elements = parsed
        .elements
        .values()
        .map(|e| Element {
            name: e.name.clone(),
            count: e.count as u64,
            properties: e
                .properties
                .values()
                .map(|p| Property {
                    name: p.name.clone(),
                    kind: match &p.data_type {
                        PropertyType::Scalar(s) => PropertyKind::Scalar(scalar(s)),
                        PropertyType::List(c, i) => PropertyKind::List {
                            count: scalar(c),
                            item: scalar(i),
                        },
                    },
                })
                .collect(),
        })
        .collect::<Vec<_>>();
    for e in &elements {
        for p in &e.properties {
            if let PropertyKind::List { count, .. } = p.kind
                && count.is_float()
            {
                return Err(Problem::file(format!(
                    "element '{}', property '{}': a list count must be an integer type, not {}",
                    e.name,
                    p.name,
                    count.name()
                )));
            }
        }
    }
    Ok(Header {
        encoding,
        version: parsed.version.to_string(),
        comments: parsed.comments,
        obj_info: parsed.obj_infos,
        elements,
        payload_offset: end,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_magic_line_may_end_in_blanks() {
        let body = "format ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                    property float z\nend_header\n0 0 0\n";
        for magic in ["ply\n", "ply \n", "ply\t \r\n", "ply\r\n"] {
            let file = format!("{magic}{body}");
            let h = parse_header(file.as_bytes()).unwrap_or_else(|e| panic!("{magic:?}: {e:?}"));
            assert_eq!(h.elements[0].count, 1);
            assert_eq!(&file[h.payload_offset..], "0 0 0\n", "{magic:?}");
        }
        for not_ply in ["plyx\n", " ply\n", "ply", "PLY\n"] {
            assert!(
                parse_header(format!("{not_ply}{body}").as_bytes()).is_err(),
                "{not_ply:?}"
            );
        }
    }
}
