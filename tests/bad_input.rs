//! Bad input: exit status 2 and a message naming the file, the key and the line; never a panic.

mod common;

use std::process::Command;

const GOOD: &str = r#"duration = 0.01
dt = 1e-3
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "uniform"
velocity = [1.0, 0.0, 0.0]
[drag]
law = "stokes"
[[groups]]
name = "a"
diameter = 1e-4
density = 1000.0
positions = [[0.0, 0.0, 0.0]]
"#;

fn check(text: &str) -> (i32, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .arg("check")
        .arg(&path)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "panic: {err}");
    (out.status.code().unwrap_or(-1), err)
}

fn expect(text: &str, key: &str, line: usize) {
    let (code, err) = check(text);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.toml"), "file named: {err}");
    assert!(
        err.contains(&format!("`{key}`")),
        "key `{key}` named: {err}"
    );
    assert!(
        err.contains(&format!("bad.toml:{line}:")),
        "line {line}: {err}"
    );
}

#[test]
fn good_scene_passes() {
    let (code, err) = check(GOOD);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn malformed_toml() {
    let (code, err) = check(&GOOD.replace("[drag]", "[drag"));
    assert_eq!(code, 2);
    assert!(err.contains("bad.toml:9:"), "{err}");
}

#[test]
fn unknown_key() {
    expect(
        &GOOD.replace("law = \"stokes\"", "law = \"stokes\"\nspeed = 3"),
        "drag.speed",
        11,
    );
}

#[test]
fn negative_and_zero_values() {
    expect(
        &GOOD.replace("diameter = 1e-4", "diameter = -1e-4"),
        "groups[0].diameter",
        13,
    );
    expect(
        &GOOD.replace("density = 1000.0", "density = 0.0"),
        "groups[0].density",
        14,
    );
    expect(&GOOD.replace("dt = 1e-3", "dt = 0.0"), "dt", 2);
    expect(&GOOD.replace("dt = 1e-3", "dt = -1.0"), "dt", 2);
    expect(
        &GOOD.replace("viscosity = 1.8e-5", "viscosity = -1"),
        "fluid.viscosity",
        5,
    );
}

#[test]
fn nan_and_infinity() {
    expect(
        &GOOD.replace("diameter = 1e-4", "diameter = nan"),
        "groups[0].diameter",
        13,
    );
    expect(
        &GOOD.replace("velocity = [1.0, 0.0, 0.0]", "velocity = [inf, 0.0, 0.0]"),
        "flow.velocity",
        8,
    );
}

#[test]
fn wrong_types_and_words() {
    let (code, err) = check(&GOOD.replace("duration = 0.01", "duration = \"long\""));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.toml:1:"), "{err}");
    expect(
        &GOOD.replace("kind = \"uniform\"", "kind = \"swirl\""),
        "flow.kind",
        7,
    );
    expect(&GOOD.replace("dt = 1e-3", "dt = \"often\""), "dt", 2);
}

#[test]
fn missing_file() {
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(["run", "/nonexistent/scene.toml", "--no-record"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("/nonexistent/scene.toml") && err.contains("cannot read"),
        "{err}"
    );
}

#[test]
fn bad_override() {
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(["run", "--no-record", "--set", "groups.9.alpha=2"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("groups.9.alpha"), "{err}");
}

/// `--set` edits the text in place: an error in an overridden value names the line it has
/// in the file, and the scene a recording stores keeps the file's comments.
#[test]
fn overrides_keep_line_numbers_and_comments() {
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/classifier.toml");
    let text = std::fs::read_to_string(case).unwrap();
    let line = text.lines().position(|l| l.starts_with("plane =")).unwrap() + 1;
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(["check", case, "--set", "outlet.plane=1.0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("classifier.toml:{line}: key `outlet.plane`")),
        "line {line}: {err}"
    );
    let scene = scg::scene::load(
        std::path::Path::new(case),
        &[
            "duration=0.01".to_string(),
            "coarse_grain.alpha=2".to_string(),
        ],
    )
    .unwrap();
    assert!(
        scene.source.starts_with("# The paper's classifier"),
        "{}",
        scene.source
    );
    assert_eq!(scene.source.lines().count(), text.lines().count());
    assert!(
        scene.source.contains("duration = 0.01 "),
        "comment after the value kept"
    );
}

#[test]
fn patch_feeders_need_a_mesh_flow_and_no_region() {
    // GOOD's lines 1–14 (the group fed, starting empty), then the feeder (15–19).
    let fed = GOOD.replace("positions = [[0.0, 0.0, 0.0]]\n", "")
        + "[[feeders]]\ngroup = \"a\"\nrate = 100.0\npatch = \"inlet\"\nvelocity = \"field\"\n";
    // `patch` without a mesh flow
    expect(&fed, "feeders[0].patch", 18);
    // `patch` and `region` together
    expect(
        &fed.replace(
            "velocity = \"field\"",
            "region = { kind = \"box\", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }",
        ),
        "feeders[0].patch",
        18,
    );
    // neither: the feeder's line
    let (code, err) = check(&fed.replace("patch = \"inlet\"\n", ""));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("`feeders[0].region`") && err.contains("needs `region` or `patch`"),
        "{err}"
    );
    assert!(
        err.contains("bad.toml:15:") || err.contains("bad.toml:16:"),
        "{err}"
    );
    // `velocity = "field"` on a region feeder, and an unknown word
    let region = fed.replace(
        "patch = \"inlet\"",
        "region = { kind = \"box\", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }",
    );
    expect(&region, "feeders[0].velocity", 19);
    expect(
        &region.replace("\"field\"", "\"fast\""),
        "feeders[0].velocity",
        19,
    );
}
