//! Unsteady fields (`[flow] series`): an OpenFOAM case's time directories (or a VTK
//! collection's files) as one field, linear in time between two snapshots. Against the
//! closed form (a uniform flow ramping in time, from either) and a fine reference
//! integration (a vortex whose rate ramps); a cycling window
//! against the same files written out in full, bit for bit; 1 and 2 threads and a
//! restart, bit for bit; the refusals, by key.
//!
//! Run: `cargo test --release --test flow_series -- --nocapture`.

mod common;

use std::path::Path;

use glam::DVec3;
use scg::scene::Scene;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{Format, write_case, write_scalar_field, write_vector_field};
use scg_mesh::{CellField, MeshGeometry, PolyMesh, ScalarField};

const SIDES: &str = r#"walls = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]"#;

/// A unit box of 6³ perturbed hexahedra, sides named.
fn unit_box() -> PolyMesh {
    BoxMesh::new(DVec3::ZERO, DVec3::ONE, [6, 6, 6])
        .shape(CellShape::Hex)
        .naming(PatchNaming::Sides)
        .perturbed(0.15, 3)
        .build()
        .unwrap()
}

/// `f` at the cell centres and at every boundary face centre (patch values, so that an
/// affine field is interpolated exactly up to the walls).
fn affine(mesh: &PolyMesh, f: impl Fn(DVec3) -> DVec3) -> CellField {
    let g = MeshGeometry::new(mesh).unwrap();
    CellField {
        cells: g.cell_centres.iter().map(|&c| f(c)).collect(),
        patches: mesh
            .patches
            .iter()
            .map(|p| {
                Some(
                    (p.start..p.start + p.size)
                        .map(|i| f(g.face_centres[i]))
                        .collect(),
                )
            })
            .collect(),
    }
}

/// A case in `dir/case` on `mesh` with one snapshot `field(t)` per time `t` of `times`
/// (each directory named by Rust's shortest form of its time).
fn series_case(dir: &Path, mesh: &PolyMesh, times: &[f64], field: impl Fn(f64) -> CellField) {
    let case = dir.join("case");
    write_case(&case, mesh, None, Format::Binary).unwrap();
    for &t in times {
        write_vector_field(&case, &format!("{t}"), "U", mesh, &field(t), Format::Binary).unwrap();
    }
}

fn load(dir: &Path, text: &str) -> Scene {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(dir: &Path, text: &str) -> String {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    match scg::scene::load(&path, &[]) {
        Ok(_) => panic!("the scene loaded"),
        Err(e) => e.to_string(),
    }
}

/// A scene on `dir/case` with `series` as `[flow.series]`'s body, Stokes drag, one
/// 100 µm particle of density `rho` at `x0` with velocity `v0`.
fn scene_text(series: &str, duration: f64, dt: f64, rho: f64, x0: DVec3, v0: DVec3) -> String {
    format!(
        "duration = {duration:e}\ndt = {dt:e}\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n\
         [flow]\nkind = \"openfoam\"\ncase = \"case\"\nseries = {{ {series} }}\n\
         [flow.patches]\n{SIDES}\nwall_model = \"rebound\"\nrestitution = 1.0\n\
         [drag]\nlaw = \"stokes\"\n[[groups]]\nname = \"p\"\ndiameter = 1.0e-4\n\
         density = {rho:e}\npositions = [[{:e}, {:e}, {:e}]]\nvelocities = [[{:e}, {:e}, {:e}]]\n",
        x0.x, x0.y, x0.z, v0.x, v0.y, v0.z
    )
}

/// τ = ρd²/(18μ) of the scene's particle.
fn tau(rho: f64) -> f64 {
    rho * 1.0e-8 / (18.0 * 1.8e-5)
}

/// U(t) = a + b·t, uniform, from snapshots 0.25 s apart: the particle's position against
/// the closed form of dv/dt = (a + b·t − v)/τ.
#[test]
fn a_uniform_flow_ramping_in_time_moves_a_particle_as_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = unit_box();
    let (a, b) = (DVec3::new(0.2, 0.05, -0.1), DVec3::new(0.4, -0.2, 0.3));
    series_case(dir.path(), &mesh, &[0.0, 0.25, 0.5], |t| {
        affine(&mesh, |_| a + b * t)
    });
    let (rho, x0, v0) = (1.0e3, DVec3::new(0.3, 0.5, 0.4), DVec3::new(-0.3, 0.1, 0.2));
    let tau = tau(rho);
    let dt = 1.0 / 16384.0;
    let duration = 0.5;
    let sc = load(dir.path(), &scene_text("", duration, dt, rho, x0, v0));
    let worst = ramp_error(&sc, (a, b), x0, v0, tau);
    println!("τ = {tau:.4e} s, dt = {dt:e} s: largest position error {worst:.3e} m");
    assert!(worst <= 1e-9, "{worst:e} m");
}

/// The largest distance over the run of `sc` between its one particle and the closed form
/// of dv/dt = (a + b·t − v)/τ from x0, v0.
fn ramp_error(sc: &Scene, (a, b): (DVec3, DVec3), x0: DVec3, v0: DVec3, tau: f64) -> f64 {
    let mut sim = sc.build(false);
    let mut worst = 0.0_f64;
    for i in 0..sc.steps() {
        sim.step().unwrap();
        let t = (i + 1) as f64 * sc.dt;
        let c = v0 - a + b * tau;
        let e = (-t / tau).exp();
        let x = x0 + a * t + b * (0.5 * t * t - tau * t) + c * tau * (1.0 - e);
        worst = worst.max((sim.particles()[0].position - x).length());
    }
    worst
}

/// `u` written as one legacy VTK file per time of `times` in `dir` (`u_k.vtk`) and the
/// ParaView collection `dir/u.pvd` listing them (the first listed last: the collection's
/// order is the times').
fn vtk_series(dir: &Path, mesh: &PolyMesh, times: &[f64], u: impl Fn(f64) -> CellField) {
    let mut sets = Vec::new();
    for (k, &t) in times.iter().enumerate() {
        let name = format!("u_{k}.vtk");
        scg_mesh::vtk::write_legacy(dir.join(&name), mesh, "U", &u(t), k % 2 == 0).unwrap();
        sets.push(format!(
            "<DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{name}\"/>"
        ));
    }
    sets.rotate_left(1);
    std::fs::write(
        dir.join("u.pvd"),
        format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n\
             <Collection>\n{}\n</Collection>\n</VTKFile>\n",
            sets.join("\n")
        ),
    )
    .unwrap();
}

/// [`scene_text`] reading the VTK collection `file` instead of the OpenFOAM case.
fn vtk_scene(file: &str, series: Option<&str>, text: &str) -> String {
    let flow = match series {
        Some(s) => format!("kind = \"vtk\"\nfile = \"{file}\"\nseries = {{ {s} }}"),
        None => format!("kind = \"vtk\"\nfile = \"{file}\""),
    };
    let cut = text.find("kind = \"openfoam\"").unwrap();
    let end = text[cut..].find("[flow.patches]").unwrap() + cut;
    format!("{}{flow}\n{}", &text[..cut], &text[end..]).replace(SIDES, r#"walls = ["boundary"]"#)
}

/// A VTK series (a ParaView `.pvd` of legacy files, one per time step) of a uniform flow
/// ramping in time moves a particle as the closed form, as the OpenFOAM series does; the
/// refusals name the key: a collection without `series`, `series` on one file, a time
/// step whose mesh is not the first one's.
#[test]
fn a_vtk_series_moves_a_particle_as_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = unit_box();
    let (a, b) = (DVec3::new(0.2, 0.05, -0.1), DVec3::new(0.4, -0.2, 0.3));
    let uniform = |t: f64| CellField {
        cells: vec![a + b * t; mesh.n_cells],
        patches: vec![None; mesh.patches.len()],
    };
    vtk_series(dir.path(), &mesh, &[0.0, 0.25, 0.5], uniform);
    let (rho, x0, v0) = (1.0e3, DVec3::new(0.3, 0.5, 0.4), DVec3::new(-0.3, 0.1, 0.2));
    let text = scene_text("", 0.5, 1.0 / 16384.0, rho, x0, v0);
    let sc = load(dir.path(), &vtk_scene("u.pvd", Some(""), &text));
    let s = sc.mesh_flow.as_ref().unwrap().series.as_ref().unwrap();
    assert_eq!(s.times, vec![0.0, 0.25, 0.5]);
    let worst = ramp_error(&sc, (a, b), x0, v0, tau(rho));
    println!("VTK series: largest position error {worst:.3e} m");
    assert!(worst <= 1e-9, "{worst:e} m");
    // refusals
    let e = load_err(dir.path(), &vtk_scene("u.pvd", None, &text));
    assert!(e.contains("flow.file") && e.contains("time series"), "{e}");
    let e = load_err(dir.path(), &vtk_scene("u_0.vtk", Some(""), &text));
    assert!(e.contains("flow.series") && e.contains(".pvd"), "{e}");
    let e = load_err(dir.path(), &vtk_scene("u.pvd", Some("start = 0.3"), &text));
    assert!(e.contains("1 time step in the window"), "{e}");
    let other = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [6, 6, 6])
        .shape(CellShape::Hex)
        .naming(PatchNaming::Sides)
        .perturbed(0.15, 4)
        .build()
        .unwrap();
    scg_mesh::vtk::write_legacy(
        dir.path().join("u_1.vtk"),
        &other,
        "U",
        &uniform(0.25),
        true,
    )
    .unwrap();
    let e = load_err(dir.path(), &vtk_scene("u.pvd", Some(""), &text));
    assert!(e.contains("u_1.vtk") && e.contains("one mesh"), "{e}");
}

/// A solid-body vortex about the box's axis whose rate Ω(t) ramps linearly between
/// snapshots (affine in space: interpolated exactly), against a fine RK4 integration of
/// dv/dt = (Ω(t)·ẑ×(x − c) − v)/τ.
#[test]
fn a_vortex_whose_rate_ramps_matches_a_fine_reference() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = unit_box();
    let c = DVec3::new(0.5, 0.5, 0.5);
    let omega = |t: f64| 2.0 + 6.0 * t; // rad/s, linear: the series holds it exactly
    let times = [0.0, 0.125, 0.25, 0.375];
    let u = |x: DVec3, t: f64| omega(t) * DVec3::Z.cross(x - c);
    series_case(dir.path(), &mesh, &times, |t| affine(&mesh, |x| u(x, t)));
    let (rho, x0, v0) = (2.0e3, DVec3::new(0.7, 0.5, 0.5), DVec3::ZERO);
    let tau = tau(rho);
    let dt = 1.0 / 16384.0;
    let duration = 0.375;
    let sc = load(dir.path(), &scene_text("", duration, dt, rho, x0, v0));
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let got = sim.particles()[0].position;
    // RK4 with 40 sub-steps per step
    let f = |t: f64, x: DVec3, v: DVec3| (v, (u(x, t) - v) / tau);
    let (mut x, mut v) = (x0, v0);
    let n = sc.steps() * 40;
    let h = duration / n as f64;
    for i in 0..n {
        let t = i as f64 * h;
        let (k1x, k1v) = f(t, x, v);
        let (k2x, k2v) = f(t + 0.5 * h, x + k1x * (0.5 * h), v + k1v * (0.5 * h));
        let (k3x, k3v) = f(t + 0.5 * h, x + k2x * (0.5 * h), v + k2v * (0.5 * h));
        let (k4x, k4v) = f(t + h, x + k3x * h, v + k3v * h);
        x += (k1x + 2.0 * k2x + 2.0 * k3x + k4x) * (h / 6.0);
        v += (k1v + 2.0 * k2v + 2.0 * k3v + k4v) * (h / 6.0);
    }
    let err = (got - x).length();
    println!(
        "τ = {tau:.4e} s: the particle moved {:.4e} m, {:.3e} m from the reference",
        (x - x0).length(),
        err
    );
    assert!((x - x0).length() > 0.05, "the particle hardly moved");
    assert!(err <= 1e-9, "{err:e} m");
}

/// A field that changes in space and between snapshots (no symmetry to hide a wrong
/// snapshot or weight).
fn wavy(mesh: &PolyMesh, k: usize) -> CellField {
    let phase = [0.0, 1.3, 2.1][k];
    affine(mesh, |x| {
        DVec3::new(
            (3.0 * x.y + phase).sin(),
            (2.0 * x.z - phase).cos() * 0.5,
            (4.0 * x.x + 0.5 * phase).sin() * 0.3,
        )
    })
}

/// A case of the wavy field's three snapshots, 0, 0.25 and 0.5 s, and its mesh.
fn wavy_series() -> (tempfile::TempDir, PolyMesh) {
    let mesh = unit_box();
    let dir = tempfile::tempdir().unwrap();
    series_case(dir.path(), &mesh, &[0.0, 0.25, 0.5], |t| {
        wavy(&mesh, (t * 4.0).round() as usize)
    });
    (dir, mesh)
}

/// Final positions and velocities of `n` particles after `duration` s in the series of
/// `dir`, as bits.
fn final_bits(scene: &Scene) -> Vec<[u64; 6]> {
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    sim.particles()
        .iter()
        .map(|p| {
            let (x, v) = (p.position.to_array(), p.velocity.to_array());
            [x[0], x[1], x[2], v[0], v[1], v[2]].map(f64::to_bits)
        })
        .collect()
}

/// Many particles spread over the box, in the series `series` (the body of
/// `flow.series`).
fn many(series: &str, duration: f64) -> String {
    many_in(&format!("series = {{ {series} }}"), duration)
}

/// [`many`] with `flow` as the line that picks the field's time(s).
fn many_in(flow: &str, duration: f64) -> String {
    let mut pos = Vec::new();
    let mut vel = Vec::new();
    for i in 0..64 {
        let f = |k: usize| 0.15 + 0.7 * ((i * (k + 3) * 37 % 64) as f64 / 63.0);
        pos.push(format!("[{}, {}, {}]", f(0), f(1), f(2)));
        vel.push(format!("[{}, 0.0, {}]", 0.1 * f(1), -0.1 * f(2)));
    }
    format!(
        "duration = {duration:e}\ndt = {:e}\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n\
         [flow]\nkind = \"openfoam\"\ncase = \"case\"\n{flow}\n\
         [flow.patches]\n{SIDES}\nwall_model = \"rebound\"\nrestitution = 0.8\n\
         [drag]\nlaw = \"schiller_naumann\"\n[[groups]]\nname = \"p\"\ndiameter = 1.0e-4\n\
         density = 1.0e3\npositions = [{}]\nvelocities = [{}]\n",
        1.0 / 512.0,
        pos.join(", "),
        vel.join(", ")
    )
}

/// `cycle = true` over snapshots 0, 0.25, 0.5 s (period 0.75 s: the last blends back to
/// the first over the mean spacing) equals the same files written out over 2.25 s in
/// full, bit for bit.
#[test]
fn a_cycling_series_equals_the_repeated_files_written_out() {
    let mesh = unit_box();
    let short = tempfile::tempdir().unwrap();
    series_case(short.path(), &mesh, &[0.0, 0.25, 0.5], |t| {
        wavy(&mesh, (t * 4.0).round() as usize)
    });
    let full = tempfile::tempdir().unwrap();
    let times: Vec<f64> = (0..10).map(|k| k as f64 * 0.25).collect();
    series_case(full.path(), &mesh, &times, |t| {
        wavy(&mesh, ((t * 4.0).round() as usize) % 3)
    });
    let duration = 2.0;
    let a = load(short.path(), &many("cycle = true", duration));
    let b = load(full.path(), &many("", duration));
    let (ba, bb) = (final_bits(&a), final_bits(&b));
    assert_eq!(ba.len(), 64);
    assert_eq!(
        ba, bb,
        "the cycled window differs from the written-out series"
    );
    // and the series moves the particles differently from its first snapshot frozen
    let frozen = tempfile::tempdir().unwrap();
    series_case(frozen.path(), &mesh, &[0.0, 2.25], |_| wavy(&mesh, 0));
    let c = load(frozen.path(), &many("", duration));
    assert_ne!(final_bits(&c), ba);
}

/// One and two threads, and a run restarted from a checkpoint half-way (past a snapshot
/// change, in another interval): the same bits; and a recording of the series verified by
/// `scg replay --verify`.
#[test]
fn a_series_is_bit_identical_on_threads_and_restarts() {
    let (dir, _) = wavy_series();
    let scene = load(dir.path(), &many("cycle = true", 1.0));
    let digest = || {
        let mut sim = scene.build(false);
        sim.run(scene.steps(), |_| true).unwrap();
        format!("{:016x}", common::state_digest(&sim.particles()))
    };
    let one = common::digest_with(1, 100_000_000, false, digest);
    let two = common::digest_with(2, 1, false, digest);
    assert_eq!(one, two);
    let total = scene.steps();
    let mut straight = scene.build(false);
    straight.run(total, |_| true).unwrap();
    let end = straight.checkpoint();
    let mut first = scene.build(false);
    first.run(total / 2 + 7, |_| true).unwrap();
    let half = first.checkpoint();
    let mut second = scene.build(false);
    second.restore(&half).unwrap();
    second.run(total - half.step, |_| true).unwrap();
    assert!(second.checkpoint() == end, "a restarted series diverged");
    // `scg replay --verify` re-runs a recording of it frame for frame, bit for bit
    let text = format!("record_every = 64\n{}", many("cycle = true", 0.5));
    std::fs::write(dir.path().join("rec.toml"), text).unwrap();
    let out = dir.path().join("out");
    common::scg_ok(
        dir.path(),
        &["run", "rec.toml", "--out", out.to_str().unwrap()],
    );
    common::assert_replays_bit_identical(&out.join("rec.mcap"));
}

/// A cycling window kept in memory after its first pass (the default budget) and one read
/// again at every pass (`SCG_SERIES_KEEP_MB=0`) give the same frames, bit for bit.
#[test]
fn keeping_the_snapshots_changes_no_bit() {
    let (dir, _) = wavy_series();
    let text = format!("record_every = 32\n{}", many("cycle = true", 2.0));
    std::fs::write(dir.path().join("keep.toml"), text).unwrap();
    let frames = |keep: &str| {
        let out = format!("frames-{keep}");
        let args = ["run", "keep.toml", "--no-record", "--frames-csv", &out];
        let run = common::scg_env(dir.path(), &args, &[("SCG_SERIES_KEEP_MB", keep)]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let mut files: Vec<_> = std::fs::read_dir(dir.path().join(&out))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        files
            .iter()
            .map(|f| std::fs::read(f).unwrap())
            .collect::<Vec<_>>()
    };
    let (streamed, kept) = (frames("0"), frames("1024"));
    assert!(streamed.len() > 10, "{} frames", streamed.len());
    assert!(streamed == kept, "keeping the snapshots changed the frames");
    // a value that is not a number of MB is an error naming it
    let bad = common::scg_env(
        dir.path(),
        &["check", "keep.toml"],
        &[("SCG_SERIES_KEEP_MB", "lots")],
    );
    let text = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(2), "{text}");
    assert!(
        text.contains("SCG_SERIES_KEEP_MB") && text.contains("lots"),
        "{text}"
    );
}

/// `scg check` states the window, the spacing and the seam, and warns where the spacing
/// exceeds the particles' response time.
#[test]
fn check_states_the_window_and_the_seam() {
    let (dir, _) = wavy_series();
    let scene = load(dir.path(), &many("cycle = true", 1.0));
    let report = scg::scene::check::check(&scene).messages().join("\n");
    println!("{report}");
    assert!(report.contains("unsteady field: 3 snapshots"), "{report}");
    assert!(report.contains("repeats every 7.500000e-1 s"), "{report}");
    // the memory: the later snapshots' tables hold their values only
    let mb = |tag: &str| -> f64 {
        let at = report
            .find(tag)
            .unwrap_or_else(|| panic!("{tag}: {report}"));
        let head = &report[..at];
        head[head.rfind(' ').unwrap() + 1..].trim().parse().unwrap()
    };
    let (first, later) = (
        mb(" MB for the first snapshot"),
        mb(" MB for each later one held"),
    );
    assert!(later > 0.0 && later < 0.5 * first, "{first} {later}");
    assert!(
        report.contains("across that seam the field changes by"),
        "{report}"
    );
    // 100 µm of 1000 kg/m³: τ ≈ 0.031 s < 0.25 s
    assert!(report.contains("longer than the response time"), "{report}");
}

#[test]
fn what_a_series_cannot_take_is_refused_by_key() {
    let (dir, mesh) = wavy_series();
    let base = many("", 0.5);
    let cases = [
        (
            base.replace("case = \"case\"\n", "case = \"case\"\ntime = 0.25\n"),
            "flow.time",
        ),
        (many("start = 0.3", 0.1), "flow.series"),
        (many("", 0.75), "duration"),
        (
            format!("{base}[forces]\nrubinow_keller = true\n"),
            "forces.rubinow_keller",
        ),
        (
            format!("{base}[forces]\npressure_gradient = true\n"),
            "forces.pressure_gradient",
        ),
        (many("cycle = 1", 0.5), "flow.series"),
    ];
    for (text, key) in cases {
        let e = load_err(dir.path(), &text);
        println!("{e}");
        assert!(e.contains(key), "expected `{key}` in: {e}");
    }
    // a time directory with a mesh of its own: the mesh changes
    write_case(dir.path().join("case/0.25"), &mesh, None, Format::Binary).unwrap();
    std::fs::rename(
        dir.path().join("case/0.25/constant/polyMesh"),
        dir.path().join("case/0.25/polyMesh"),
    )
    .unwrap();
    let e = load_err(dir.path(), &base);
    assert!(e.contains("the mesh changes in time"), "{e}");
}

/// `k(t, x)` and `ε(x)` written beside the velocity of every time folder of `dir/case`.
fn write_turbulence(
    dir: &Path,
    mesh: &PolyMesh,
    times: &[f64],
    k: impl Fn(f64, DVec3) -> f64,
    epsilon: impl Fn(DVec3) -> f64,
) {
    let g = MeshGeometry::new(mesh).unwrap();
    let scalar = |f: &dyn Fn(DVec3) -> f64| ScalarField {
        cells: g.cell_centres.iter().map(|&c| f(c)).collect(),
        patches: vec![None; mesh.patches.len()],
    };
    for &t in times {
        let case = dir.join("case");
        let (kt, et) = (scalar(&|x| k(t, x)), scalar(&epsilon));
        write_scalar_field(&case, &format!("{t}"), "k", mesh, &kt, Format::Binary).unwrap();
        write_scalar_field(&case, &format!("{t}"), "epsilon", mesh, &et, Format::Binary).unwrap();
    }
}

/// With `[dispersion]` (either model) a series of equal snapshots moves every particle
/// as the frozen field does, bit for bit: the blend, the turbulence read per snapshot and
/// the mean velocity read afresh change no bit.
#[test]
fn dispersion_over_equal_snapshots_equals_the_frozen_field() {
    let mesh = unit_box();
    let dir = tempfile::tempdir().unwrap();
    let times = [0.0, 0.25, 0.5, 0.75];
    series_case(dir.path(), &mesh, &times, |_| wavy(&mesh, 1));
    write_turbulence(
        dir.path(),
        &mesh,
        &times,
        |_, x| 0.02 * (1.0 + x.x * x.y),
        |x| 0.5 + x.z,
    );
    for model in ["stochastic_ras", "langevin"] {
        let c0 = if model == "langevin" {
            "c0 = 2.1\n"
        } else {
            ""
        };
        let disp =
            format!("[dispersion]\nmodel = \"{model}\"\n{c0}k = \"k\"\nepsilon = \"epsilon\"\n");
        let series = load(dir.path(), &(many("", 0.6) + &disp));
        let frozen = load(dir.path(), &(many_in("time = 0", 0.6) + &disp));
        let (a, b) = (final_bits(&series), final_bits(&frozen));
        assert_eq!(a, b, "{model}: the series differs from its frozen snapshot");
        // and dispersion moved them (the run without it ends elsewhere)
        let plain = load(dir.path(), &many_in("time = 0", 0.6));
        assert_ne!(final_bits(&plain), a, "{model} changed nothing");
    }
}

/// Tracers at rest in still air, the Langevin walk with k = 0.01 + 0.12·t m²/s² (0.01
/// at t = 0, 0.04 at 0.25 s, uniform in space), ε = 1 m²/s³: the normalised walk's
/// fluctuation u′ = σ·w has the variance 2k/3 per direction of the k at the step's mid
/// time; measured over 3000 tracers × 3 directions against that, and against the first
/// snapshot's k frozen.
#[test]
fn the_langevin_walk_follows_k_in_time() {
    let mesh = unit_box();
    let dir = tempfile::tempdir().unwrap();
    let times = [0.0, 0.25];
    series_case(dir.path(), &mesh, &times, |_| {
        affine(&mesh, |_| DVec3::ZERO)
    });
    let k = |t: f64| 0.01 + 0.12 * t;
    write_turbulence(dir.path(), &mesh, &times, |t, _| k(t), |_| 1.0);
    let dt = 1.0 / 1024.0;
    let duration = 0.125;
    let text = format!(
        "duration = {duration:e}\ndt = {dt:e}\nseed = 3\n[fluid]\ndensity = 1.2\n\
         viscosity = 1.8e-5\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\nseries = {{}}\n\
         [flow.patches]\n{SIDES}\nwall_model = \"rebound\"\n[drag]\nlaw = \"stokes\"\n\
         [dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = \"k\"\nepsilon = \"epsilon\"\n\
         [[groups]]\nname = \"tracer\"\ndiameter = 1.0e-6\ndensity = 1.0e3\ncount = 3000\n\
         region = {{ kind = \"box\", min = [0.3, 0.3, 0.3], max = [0.7, 0.7, 0.7] }}\n"
    );
    let sc = load(dir.path(), &text);
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let mut q = sim.world.query::<&scg::core::components::CarrierOffset>();
    let offs: Vec<DVec3> = q.iter(&sim.world).map(|o| o.0).collect();
    assert_eq!(offs.len(), 3000);
    let n = 3.0 * offs.len() as f64;
    let var = offs.iter().map(|u| u.length_squared()).sum::<f64>() / n;
    // the variance of a variance estimate from n normal draws: 2σ⁴/n
    let t_mid = (sc.steps() as f64 - 0.5) * dt;
    let want = 2.0 * k(t_mid) / 3.0;
    let half = 3.0 * want * (2.0 / n).sqrt();
    println!(
        "⟨u′²⟩ = {var:.5e} m²/s², 2k/3 at t = {t_mid:.5} s: {want:.5e} ± {half:.1e} (3σ); \
         the first snapshot's: {:.5e}",
        2.0 * k(0.0) / 3.0
    );
    assert!((var - want).abs() <= half, "{var} vs {want} ± {half}");
    assert!((var - 2.0 * k(0.0) / 3.0).abs() > 10.0 * half);
}
