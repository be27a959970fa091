//! Checkpoint files: `SCGCKPT` and a format number, then the [`Checkpoint`] in postcard
//! (a compact binary serde format; f64 values as their 8 bytes, so a restart is exact).
//! Written to a temporary file, synced and renamed, so a run killed while writing leaves
//! the previous checkpoint whole.

use std::io::Write;
use std::path::Path;

use scg_core::checkpoint::Checkpoint;

const MAGIC: &[u8; 8] = b"SCGCKPT\0";
/// 2: particle records carry the carrier offset and the dispersion state; 3: the
/// collecting zones' log; 4: the particles waiting in a collecting zone; 5: the erosion
/// log; 6: its impact angles and speeds per face.
const FORMAT: u32 = 6;

/// Write `c` to `path` atomically.
pub fn write_checkpoint(path: &Path, c: &Checkpoint) -> Result<(), String> {
    let body = postcard::to_stdvec(c).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp);
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(MAGIC)?;
        f.write_all(&FORMAT.to_le_bytes())?;
        f.write_all(&body)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| format!("{}: {e}", path.display()))
}

/// Read a checkpoint written by [`write_checkpoint`].
pub fn read_checkpoint(path: &Path) -> Result<Checkpoint, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = |m: &str| format!("{}: {m}", path.display());
    if bytes.len() < 12 || &bytes[..8] != MAGIC {
        return Err(bad("not an scg checkpoint"));
    }
    let format = u32::from_le_bytes(bytes[8..12].try_into().unwrap_or_default());
    if format != FORMAT {
        return Err(bad(&format!(
            "checkpoint format {format}; this scg reads format {FORMAT}"
        )));
    }
    let (c, rest): (Checkpoint, &[u8]) = postcard::take_from_bytes(&bytes[12..])
        .map_err(|e| bad(&format!("damaged checkpoint: {e}")))?;
    if !rest.is_empty() {
        return Err(bad("damaged checkpoint: trailing bytes"));
    }
    Ok(c)
}
