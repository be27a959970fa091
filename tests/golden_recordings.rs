//! Recordings made by an earlier scg still replay bit for bit.
//!
//! `tests/fixtures/golden*.mcap` are recordings of an earlier scg. All three were first
//! recorded by commit cc41a42, before the core was laid out anew (one storage table,
//! stages and physics split), and replayed bit for bit after it. `golden.mcap` and
//! `golden-vortex.mcap` (which has wall contacts) were recorded again when the Tsuji
//! damping became its exact closed form, a deliberate change of the contact bits. Each
//! stores its scene; `scg replay --verify` re-runs it and compares every frame, every particle and
//! every field to the last bit. The three cover the Stokes fast path in a uniform flow and
//! in the vortex, and `golden.toml`: Schiller–Naumann drag with gravity, Hertz–Mindlin
//! contacts with friction and rolling resistance, frictional walls (rotation), a feeder
//! and an outlet. A change of physics shows here first; such a change must come with new
//! fixtures and the reason in its commit.
//!
//! The bits are those of x86-64 (libm's exp and sqrt on this platform); elsewhere the
//! test is skipped.

use std::path::Path;
use std::process::Command;

fn verify(name: &str) {
    if !cfg!(target_arch = "x86_64") {
        return;
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .arg("replay")
        .arg(&path)
        .arg("--verify")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && text.contains("bit-identical"),
        "{name}: {text}{err}"
    );
    eprintln!("{name}: {}", text.trim());
}

#[test]
fn uniform_flow_recording_replays_bit_for_bit() {
    verify("golden-uniform.mcap");
}

#[test]
fn vortex_recording_replays_bit_for_bit() {
    verify("golden-vortex.mcap");
}

#[test]
fn contacts_walls_feeder_outlet_recording_replays_bit_for_bit() {
    verify("golden.mcap");
}
