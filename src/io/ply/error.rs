//! Errors of the PLY reader: every one names the file, and where it can, the header line
//! or the element and row at fault.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a PLY file a problem lies.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (cannot be opened, is empty, holds no vertex…).
    File,
    /// A line of the header, counted from 1.
    HeaderLine(usize),
    /// A row of an element, counted from 0 as PLY indices are; `line` for ASCII files.
    Row {
        element: String,
        row: u64,
        line: Option<usize>,
    },
}

/// A PLY file that cannot be read, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyError {
    pub path: PathBuf,
    pub location: Location,
    pub message: String,
}

impl fmt::Display for PlyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: ", self.path.display())?;
        match &self.location {
            Location::File => {}
            Location::HeaderLine(line) => write!(f, "header line {line}: ")?,
            Location::Row { element, row, line } => {
                write!(f, "element '{element}', row {row}")?;
                if let Some(line) = line {
                    write!(f, " (line {line})")?;
                }
                write!(f, ": ")?;
            }
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for PlyError {}

/// A problem found while decoding, before the file name is attached.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Problem {
    pub location: Location,
    pub message: String,
}

impl Problem {
    pub fn file(message: impl Into<String>) -> Self {
        Problem {
            location: Location::File,
            message: message.into(),
        }
    }

    pub fn header(line: usize, message: impl Into<String>) -> Self {
        Problem {
            location: Location::HeaderLine(line),
            message: message.into(),
        }
    }

    pub fn row(element: &str, row: u64, message: impl Into<String>) -> Self {
        Problem {
            location: Location::Row {
                element: element.to_owned(),
                row,
                line: None,
            },
            message: message.into(),
        }
    }

    pub fn at_line(mut self, line: usize) -> Self {
        if let Location::Row { line: l, .. } = &mut self.location {
            *l = Some(line);
        }
        self
    }

    pub fn in_file(self, path: &Path) -> PlyError {
        PlyError {
            path: path.to_owned(),
            location: self.location,
            message: self.message,
        }
    }
}
