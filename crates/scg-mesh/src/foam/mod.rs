//! OpenFOAM cases: the mesh (`constant/polyMesh`), volVectorFields ([`read_vector_field`])
//! and volScalarFields ([`read_scalar_field`]: turbulence `k`, `epsilon`, `omega`, `nut`) in
//! time directories, rotating-frame properties ([`read_srf`], [`read_mrf`]), and writers
//! for the first three.
//!
//! Reads what OpenFOAM writes: the `FoamFile` header (`format ascii|binary`, `arch
//! "LSB;label=32;scalar=64"`, also `label=64`, `scalar=32` and `MSB`), `//` and `/* */`
//! comments, ASCII and binary lists (`N (...)`, `N (<raw bytes>)`, `N{value}`), faces as
//! `faceList` or `faceCompactList`, every file optionally gzipped (`points.gz`). Dictionary
//! directives (`#include`, …) and `$var` macros are rejected with an error naming the entry.

pub mod boundary;
mod field;
mod frame;
#[cfg(test)]
mod fuzz_tests;
mod mesh;
pub(crate) mod parse;
mod scalar;
mod write;

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::MeshError;

pub use field::read_vector_field;
pub use frame::{MrfZone, Srf, read_mrf, read_srf};
pub use mesh::{read_cell_zones, read_mesh};
pub use scalar::read_scalar_field;
pub use write::{Format, write_case, write_scalar_field, write_vector_field};

/// Which time directory to read a field from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeSel {
    /// The largest numeric time directory (which may be `0`).
    Latest,
    /// The time directory whose name parses to this number, s.
    Time(f64),
}

/// The numeric time directories of a case, sorted by time: `(time in s, directory)`.
pub fn time_dirs(case_dir: impl AsRef<Path>) -> Result<Vec<(f64, PathBuf)>, MeshError> {
    let case_dir = case_dir.as_ref();
    let io = |source| MeshError::Io {
        file: case_dir.to_path_buf(),
        source,
    };
    let mut out = Vec::new();
    for entry in std::fs::read_dir(case_dir).map_err(io)? {
        let entry = entry.map_err(io)?;
        let Some(name) = entry.file_name().to_str().map(str::to_owned) else {
            continue;
        };
        let Ok(t) = name.parse::<f64>() else { continue };
        if t.is_finite() && entry.path().is_dir() {
            out.push((t, entry.path()));
        }
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(out)
}

/// The time directory `sel` picks.
pub fn select_time(case_dir: impl AsRef<Path>, sel: TimeSel) -> Result<PathBuf, MeshError> {
    let case_dir = case_dir.as_ref();
    let dirs = time_dirs(case_dir)?;
    let found = match sel {
        TimeSel::Latest => dirs.last(),
        TimeSel::Time(t) => dirs
            .iter()
            .find(|(d, _)| (d - t).abs() <= 1e-12 * t.abs().max(1.0)),
    };
    match found {
        Some((_, p)) => Ok(p.clone()),
        None => {
            let list: Vec<String> = dirs
                .iter()
                .map(|(_, p)| {
                    p.file_name()
                        .unwrap_or_default()
                        .to_string_lossy()
                        .into_owned()
                })
                .collect();
            Err(MeshError::invalid(
                case_dir,
                "time",
                match sel {
                    TimeSel::Latest => "no numeric time directory in the case".to_string(),
                    TimeSel::Time(t) => {
                        format!("no time directory for t = {t} (found: {})", list.join(" "))
                    }
                },
            ))
        }
    }
}

/// Read `base`, or `base.gz` (gunzipped) when `base` does not exist. Returns the path read
/// and its bytes.
pub(crate) fn read_maybe_gz(base: &Path) -> Result<(PathBuf, Vec<u8>), MeshError> {
    match std::fs::read(base) {
        Ok(b) => return Ok((base.to_path_buf(), b)),
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(MeshError::Io {
                file: base.to_path_buf(),
                source: e,
            });
        }
        Err(_) => {}
    }
    let mut gz = base.as_os_str().to_owned();
    gz.push(".gz");
    let gz = PathBuf::from(gz);
    let raw = std::fs::read(&gz).map_err(|e| MeshError::Io {
        file: if e.kind() == std::io::ErrorKind::NotFound {
            base.to_path_buf()
        } else {
            gz.clone()
        },
        source: e,
    })?;
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(&raw[..])
        .read_to_end(&mut out)
        .map_err(|e| MeshError::invalid(&gz, "gzip", format!("cannot decompress: {e}")))?;
    Ok((gz, out))
}
