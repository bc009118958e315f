//! The command-line applications built on the library.

pub mod info;
