//! The second step of an out-of-core build: one job, alone, from the [`Manifest`] and its
//! input files, into its part file and record ([`PartRecord`]). A job whose record and
//! part are whole and of this plan and build parameters is kept; any other is built,
//! after its inputs are checked against their checksums. The same inputs give the same
//! part, byte for byte, so a job may run twice, or on two machines at once.

use std::path::Path;

use glam::DVec3;

use super::Behind;
use super::checksums::{self, Check};
use super::job::{self, Model};
use super::manifest::Manifest;
use super::mesh_job;
use super::record::{PartRecord, part_name};
use super::spill::JobFiles;

/// What [`run`] did with a job.
#[derive(Debug, Clone)]
pub enum Ran {
    Built(PartRecord),
    /// Its part was already built for this plan.
    Kept(PartRecord),
}

/// The record of job `j` in `dir` when its part is whole (by `check`) and built for
/// `manifest`.
pub fn done(
    dir: &Path,
    manifest: &Manifest,
    j: usize,
    check: Check,
) -> anyhow::Result<Option<PartRecord>> {
    let Some(record) = PartRecord::read(dir, j).unwrap_or(None) else {
        return Ok(None);
    };
    let current = record.plan == manifest.id() && record.built_with == manifest.build;
    Ok((current && record.part_intact(check)?).then_some(record))
}

/// Runs job `j` of the plan in `dir` (its manifest `manifest`), its input files and a
/// part already there checked by `check`; returns once its part and record are written.
pub fn run(dir: &Path, manifest: &Manifest, j: usize, check: Check) -> anyhow::Result<Ran> {
    let mut behind = Behind::default();
    let ran = run_behind(dir, manifest, j, check, &mut behind)?;
    behind.finish()?;
    Ok(ran)
}

/// [`run`], the part file and then its record written `behind` the lane: the record
/// returned names a part that is whole once `behind` has finished.
pub fn run_behind(
    dir: &Path,
    manifest: &Manifest,
    j: usize,
    check: Check,
    behind: &mut Behind,
) -> anyhow::Result<Ran> {
    let jobs = manifest.jobs.len();
    let Some(entry) = manifest.jobs.get(j) else {
        anyhow::bail!(
            "{}: no job {j} (the plan has jobs 0 to {})",
            dir.display(),
            jobs - 1
        );
    };
    if let Some(record) = done(dir, manifest, j, check)? {
        return Ok(Ran::Kept(record));
    }
    for f in &entry.files {
        checksums::verify(dir, f, check).map_err(|e| {
            e.context(format!(
                "job {j}: an input file differs from the plan; plan again (`spt jobs plan`)"
            ))
        })?;
    }
    let model = Model {
        error_scale: manifest.build.error_scale,
        ..manifest.model.clone()
    };
    let part = dir.join(part_name(j));
    let file = |role| entry.file(dir, role);
    let missing = |role| anyhow::anyhow!("job {j}: the plan lists no {role} file");
    let (own, halo) = (
        file("own").ok_or_else(|| missing("own"))?,
        file("halo").ok_or_else(|| missing("halo"))?,
    );
    let (built, vote) = if manifest.input.mesh {
        let triangles = file("tri").ok_or_else(|| missing("tri"))?;
        let c = DVec3::from(manifest.input.vote_centre);
        let (built, vote) = mesh_job::build(
            &model,
            (&own, &halo, &triangles),
            (manifest.build.turn, c),
            &part,
        )?;
        (built, Some(vote))
    } else {
        let normals = (file("own_normals"), file("halo_normals"));
        let normals = match &normals {
            (Some(o), Some(h)) => Some((o.as_path(), h.as_path())),
            _ => None,
        };
        let files = JobFiles {
            own: &own,
            halo: &halo,
            normals,
        };
        (job::build(&model, files, &part)?, None)
    };
    let record = PartRecord {
        job: j,
        plan: manifest.id(),
        built_with: manifest.build,
        file: built.file.clone(),
        part: built.part.clone(),
        vote,
    };
    let (dir, written) = (dir.to_owned(), record.clone());
    behind.start(move || {
        built.write()?;
        written.write(&dir)
    })?;
    Ok(Ran::Built(record))
}
