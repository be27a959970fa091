//! Bad input never hurts: random and mutated scene files and random `--set` arguments go
//! through `scg_scene::parse`, `check::check` and `Scene::build` (plus two steps): no
//! panic, no hang, no case holding more than 2 GB ([`MEMORY_CAP`]), and every rejection is
//! a `SceneError` that names a key or a line.
//!
//! The number of cases comes from `PROPTEST_CASES` (default 2 000, a few seconds). CI runs
//! `PROPTEST_CASES=100000 cargo test --release --test fuzz_scenes` (see `.ci/run`). Each
//! run prints its seed; `PROPTEST_RNG_SEED=<seed>` replays it.
//! A few handpicked command lines exercise the `scg` binary itself.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Write;
use std::process::Command;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};

use scg::scene::{SceneError, check, error, parse};

/// Scenes the mutations start from: every case file plus small inline scenes that reach
/// the other tables (contacts, regions, planes, gravity, linear contacts).
fn seeds() -> Vec<String> {
    let mut out = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(common::repo("cases"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    // Paths in the case files are relative to cases/; the mutated text is parsed as
    // `fuzz.toml` in the working folder, so make them absolute.
    let dir = common::repo("cases");
    for f in files {
        let text = std::fs::read_to_string(f).unwrap();
        let text: Vec<String> = text
            .lines()
            .map(|l| {
                for key in ["case = \"", "file = \""] {
                    if let Some(rest) = l.strip_prefix(key)
                        && !rest.starts_with('/')
                    {
                        return format!("{key}{}/{rest}", dir.display());
                    }
                }
                l.to_string()
            })
            .collect();
        out.push(text.join("\n"));
    }
    out.push(
        r#"
name = "box"
duration = 1e-3
dt = "auto"
[gravity]
acceleration = [0.0, 0.0, -9.81]
[material]
youngs_modulus = 1e8
poisson_ratio = 0.3
restitution = 0.7
friction = 0.3
normal_model = "linear"
linear_stiffness = 1e4
[contacts]
periodic = [0.012, 0.012, 0.012]
rolling_friction = 0.01
tangential_stiffness_ratio = 0.8
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[groups]]
name = "small"
diameter = 1e-3
density = 2500.0
count = 30
velocity = [0.2, -0.1, 0.3]
region = { kind = "box", min = [0.0, 0.0, 0.001], max = [0.012, 0.012, 0.012] }
[[groups]]
name = "ring"
diameter = 2e-3
density = 2500.0
alpha = 2.0
law = "parcel"
count = 5
color = [10, 20, 30]
region = { kind = "cylinder", center = [0.006, 0.006, 0.006], radius_min = 0.001, radius_max = 0.004, height = [0.0, 0.004] }
"#
        .to_string(),
    );
    out.push(
        r#"
duration = 0.01
dt = 1e-3
integrator = "explicit"
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "uniform"
velocity = [1.0, 0.0, 0.0]
[drag]
law = "schiller_naumann"
[[groups]]
name = "a"
diameter = 1e-4
density = 1000.0
positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
velocities = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
"#
        .to_string(),
    );
    // A CFD flow with an inlet-patch feeder, contact wall patches and an STL wall.
    out.push(common::cfd_box_scene());
    out
}

/// Values a mutation writes in place of a number (or a `--set` value).
const VALUES: &[&str] = &[
    "-1",
    "0",
    "0.0",
    "-0.0",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-300",
    "5e-324",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "\"x\"",
    "\"auto\"",
    "true",
    "[1, 2]",
    "[]",
    "[[0.0, 0.0, 0.0]]",
    "{ a = 1 }",
    "0.5",
    "2",
    "16",
    "1e9",
    "1e-9",
    "0.999",
];

const KEYS: &[&str] = &[
    "duration",
    "dt",
    "record_every",
    "seed",
    "integrator",
    "name",
    "fluid.density",
    "fluid.viscosity",
    "flow.kind",
    "flow.rpm",
    "flow.velocity",
    "flow.inflow_ratio",
    "drag.law",
    "gravity.acceleration",
    "material.youngs_modulus",
    "material.restitution",
    "material.poisson_ratio",
    "material.friction",
    "contacts.skin",
    "contacts.periodic",
    "walls.0.radius",
    "walls.0.kind",
    "groups.0.alpha",
    "groups.0.law",
    "groups.0.diameter",
    "groups.0.density",
    "groups.0.positions",
    "groups.0.count",
    "groups.1.name",
    "groups.9.alpha",
    "groups.x.alpha",
    "groups.0.alpha.inner",
    "coarse_grain.alpha",
    "coarse_grain.law",
    "flow.case",
    "flow.time",
    "flow.field",
    "flow.interpolation",
    "flow.scale",
    "flow.patches.walls",
    "flow.patches.inlets",
    "flow.patches.outlets",
    "flow.patches.wall_model",
    "feeders.0.patch",
    "feeders.0.velocity",
    "feeders.0.rate",
    "feeders.1.interval",
    "walls.0.file",
    "a.b.c",
    "",
];

#[derive(Clone, Debug)]
enum Op {
    DeleteLine(usize),
    DuplicateLine(usize),
    SwapLines(usize, usize),
    Number(usize, usize),
    SwapType(usize),
    Bytes(usize, Vec<u8>),
    Truncate(usize),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        any::<usize>().prop_map(Op::DeleteLine),
        any::<usize>().prop_map(Op::DuplicateLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Op::SwapLines(a, b)),
        (any::<usize>(), 0..VALUES.len()).prop_map(|(a, b)| Op::Number(a, b)),
        (any::<usize>(), 0..VALUES.len()).prop_map(|(a, b)| Op::Number(a, b)),
        any::<usize>().prop_map(Op::SwapType),
        (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(a, b)| Op::Bytes(a, b)),
        any::<usize>().prop_map(Op::Truncate),
    ]
}

/// Byte ranges of the numbers in `text`.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start_ok = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if start_ok
            && (b[i].is_ascii_digit()
                || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit()))
        {
            let s = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_digit() || matches!(b[i], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                i += 1;
            }
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

fn floor_char(text: &str, mut i: usize) -> usize {
    i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, op: &Op) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len().max(1);
    match op {
        Op::DeleteLine(i) => {
            let mut l = lines.clone();
            if !l.is_empty() {
                l.remove(i % n);
            }
            l.join("\n")
        }
        Op::DuplicateLine(i) => {
            let mut l = lines.clone();
            if !l.is_empty() {
                l.insert(i % n, lines[i % n]);
            }
            l.join("\n")
        }
        Op::SwapLines(a, b) => {
            let mut l = lines.clone();
            if !l.is_empty() {
                l.swap(a % n, b % n);
            }
            l.join("\n")
        }
        Op::Number(k, v) => {
            let nums = numbers(text);
            if nums.is_empty() {
                return text.to_string();
            }
            let (s, e) = nums[k % nums.len()];
            format!("{}{}{}", &text[..s], VALUES[*v], &text[e..])
        }
        Op::SwapType(k) => {
            // A quoted string becomes a number, or a number becomes a string.
            let nums = numbers(text);
            if k % 2 == 0 && !nums.is_empty() {
                let (s, e) = nums[k / 2 % nums.len()];
                format!("{}\"{}\"{}", &text[..s], &text[s..e], &text[e..])
            } else if let Some(q) = text.match_indices('"').nth(2 * (k / 2 % 8)) {
                let s = q.0;
                match text[s + 1..].find('"') {
                    Some(e) => format!("{}42{}", &text[..s], &text[s + 2 + e..]),
                    None => text.to_string(),
                }
            } else {
                text.to_string()
            }
        }
        Op::Bytes(at, bytes) => {
            let i = floor_char(text, at % (text.len() + 1));
            let junk = String::from_utf8_lossy(bytes);
            format!("{}{}{}", &text[..i], junk, &text[i..])
        }
        Op::Truncate(at) => text[..floor_char(text, at % (text.len() + 1))].to_string(),
    }
}

fn set_arg() -> impl Strategy<Value = String> {
    prop_oneof![
        (0..KEYS.len(), 0..VALUES.len()).prop_map(|(k, v)| format!("{}={}", KEYS[k], VALUES[v])),
        (0..KEYS.len(), "[a-z_ ]{0,6}").prop_map(|(k, v)| format!("{}={v}", KEYS[k])),
        "[ -~]{0,12}",
    ]
}

/// Steps each case runs (or its whole run, if shorter).
const STEPS: u64 = 2;

/// Particles a case holds over its steps: at the start and fed (skip building huge ones).
fn case_particles(s: &scg::scene::Scene) -> u64 {
    s.particles_after(STEPS.min(s.steps()))
}

fn check_error(e: &SceneError, text: &str, sets: &[String]) -> Result<(), TestCaseError> {
    prop_assert!(!e.message.trim().is_empty(), "empty message: {e:?}");
    prop_assert!(!e.file.is_empty());
    if e.file.ends_with("(--set)") {
        prop_assert!(e.key.is_some(), "--set error without a key: {e:?}");
        return Ok(());
    }
    prop_assert!(
        e.key.is_some() || e.line.is_some(),
        "error names neither key nor line: {e}"
    );
    // A key that is written in the file (and not replaced by --set) comes with its line.
    if let Some(k) = &e.key
        && sets.is_empty()
        && error::locate(text, k).is_some()
    {
        prop_assert!(
            e.line.is_some(),
            "key `{k}` is in the file but no line: {e}"
        );
    }
    Ok(())
}

/// One case; returns how long it took.
fn one_case(text: &str, sets: &[String]) -> Result<(), TestCaseError> {
    match parse(text, "fuzz.toml", "fuzz", sets) {
        Err(e) => check_error(&e, text, sets)?,
        Ok(scene) => {
            let r = check::check(&scene);
            let _ = check::render(&scene, &r);
            let _ = scene.run_meta(r.messages());
            if case_particles(&scene) <= 5_000 {
                let mut sim = scene.build(false);
                for _ in 0..STEPS.min(scene.steps()) {
                    if sim.step().is_err() {
                        break;
                    }
                }
            }
        }
    }
    Ok(())
}

/// The runner's seed: `PROPTEST_RNG_SEED` if set, else a fresh one. It is written to the
/// process's stderr before the run, outside the test harness's capture, so that a case
/// which kills the process (the OOM killer) can still be replayed with
/// `PROPTEST_RNG_SEED=<seed> PROPTEST_CASES=<n> cargo test --release --test fuzz_scenes`.
fn rng_seed(test: &str) -> u64 {
    let seed = std::env::var("PROPTEST_RNG_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            use std::hash::{BuildHasher, RandomState};
            RandomState::new().hash_one(Instant::now())
        });
    let _ = writeln!(
        std::io::stderr(),
        "{test}: PROPTEST_RNG_SEED={seed} PROPTEST_CASES={}",
        cases()
    );
    seed
}

// ── memory: no case may hold more than `MEMORY_CAP` ─────────────────────────────────────

/// The most a case may hold at once (bytes, every thread's allocations together). The
/// largest legitimate case (5 000 particles, the CFD seed's mesh and locator) holds tens
/// of MB; a case that asks for more than this is a scene whose size validation let
/// through.
const MEMORY_CAP: usize = 2 << 30;

/// The system allocator, counting the bytes held. An allocation that would take the
/// total past [`MEMORY_CAP`] while a case runs writes the case to stderr and aborts: a
/// runaway case is named, not left to the OOM killer.
struct Capped;

static HELD: AtomicUsize = AtomicUsize::new(0);
/// [`MEMORY_CAP`], or `SCG_FUZZ_MEMORY_CAP` (bytes) to hunt smaller runaways.
static CAP: AtomicUsize = AtomicUsize::new(MEMORY_CAP);
static CAPPED: AtomicBool = AtomicBool::new(false);
static CASE: Mutex<String> = Mutex::new(String::new());

impl Capped {
    /// Count `bytes` more held; over the cap while a case runs, name it and stop.
    #[inline]
    fn take(bytes: usize) {
        let held = HELD.fetch_add(bytes, Ordering::Relaxed) + bytes;
        if held > CAP.load(Ordering::Relaxed) && CAPPED.load(Ordering::Relaxed) {
            over_cap(bytes);
        }
    }
}

unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        Capped::take(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        HELD.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        Capped::take(layout.size());
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            Capped::take(new_size - layout.size());
        } else {
            HELD.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Capped = Capped;

/// Name the case and stop (no allocation here: the case text was written beforehand).
#[cold]
fn over_cap(asked: usize) -> ! {
    CAPPED.store(false, Ordering::Relaxed);
    let mut err = std::io::stderr().lock();
    let _ = writeln!(
        err,
        "\nfuzz_scenes: a case asked for {asked} bytes with more than {} held; the case:",
        CAP.load(Ordering::Relaxed)
    );
    if let Ok(case) = CASE.try_lock() {
        let _ = err.write_all(case.as_bytes());
    }
    let _ = writeln!(err);
    std::process::abort()
}

/// [`one_case`] under the memory cap, the case written down first to be named if it
/// breaks it.
fn capped_case(text: &str, sets: &[String]) -> Result<(), TestCaseError> {
    static FROM_ENV: std::sync::Once = std::sync::Once::new();
    FROM_ENV.call_once(|| {
        if let Some(cap) = std::env::var("SCG_FUZZ_MEMORY_CAP")
            .ok()
            .and_then(|s| s.parse().ok())
        {
            CAP.store(cap, Ordering::Relaxed);
        }
    });
    let described = format!("--set {sets:?}, text:\n{text}");
    *CASE.lock().unwrap_or_else(|e| e.into_inner()) = described;
    CAPPED.store(true, Ordering::Relaxed);
    let out = one_case(text, sets);
    CAPPED.store(false, Ordering::Relaxed);
    out
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2_000)
}

#[test]
fn mutated_scenes_never_hurt() {
    let seeds = seeds();
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        max_shrink_iters: 2_000,
        rng_seed: RngSeed::Fixed(rng_seed("mutated_scenes_never_hurt")),
        ..Config::default()
    });
    let strategy = (
        0..seeds.len(),
        proptest::collection::vec(op(), 0..5),
        proptest::collection::vec(set_arg(), 0..3),
    );
    let t0 = Instant::now();
    let slowest = Cell::new(Duration::ZERO);
    runner
        .run(&strategy, |(seed, ops, sets)| {
            let mut text = seeds[seed].clone();
            for o in &ops {
                text = apply(&text, o);
            }
            let t = Instant::now();
            let r = capped_case(&text, &sets);
            let dt = t.elapsed();
            slowest.set(slowest.get().max(dt));
            // No hang: the slowest legitimate case (an uncached contact-damping solve
            // for a tiny restitution) takes a few seconds.
            prop_assert!(dt < Duration::from_secs(20), "case took {dt:?}");
            r
        })
        .unwrap();
    eprintln!(
        "fuzz_scenes: {} cases in {:.1} s (slowest {:.3} s)",
        cases(),
        t0.elapsed().as_secs_f64(),
        slowest.get().as_secs_f64()
    );
}

#[test]
fn random_text_never_hurts() {
    let mut runner = TestRunner::new(Config {
        cases: (cases() / 10).max(100),
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(rng_seed("random_text_never_hurts")),
        ..Config::default()
    });
    runner
        .run(
            &("(?s).{0,200}", proptest::collection::vec(set_arg(), 0..2)),
            |(text, sets)| capped_case(&text, &sets),
        )
        .unwrap();
}

// ── the binary ──────────────────────────────────────────────────────────────────────────

fn scg(args: &[&str], dir: &std::path::Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let err =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    assert!(!err.contains("panicked"), "{args:?}: panic: {err}");
    (out.status.code().unwrap_or(-1), err)
}

#[test]
fn handpicked_command_lines_exit_2_without_panic() {
    let dir = tempfile::tempdir().unwrap();
    let case = common::repo("cases/uniform.toml");
    let case = case.to_str().unwrap();
    let bad: &[&[&str]] = &[
        &["--bogus"],
        &["run", "--set"],
        &["run", "does-not-exist.toml"],
        &["run", case, "--set", "noequals"],
        &["run", case, "--set", "groups.99.alpha=2"],
        &["run", case, "--set", "dt=-1"],
        &["run", case, "--set", "duration=nan"],
        &["check"],
        &["check", case, "--set", "groups.0.alpha.x=1"],
        &["check", "/"],
        &["cost", case, "--alphas", "0"],
        &["cost", case, "--laws", "magic"],
        &["cost", case, "--dt-mult", "0"],
        &["cost", case, "--integrators", "rk4"],
        &["bench", "drag", "--particles", "0"],
        &["replay", "does-not-exist.mcap"],
        &["run", "\u{1}\u{7f}"],
    ];
    for args in bad {
        let (code, err) = scg(args, dir.path());
        assert_eq!(code, 2, "{args:?} → {code}: {err}");
        assert!(err.contains("error"), "{args:?}: {err}");
        // one prefix, and no part of a message said twice ("error: error: …",
        // "file: file: …")
        for line in err.lines().filter(|l| l.starts_with("error:")) {
            let parts: Vec<&str> = line.split(": ").collect();
            assert!(
                parts.windows(2).all(|w| w[0] != w[1]) && !line[6..].contains("error:"),
                "{args:?}: {line}"
            );
        }
    }
}

#[test]
fn unwritable_output_folder_fails_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    // A regular file where the output folder should be: even root cannot create it.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, b"x").unwrap();
    let out = blocker.join("recordings");
    let case = common::repo("cases/vortex.toml");
    let t0 = Instant::now();
    let (code, err) = scg(
        &[
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        dir.path(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot create output folder"), "{err}");
    assert!(!err.contains("running `"), "failed before the run: {err}");
    assert!(
        t0.elapsed() < Duration::from_secs(10),
        "no 3 s run was started"
    );
}

/// The seeds are valid scenes as written (a seed that fails to parse would fuzz only the
/// first error it meets): the CFD seed loads its mesh, feeds through the inlet and steps.
#[test]
fn seeds_parse_and_run() {
    for (i, text) in seeds().iter().enumerate() {
        let scene =
            parse(text, "fuzz.toml", "fuzz", &[]).unwrap_or_else(|e| panic!("seed {i}: {e}"));
        if case_particles(&scene) <= 5_000 {
            let mut sim = scene.build(false);
            for _ in 0..3 {
                sim.step().unwrap_or_else(|e| panic!("seed {i}: {e}"));
            }
        }
    }
}
