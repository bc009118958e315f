//! The last step of an out-of-core build: every part checked against its record and the
//! plan, then joined by the top tree into the `.spt` file ([`assemble::write_file`],
//! atomic). Only here are all parts seen together, so only here can two build
//! parameters be decided: the error scale (the leaves' own, when it exceeds the
//! model's by more than [`SCALE_SLACK`]) and a mesh's orientation (the whole model's
//! vote). When either differs from what the parts were built with, the manifest is
//! written with the new value and every part must be built again ([`Joined::Rebuild`]).

use std::path::Path;

use super::checksums::Check;
use super::job::{Model, Part};
use super::manifest::Manifest;
use super::plan::remove_inputs;
use super::read_ahead::AfterRead;
use super::record::{PartRecord, part_name};
use super::{Built, Progress, SCALE_SLACK, assemble};
use crate::surfel::outward::Vote;

/// What [`join`] did.
#[derive(Debug, Clone)]
pub enum Joined {
    Written(Built),
    /// The parts must be built again with the manifest's new parameters (the reason).
    Rebuild(String),
}

/// Each job's record, checked against the plan and its part file (by `check`): an error
/// names the first job that is missing, stale or damaged, and says how to mend it.
fn records(dir: &Path, m: &Manifest, check: Check) -> anyhow::Result<Vec<PartRecord>> {
    use rayon::prelude::*;
    let id = m.id();
    let again = |j: usize| format!("build it again: `spt jobs build {} {j}`", dir.display());
    (0..m.jobs.len())
        .into_par_iter()
        .map(|j| {
            let Some(r) = PartRecord::read(dir, j)? else {
                anyhow::bail!(
                    "job {j} has no part yet; build it: `spt jobs build {} {j}`",
                    dir.display()
                );
            };
            anyhow::ensure!(
                r.plan == id && r.built_with == m.build,
                "{}: built for another plan or other parameters; {}",
                r.part.path.display(),
                again(j)
            );
            anyhow::ensure!(
                r.part_intact(check)?,
                "{}: damaged or truncated: it does not hold the {} bytes of checksum {} that \
                 job {j} wrote; {}",
                dir.join(part_name(j)).display(),
                r.file.bytes,
                r.file.xxh3,
                again(j)
            );
            Ok(r)
        })
        .collect()
}

/// Joins the parts of the plan in `dir`, checked by `check`, into the `.spt` file
/// `output`. With [`AfterRead::Free`], once nothing can send the jobs back to be built
/// again, the job inputs are removed and each part's bytes freed as they are read.
pub fn join(
    dir: &Path,
    output: &Path,
    (check, after): (Check, AfterRead),
    progress: &dyn Progress,
) -> anyhow::Result<Joined> {
    let mut m = Manifest::read(dir)?;
    let records = records(dir, &m, check)?;
    let vote = (records.iter())
        .filter_map(|r| r.vote)
        .fold(Vote::default(), Vote::plus);
    let parts: Vec<Part> = (records.into_iter())
        .map(PartRecord::into_part)
        .collect::<anyhow::Result<_>>()?;
    // Errors are stored as f16 multiples of the scale, so it must not be far below
    // the leaves' own (their disks reach past the points' box by their radii, which
    // the scale from the points cannot know: on degenerate models, by far).
    let needed = parts.iter().map(|p| p.disk_extent).fold(0.0, f32::max);
    let turn = m.input.mesh && vote.turns();
    let reason = if needed > SCALE_SLACK * m.build.error_scale {
        let why = format!(
            "the leaves need an error scale of {needed}, the parts were built with {}",
            m.build.error_scale
        );
        m.build.error_scale = needed;
        Some(why)
    } else if turn != m.build.turn {
        m.build.turn = turn;
        Some("the parts' orientation vote differs from the plan's".to_owned())
    } else {
        None
    };
    if let Some(reason) = reason {
        m.build.round += 1;
        m.write(dir)?;
        return Ok(Joined::Rebuild(reason));
    }
    let model = Model {
        error_scale: m.build.error_scale,
        ..m.model.clone()
    };
    let two_sided = m.input.mesh && !vote.closed();
    if after == AfterRead::Free {
        remove_inputs(dir, &m)?;
    }
    let joined = (&m.split_tree()?, &parts[..], after);
    let meta = assemble::write_file(output, &model, joined, (two_sided, progress))?;
    Ok(Joined::Written(Built {
        meta,
        jobs: parts.len(),
        dropped: m.input.dropped,
        outliers: m.input.outliers,
        walls: parts.iter().map(|p| p.walls).sum(),
        rebuilt: m.build.turn != m.input.turn_guess,
    }))
}
