//! How opening a model tells its progress: one trait for every step, from reading the
//! file to uploading it, heard by `spt convert`'s progress bars and the viewer's loader.

use crate::io::model::Model;
use crate::surfel::LeafSurfels;

use super::TreeMeta;

/// A step of opening a model, in the order they come.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// A model file read into geometry (work: the file's bytes).
    Read,
    /// Leaf surfels made.
    Surfels,
    /// The hierarchy built (work: leaves).
    Hierarchy,
    /// Node disks and errors computed (work: internal nodes).
    Errors,
    /// The sequential list sorted.
    Sort,
    /// An `.spt` file mapped and checked.
    Check,
    /// The prefix index built.
    Index,
    /// The list uploaded to the GPU (work: nodes).
    Upload,
    /// The mesh of the reference pass uploaded.
    Mesh,
}

impl Step {
    /// The step as the viewer's progress shows it.
    pub fn name(self) -> &'static str {
        match self {
            Step::Read => "reading",
            Step::Surfels => "surfels",
            Step::Hierarchy => "tree",
            Step::Errors => "errors",
            Step::Sort => "sorting",
            Step::Check => "checking",
            Step::Index => "indexing",
            Step::Upload => "uploading",
            Step::Mesh => "mesh",
        }
    }
}

/// What a step made, told when it ends.
pub enum Finished<'a> {
    Read(&'a Model),
    Surfels(&'a LeafSurfels),
    Hierarchy { leaves: u64, internal: u64 },
    Errors(&'a TreeMeta),
    Sort { nodes: u64 },
}

/// Hears how opening a model goes. Every method has a default that ignores it.
pub trait Report: Sync {
    /// `step` begins, with its amount of work (0 when unknown).
    fn step(&self, _step: Step, _total: u64) {}
    /// `n` more units of the current step are done (from any thread).
    fn advance(&self, _n: u64) {}
    /// The current step ended with `what`.
    fn finished(&self, _what: Finished) {}
}

/// A [`Report`] that ignores everything.
pub struct Silent;

impl Report for Silent {}
