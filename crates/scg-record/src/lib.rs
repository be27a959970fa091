//! scg-record: Rerun (.rrd) and MCAP recordings of scg runs, and reading them back.
//!
//! Two [`FrameSink`](scg_core::frame::FrameSink)s write a run as it goes:
//!
//! * [`RrdSink`] writes a Rerun recording (`.rrd`) for viewing: one `Points3D` entity per
//!   particle group, the scene geometry as static line strips, the run's scalars as time
//!   series, on the timelines `sim_time` and `step`.
//! * [`McapSink`] writes an MCAP file: the full particle state of every frame as a
//!   `foxglove.PointCloud` (protobuf, float64 fields), the scalars as JSON, the run
//!   description as a metadata record and the scene file as an attachment. It is the archival
//!   format: [`read_mcap`] reads it back bit for bit, and recovers what a killed run left.
//!
//! [`write_rrd`] turns a [`Recording`] read from an MCAP file into a Rerun recording with the
//! same layout as a live run. Both sinks write to `<path>.partial` and rename the file to
//! `<path>` only when the run finishes, so a crashed run never replaces an earlier good file.
//!
//! The layouts are described in `docs/recordings.md` and by the constants in [`layout`].

use std::path::{Path, PathBuf};

use scg_core::frame::{Frame, RunMeta};

mod background;
mod blueprint;
pub mod checkpoint;
pub mod layout;
mod mcap_read;
mod mcap_scene;
mod mcap_write;
mod parts;
mod rrd_write;
pub mod vtk;

pub use background::Background;
pub use mcap_read::{McapFrames, read_mcap};
pub use mcap_write::{McapOptions, McapSink};
pub use rrd_write::{RrdSink, write_rrd};
pub use vtk::{CsvSink, VtkSink};

/// Errors of the recorders and readers.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// A file could not be created, read, written or renamed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The Rerun SDK refused a log call or could not encode the stream.
    #[error("rerun: {0}")]
    Rerun(String),
    /// The MCAP library failed to write or read a record.
    #[error("mcap: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A message could not be encoded.
    #[error("could not encode a message: {0}")]
    Encode(String),
    /// A file is readable but is not an scg recording (or is damaged beyond recovery).
    #[error("{}: not a valid scg recording: {reason}", path.display())]
    Format {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A frame handed to a sink is inconsistent (vector lengths, group index, time…).
    #[error("invalid frame (step {step}): {reason}")]
    InvalidFrame {
        /// The frame's step.
        step: u64,
        /// What is wrong with it.
        reason: String,
    },
    /// A frame was written after `finish()`.
    #[error("the recording is already finished")]
    Finished,
}

impl RecordError {
    /// Wraps an I/O error with the path it concerns.
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// A recording read back from a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// The run description stored in the file.
    pub meta: RunMeta,
    /// Every complete frame, in the order written.
    pub frames: Vec<Frame>,
    /// True when the file was closed properly (summary and footer present and valid); false
    /// for a file cut short, e.g. by a killed run, whose complete frames were recovered.
    pub complete: bool,
    /// The wear of the walls at the end of a run with `[erosion]` (`None` without, or when
    /// the run did not finish).
    pub wear: Option<scg_core::frame::WearMap>,
}

/// `<path>.partial`: where a sink writes until it is finished.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

/// Checks that a frame's vectors have one entry per particle and that its group indices
/// refer to `n_groups` groups.
pub(crate) fn check_frame(frame: &Frame, n_groups: usize) -> Result<(), RecordError> {
    let n = frame.id.len();
    let bad = |reason: String| RecordError::InvalidFrame {
        step: frame.step,
        reason,
    };
    for (name, len) in [
        ("group", frame.group.len()),
        ("position", frame.position.len()),
        ("velocity", frame.velocity.len()),
        ("diameter", frame.diameter.len()),
        ("density", frame.density.len()),
    ] {
        if len != n {
            return Err(bad(format!("{n} ids but {len} entries in `{name}`")));
        }
    }
    let m = frame.fluctuation.len();
    if m != 0 && m != n {
        return Err(bad(format!("{n} ids but {m} entries in `fluctuation`")));
    }
    if let Some(g) = frame.group.iter().find(|&&g| g as usize >= n_groups) {
        return Err(bad(format!(
            "group index {g} out of range ({n_groups} groups)"
        )));
    }
    if !(frame.time.is_finite() && frame.time >= 0.0) {
        return Err(bad(format!(
            "time {} is not a finite non-negative number",
            frame.time
        )));
    }
    Ok(())
}

/// Renames the finished `<path>.partial` to `<path>`.
pub(crate) fn commit_partial(partial: &Path, path: &Path) -> Result<(), RecordError> {
    std::fs::rename(partial, path).map_err(|e| RecordError::io(path, e))
}
