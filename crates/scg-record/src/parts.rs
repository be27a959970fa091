//! A recording written per MPI rank, read as one: the index file names its parts (one
//! MCAP per rank, the same layout, each holding its rank's particles of every frame and
//! its rank's counts), and [`merge_parts`] joins frame k of every part into the frame one
//! rank would have written: the particles of all parts sorted by id, the counts summed,
//! and the stats recomputed in id order (bit for bit those of one rank: a particle's
//! simulated mass is `sphere_mass` of its recorded diameter and density: `rows_of_frame`).

use std::path::Path;

use scg_core::frame::Frame;
use scg_core::stages::recording::{RecordingParams, frame_from_rows, rows_of_frame};
use scg_core::state::Tally;
use scg_core::stats::Stat;

use crate::{RecordError, Recording, read_mcap};

/// The recording the index `index` (already read: `rec`, no frame) and its parts make.
/// Complete when the index and every part are, with as many frames each; otherwise the
/// frames every part holds (a killed run). Errors: a part cannot be read, is itself an
/// index, holds frames of another step than the others at the same place, or the
/// index holds frames.
pub(crate) fn merge_parts(index: &Path, mut rec: Recording) -> Result<Recording, RecordError> {
    let format = |reason: String| RecordError::Format {
        path: index.to_path_buf(),
        reason,
    };
    if !rec.frames.is_empty() {
        return Err(format(format!(
            "an index of {} parts that holds frames itself",
            rec.meta.parts.len()
        )));
    }
    let dir = index.parent().unwrap_or(Path::new("."));
    let mut parts = Vec::with_capacity(rec.meta.parts.len());
    for name in &rec.meta.parts {
        let p = read_mcap(&dir.join(name))?;
        if !p.meta.parts.is_empty() {
            return Err(format(format!("part `{name}` is an index itself")));
        }
        parts.push(p);
    }
    let n = parts.iter().map(|p| p.frames.len()).min().unwrap_or(0);
    rec.complete &= parts
        .iter()
        .all(|p| p.complete && p.frames.len() == parts[0].frames.len());
    let params = RecordingParams {
        every: rec.meta.record_every.max(1),
        groups: rec.meta.groups.iter().map(|g| g.name.clone()).collect(),
    };
    let mut frames = Vec::with_capacity(n);
    for k in 0..n {
        let these: Vec<&Frame> = parts.iter().map(|p| &p.frames[k]).collect();
        if let Some((at, f)) = these
            .iter()
            .enumerate()
            .find(|(_, f)| f.step != these[0].step)
        {
            return Err(format(format!(
                "frame {k} is at step {} in part `{}` and at step {} in part `{}`",
                these[0].step, rec.meta.parts[0], f.step, rec.meta.parts[at]
            )));
        }
        frames.push(merge_frame(&these, &params));
    }
    rec.frames = frames;
    if rec.meta.patches.is_empty()
        && let Some(p) = parts.first()
    {
        rec.meta.patches.clone_from(&p.meta.patches);
    }
    rec.wear = None;
    Ok(rec)
}

/// One frame from the same frame of every part.
fn merge_frame(parts: &[&Frame], params: &RecordingParams) -> Frame {
    let groups = params.groups.len();
    let mut tally = Tally::new(groups);
    let stat = |f: &Frame, key: &str| f.stats.iter().find(|(k, _)| k == key).map(|(_, v)| *v);
    let with_collisions = parts.iter().any(|f| {
        params
            .groups
            .iter()
            .any(|g| stat(f, &Stat::Collisions(g).key()).is_some())
    });
    tally.collisions = vec![0; if with_collisions { groups } else { 0 }];
    let mut rows = Vec::with_capacity(parts.iter().map(|f| f.len()).sum());
    for f in parts {
        for (i, g) in params.groups.iter().enumerate() {
            // counts are integers, exact in f64
            tally.drained[i] += stat(f, &Stat::Drained(g).key()).unwrap_or(0.0) as u64;
            if with_collisions {
                tally.collisions[i] += stat(f, &Stat::Collisions(g).key()).unwrap_or(0.0) as u64;
            }
        }
        rows.extend(rows_of_frame(f));
    }
    let first = parts.first();
    frame_from_rows(
        first.map_or(0, |f| f.step),
        first.map_or(0.0, |f| f.time),
        params,
        &tally,
        rows,
    )
}
