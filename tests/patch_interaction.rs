//! A user's own OpenFOAM case: walls written as OpenFOAM writes them today (`noSlip`) give
//! the same trajectories, bit for bit, as the same walls written `fixedValue uniform
//! (0 0 0)`; the per-patch interaction models (rebound, stick, escape) and the fates
//! every run ends with, which account for every particle exactly.
//!
//! Run: `cargo test --release --test patch_interaction -- --nocapture`.

use std::path::Path;

use glam::DVec3;
use scg::scene::Scene;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{Format, write_case};
use scg_mesh::{MeshGeometry, PolyMesh};

/// A square duct along x, 20 × 4 × 4 mm: `inlet` (x = 0), `outlet`, `walls`.
fn duct() -> PolyMesh {
    BoxMesh::new(DVec3::ZERO, DVec3::new(0.02, 0.004, 0.004), [20, 5, 5])
        .shape(CellShape::Hex)
        .perturbed(0.1, 7)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .build()
        .unwrap()
}

/// A developing duct flow at the cell centres, plus a cross flow toward the y = 0 wall, so
/// that particles reach the walls.
fn cells(mesh: &PolyMesh) -> Vec<DVec3> {
    let g = MeshGeometry::new(mesh).unwrap();
    g.cell_centres
        .iter()
        .map(|c| {
            let (y, z) = (c.y / 0.004, c.z / 0.004);
            let s = 16.0 * y * (1.0 - y) * z * (1.0 - z);
            DVec3::new(2.0 * s.sqrt(), -0.3 * s, 0.1 * (y - 0.5) * s)
        })
        .collect()
}

/// A case in `dir` with the walls' boundary condition `walls` (the body of its entry).
fn write(dir: &Path, mesh: &PolyMesh, walls: &str) {
    write_case(dir, mesh, None, Format::Ascii).unwrap();
    let mut s = String::from(
        "FoamFile\n{\n    version 2.0;\n    format ascii;\n    class volVectorField;\n    \
         object U;\n}\ndimensions [0 1 -1 0 0 0 0];\n",
    );
    let u = cells(mesh);
    s += &format!("internalField nonuniform List<vector> {}\n(\n", u.len());
    for c in &u {
        s += &format!("({:e} {:e} {:e})\n", c.x, c.y, c.z);
    }
    s += ");\nboundaryField\n{\n";
    s += "    inlet { type fixedValue; value uniform (2 0 0); }\n";
    s += "    outlet { type zeroGradient; }\n";
    s += &format!("    walls {{ {walls} }}\n}}\n");
    std::fs::create_dir_all(dir.join("0")).unwrap();
    std::fs::write(dir.join("0/U"), s).unwrap();
}

fn scene(dir: &Path, patches: &str, duration: f64) -> Scene {
    let path = write_scene(dir, patches, duration);
    scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// The scene file of [`scene`], written to `dir/scene.toml`.
fn write_scene(dir: &Path, patches: &str, duration: f64) -> std::path::PathBuf {
    let text = format!(
        r#"duration = {duration:e}
dt = 2.0e-5
seed = 5
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "openfoam"
case = "case"
time = "latest"
field = "U"
[flow.patches]
walls = ["walls"]
outlets = ["outlet"]
inlets = ["inlet"]
{patches}
[drag]
law = "schiller_naumann"
[[groups]]
name = "d10"
diameter = 10e-6
density = 2500.0
count = 300
region = {{ kind = "box", min = [0.001, 0.0002, 0.0002], max = [0.005, 0.0038, 0.0038] }}
[[groups]]
name = "d40"
diameter = 40e-6
density = 2500.0
[[feeders]]
group = "d40"
rate = 2.0e4
patch = "inlet"
velocity = [2.0, -1.0, 0.0]
stop = 0.01
"#
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn positions(scene: &Scene) -> Vec<[u64; 3]> {
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    sim.particles()
        .iter()
        .map(|p| p.position.to_array().map(f64::to_bits))
        .collect()
}

/// `noSlip` walls and `fixedValue uniform (0 0 0)` walls: the same bits. Walls taken as
/// zeroGradient (what `noSlip` used to be read as) give other trajectories, so the test
/// can fail.
#[test]
fn no_slip_walls_equal_fixed_value_zero_bit_for_bit() {
    let mesh = duct();
    let run = |walls: &str| {
        let d = tempfile::tempdir().unwrap();
        write(&d.path().join("case"), &mesh, walls);
        positions(&scene(d.path(), "wall_model = \"rebound\"", 0.01))
    };
    let no_slip = run("type noSlip;");
    let fixed = run("type fixedValue; value uniform (0 0 0);");
    let zero_gradient = run("type zeroGradient;");
    assert!(no_slip.len() > 100, "{} particles", no_slip.len());
    assert_eq!(no_slip, fixed);
    assert_ne!(no_slip, zero_gradient);
}

/// A `stick` wall keeps every particle that reaches it; fed = escaped + stuck + lost +
/// airborne exactly, per group, and the fates the console prints say the same.
#[test]
fn stick_walls_keep_what_reaches_them_and_every_particle_is_accounted_for() {
    let mesh = duct();
    let d = tempfile::tempdir().unwrap();
    write(&d.path().join("case"), &mesh, "type noSlip;");
    for patches in [
        "wall_model = \"stick\"",
        "wall_model = \"rebound\"\nrestitution = 0.8\nfriction = 0.3",
        "wall_model = \"rebound\"\nrestitution = 0.8\nfriction = 0.3\nfriction_model = \"openfoam_fraction\"",
        "[flow.patches.interaction]\nwalls = { model = \"rebound\", restitution = 0.5, friction = 0.1 }\ninlet = { model = \"stick\" }",
    ] {
        let sc = scene(d.path(), patches, 0.02);
        let mut sim = sc.build(false);
        sim.run(sc.steps(), |_| true).unwrap();
        let fates = scg::cli::fates::fates(&sc, &mut sim);
        let text = scg::cli::fates::render(&fates);
        println!("{patches}:\n{text}");
        assert!(!text.contains("warning"), "{text}");
        for f in &fates {
            assert_eq!(f.accounted(), f.entered(), "{}", f.group);
            let json = scg::cli::fates::json(f);
            assert_eq!(json["conserved"], true);
        }
        let stuck: u64 = fates
            .iter()
            .flat_map(|f| f.patches.iter())
            .filter(|p| p.0 == "walls")
            .map(|p| p.3)
            .sum();
        let escaped: u64 = fates
            .iter()
            .flat_map(|f| f.patches.iter())
            .filter(|p| p.0 == "outlet")
            .map(|p| p.2)
            .sum();
        if patches.contains("\"stick\"") && !patches.contains("inlet") {
            // the cross flow carries particles to the y = 0 wall: many stick there, and
            // none is left within a radius of a wall
            assert!(stuck > 50, "{stuck} stuck");
            for p in sim.particles() {
                let y = p.position.y.min(0.004 - p.position.y);
                let z = p.position.z.min(0.004 - p.position.z);
                assert!(y > 0.0 && z > 0.0, "{:?} beyond a wall", p.position);
            }
        } else {
            assert_eq!(stuck, 0, "{patches}: nothing sticks to rebound walls");
            // rebound walls keep every centre inside
            for p in sim.particles() {
                assert!(
                    p.position.y >= 0.0 && p.position.y <= 0.004,
                    "{:?}",
                    p.position
                );
            }
        }
        assert!(
            escaped > 0 || sc.duration < 0.015,
            "{patches}: none escaped"
        );
    }
}

/// Unknown keys and models are errors naming the key; `restitution` on a `stick` patch is
/// refused as unused; a feeder on a wall patch is refused.
#[test]
fn bad_patch_models_are_refused() {
    let mesh = duct();
    let d = tempfile::tempdir().unwrap();
    write(&d.path().join("case"), &mesh, "type noSlip;");
    let load = |patches: &str, feed_patch: &str| {
        let sc = scene(d.path(), patches, 0.01);
        let _ = sc;
        let text = std::fs::read_to_string(d.path().join("scene.toml"))
            .unwrap()
            .replace("patch = \"inlet\"", &format!("patch = \"{feed_patch}\""));
        let path = d.path().join("bad.toml");
        std::fs::write(&path, text).unwrap();
        scg::scene::load(&path, &[])
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    assert!(load("wall_model = \"stick\"", "inlet").is_ok());
    let e = load("wall_model = \"stick\"", "walls").unwrap_err();
    assert!(e.contains("is a wall"), "{e}");
    let scene_with = |patches: &str| {
        let text = format!(
            "duration = 0.01\ndt = 1e-5\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\n[flow.patches]\nwalls = [\"walls\"]\n{patches}\n[drag]\nlaw = \"stokes\"\n[[groups]]\nname = \"a\"\ndiameter = 1e-5\ndensity = 1000.0\npositions = [[0.01, 0.002, 0.002]]\n"
        );
        let path = d.path().join("s.toml");
        std::fs::write(&path, text).unwrap();
        scg::scene::load(&path, &[])
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    for (patches, key, message) in [
        ("wall_model = \"glue\"", "wall_model", "glue"),
        (
            "[flow.patches.interaction]\nwalls = { model = \"stick\", restitution = 0.5 }",
            "flow.patches.interaction.walls.restitution",
            "rebound",
        ),
        (
            "[flow.patches.interaction]\nnope = { model = \"stick\" }",
            "flow.patches.interaction.nope",
            "unknown patch",
        ),
        ("restitution = 1.5", "flow.patches.restitution", "[0, 1]"),
        ("friction = -1", "flow.patches.friction", ""),
        (
            "wall_model = \"contact\"",
            "flow.patches.wall_model",
            "[material]",
        ),
        (
            "wall_model = \"rebound\"\nfriction_model = \"sliding\"",
            "friction_model",
            "sliding",
        ),
        (
            "[flow.patches.interaction]\nwalls = { model = \"stick\", friction_model = \"coulomb\" }",
            "flow.patches.interaction.walls.friction_model",
            "rebound",
        ),
    ] {
        let e = scene_with(patches).expect_err(patches);
        assert!(e.contains(key) && e.contains(message), "{patches}: {e}");
        assert!(!e.starts_with("error:"), "{e}");
    }
}

/// `friction_model` reaches the patch models: `[flow.patches]`'s for the walls, a per-patch
/// entry's own, the Coulomb impact by default (and for the contact law's guard).
#[test]
fn friction_model_selects_the_rebound_rule_per_patch() {
    use scg::core::physics::mesh_flow::{PatchInteraction, WallFriction};
    let mesh = duct();
    let d = tempfile::tempdir().unwrap();
    write(&d.path().join("case"), &mesh, "type noSlip;");
    // the "walls" patch's (mu, friction rule) under a [flow.patches] block
    let walls = |patches: &str| {
        let sc = scene(d.path(), patches, 0.01);
        let mesh = sc.mesh_flow.as_ref().unwrap().flow.mesh();
        mesh.patches
            .iter()
            .zip(&sc.patch_models)
            .find(|(p, _)| p.name == "walls")
            .and_then(|(_, m)| match m.interaction {
                PatchInteraction::Rebound { mu, friction, .. } => Some((mu, friction)),
                _ => None,
            })
    };
    assert_eq!(
        walls("wall_model = \"rebound\"\nfriction = 0.3"),
        Some((0.3, WallFriction::Coulomb))
    );
    assert_eq!(
        walls("wall_model = \"rebound\"\nfriction = 0.3\nfriction_model = \"openfoam_fraction\""),
        Some((0.3, WallFriction::OpenfoamFraction))
    );
    // a per-patch entry inherits [flow.patches]' rule, or names its own
    let inherit = "wall_model = \"stick\"\nfriction_model = \"openfoam_fraction\"\n\n[flow.patches.interaction]\nwalls = { model = \"rebound\", friction = 0.2 }";
    assert_eq!(walls(inherit), Some((0.2, WallFriction::OpenfoamFraction)));
    let own = "wall_model = \"stick\"\n\n[flow.patches.interaction]\nwalls = { model = \"rebound\", friction = 0.2, friction_model = \"openfoam_fraction\" }";
    assert_eq!(walls(own), Some((0.2, WallFriction::OpenfoamFraction)));
}

/// 5 µm dust with rebound walls (restitution and friction only, no `[material]`): `dt =
/// "auto"` follows the drag time and the mesh, not a Hertz contact time, and `scg check`
/// says so. With contact walls the same dust takes the contact time (orders smaller).
#[test]
fn dust_with_rebound_walls_takes_its_dt_from_the_drag() {
    let mesh = duct();
    let d = tempfile::tempdir().unwrap();
    write(&d.path().join("case"), &mesh, "type noSlip;");
    let text = |patches: &str| {
        format!(
            "duration = 0.01\ndt = \"auto\"\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\n[flow.patches]\nwalls = [\"walls\"]\noutlets = [\"outlet\"]\ninlets = [\"inlet\"]\n{patches}\n[drag]\nlaw = \"schiller_naumann\"\n[[groups]]\nname = \"dust\"\ndiameter = 5e-6\ndensity = 2500.0\n[[feeders]]\ngroup = \"dust\"\nmass_rate = 1e-9\npatch = \"inlet\"\nvelocity = \"field\"\n"
        )
    };
    let load = |t: String| {
        let path = d.path().join("dust.toml");
        std::fs::write(&path, t).unwrap();
        scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
    };
    let rebound = load(text(
        "wall_model = \"rebound\"\nrestitution = 0.8\nfriction = 0.3",
    ));
    let tau = 2500.0 * 25e-12 / (18.0 * 1.8e-5);
    assert!(
        rebound.dt <= tau && rebound.dt > 0.05 * tau,
        "dt {} vs τ {tau}",
        rebound.dt
    );
    let report = scg::scene::check::check(&rebound);
    // fed at the field's velocity (the patch's mean, 1.6 m/s): the slip is measured against
    // the mesh flow's velocity at the patch centre (2 m/s), not against still air (which
    // gave the whole 1.6 m/s)
    assert!(
        report.groups[0].slip < 0.5,
        "slip {}",
        report.groups[0].slip
    );
    let shown = scg::scene::check::render(&rebound, &report);
    assert!(shown.contains("no Hertz contact"), "{shown}");
    assert!(shown.contains("kg/s of the original powder"), "{shown}");
    // mass_rate → simulated particles per second: 1e-9 kg/s of 5 µm spheres
    let m = 2500.0 * std::f64::consts::PI / 6.0 * 125e-18;
    assert!((rebound.feeders[0].rate - 1e-9 / m).abs() < 1e-9 * rebound.feeders[0].rate);
    let contact = load(text(
        "wall_model = \"contact\"\n[material]\nyoungs_modulus = 1e8\npoisson_ratio = 0.3\nrestitution = 0.8",
    ));
    assert!(
        contact.dt < 0.01 * rebound.dt,
        "{} vs {}",
        contact.dt,
        rebound.dt
    );
}

/// OpenFOAM's own squareBend tutorial duct with its own `noSlip` walls
/// (`cases/squarebend.toml`, `cases/squarebend/coarse`): stick walls, outlet and inlet
/// escape. The fates against OpenFOAM's `uncoupledKinematicParcelFoam` with
/// `localInteraction` on the same field (`bash cases/squarebend/vs-openfoam.sh`, 500
/// particles per class; 95 % Wilson intervals of OpenFOAM's counts): 5 µm escape through
/// the outlet 0.738 [0.698, 0.775], 20 µm stick 0.958 [0.937, 0.972], 50 and 100 µm all
/// stick; none leaves through the inlet. scg's run must land inside those intervals (it
/// is deterministic: the same bits every run).
#[test]
fn squarebend_fates_agree_with_openfoams_tracker() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/squarebend.toml");
    let sc = scg::scene::load(Path::new(path), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let fates = scg::cli::fates::fates(&sc, &mut sim);
    println!("{}", scg::cli::fates::render(&fates));
    let frac = |g: usize, patch: &str, stuck: bool| {
        let f = &fates[g];
        let n = f
            .patches
            .iter()
            .find(|p| p.0 == patch)
            .map_or(0, |p| if stuck { p.3 } else { p.2 });
        n as f64 / f.entered() as f64
    };
    for f in &fates {
        assert_eq!(f.entered(), 500, "{}", f.group);
        assert_eq!(f.accounted(), f.entered(), "{}", f.group);
        assert_eq!(frac(0, "inlet", false), 0.0);
    }
    let out5 = frac(0, "outlet", false);
    assert!((0.698..=0.775).contains(&out5), "5 µm outlet {out5}");
    let wall20 = frac(1, "walls", true);
    assert!((0.937..=0.972).contains(&wall20), "20 µm walls {wall20}");
    assert_eq!(frac(2, "walls", true), 1.0);
    assert_eq!(frac(3, "walls", true), 1.0);
}

/// Every shipped case accounts for every particle at the end of a short run: entered =
/// escaped + stuck + lost + airborne, per group, exactly.
#[test]
fn every_shipped_case_accounts_for_every_particle() {
    for (case, duration) in [
        ("uniform", "0.05"),
        ("vortex", "0.01"),
        ("classifier", "0.0004"),
        ("classifier-psd", "0.0004"),
        ("classifier-cut", "0.004"),
        ("cyclone", "0.04"),
        ("squarebend", "0.02"),
        ("elbow", "0.02"),
        ("duct", "0.1"),
    ] {
        let path = format!("{}/cases/{case}.toml", env!("CARGO_MANIFEST_DIR"));
        let sets = [format!("duration={duration}")];
        let sc = scg::scene::load(Path::new(&path), &sets).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = sc.build(false);
        sim.run(sc.steps(), |_| true).unwrap();
        let fates = scg::cli::fates::fates(&sc, &mut sim);
        for f in &fates {
            assert_eq!(f.accounted(), f.entered(), "{case}: {}", f.group);
        }
        let entered: u64 = fates.iter().map(|f| f.entered()).sum();
        assert!(entered > 0, "{case}: no particle entered");
    }
}

/// An unknown boundary-condition type in a user's case: `scg check` and `scg run` exit 2
/// with one message naming the field file, the patch and the type, and listing the types
/// scg reads.
#[test]
fn an_unknown_boundary_type_exits_2_naming_patch_and_type() {
    let mesh = duct();
    let d = tempfile::tempdir().unwrap();
    write(
        &d.path().join("case"),
        &mesh,
        "type myWallFunction; value uniform (0 0 0);",
    );
    write_scene(d.path(), "", 0.01);
    for args in [
        &["check", "scene.toml"][..],
        &["run", "scene.toml", "--no-record"],
    ] {
        let cmd = args[0];
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
            .args(args)
            .current_dir(d.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains("0/U")
                && err.contains("boundaryField/walls/type")
                && err.contains("unknown boundary condition type 'myWallFunction'")
                && err.contains("noSlip"),
            "{cmd}: {err}"
        );
        assert_eq!(err.matches("error:").count(), 1, "{cmd}: {err}");
    }
}

/// `[[walls]] model = "rebound" | "stick"` act as impulses on analytic and STL walls
/// alike, with no `[material]`: a sphere thrown at a plane leaves it with the impulse
/// model's closed-form velocity (sliding: v_t' = v_t − μ(1+e)v_n) at touching distance;
/// beads dropped into the open STL box of `tests/fixtures/mesh-box.stl` with `stick` all
/// deposit, and the fates count them on the wall.
#[test]
fn stl_and_analytic_walls_rebound_and_stick_as_impulses() {
    let d = tempfile::tempdir().unwrap();
    let plane = r#"duration = 0.02
dt = 1.0e-4
[[walls]]
name = "floor"
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
model = "rebound"
restitution = 0.5
friction = 0.1
[[groups]]
name = "a"
diameter = 1.0e-3
density = 2500.0
positions = [[0.0, 0.0, 5.0e-3]]
velocities = [[1.0, 0.0, -1.0]]
"#;
    let path = d.path().join("plane.toml");
    std::fs::write(&path, plane).unwrap();
    let sc = scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(sc.walls.is_empty() && sc.impulse_walls.len() == 1);
    let mut sim = sc.build(false);
    assert!(
        sim.plan()
            .contains(scg::core::step::StepSystem::ImpulseWalls)
    );
    sim.run(sc.steps(), |_| true).unwrap();
    let p = sim.particles()[0];
    // v_n = 1, μ(1+e)v_n = 0.15 < |v_t|/3.5: sliding, v_t' = 0.85; v_n' = 0.5
    assert!(
        (p.velocity - glam::DVec3::new(0.85, 0.0, 0.5)).length() < 1e-12,
        "{p:?}"
    );
    assert!(p.position.z > 0.5e-3, "{p:?}");

    let fixture = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/mesh-box.stl");
    let mut text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/mesh-box.toml"
    ))
    .unwrap();
    text = text
        .replace(
            "file = \"mesh-box.stl\"",
            &format!("file = \"{fixture}\"\nmodel = \"stick\""),
        )
        .replace("duration = 0.02", "duration = 0.1");
    let i = text.find("[material]").unwrap();
    let j = text.find("[[walls]]").unwrap();
    text.replace_range(i..j, "");
    let path = d.path().join("box.toml");
    std::fs::write(&path, &text).unwrap();
    let sc = scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let fates = scg::cli::fates::fates(&sc, &mut sim);
    println!("{}", scg::cli::fates::render(&fates));
    let f = &fates[0];
    assert_eq!(f.accounted(), f.entered());
    assert_eq!(f.airborne, 0, "every bead reaches the floor and sticks");
    assert_eq!(f.patches, vec![("wall box".to_string(), "wall", 0, 4)]);
    // restitution on a stick wall is a key the model does not use
    std::fs::write(
        &path,
        text.replace("model = \"stick\"", "model = \"stick\"\nrestitution = 0.5"),
    )
    .unwrap();
    let e = scg::scene::load(&path, &[]).unwrap_err().to_string();
    assert!(e.contains("walls[0].restitution"), "{e}");
}

/// A 2-D case (the duct's z sides `empty`, as OpenFOAM's 2-D cases are): `scg check` says
/// so, the particles reflect at the empty sides and stay in the slab, none is lost there;
/// `--no-record --frames-csv` writes its frames.
#[test]
fn a_two_dimensional_case_is_reported_and_keeps_its_particles() {
    let mut mesh = BoxMesh::new(DVec3::ZERO, DVec3::new(0.02, 0.004, 0.001), [20, 5, 1])
        .shape(CellShape::Hex)
        .naming(PatchNaming::Sides)
        .build()
        .unwrap();
    for p in &mut mesh.patches {
        p.kind = match p.name.as_str() {
            "zmin" | "zmax" => "empty",
            "ymin" | "ymax" => "wall",
            _ => "patch",
        }
        .into();
    }
    let d = tempfile::tempdir().unwrap();
    let case = d.path().join("case");
    write_case(&case, &mesh, None, Format::Ascii).unwrap();
    let g = MeshGeometry::new(&mesh).unwrap();
    let mut s = String::from(
        "FoamFile { version 2.0; format ascii; class volVectorField; object U; }\ndimensions [0 1 -1 0 0 0 0];\n",
    );
    s += &format!(
        "internalField nonuniform List<vector> {}\n(\n",
        g.cell_centres.len()
    );
    for c in &g.cell_centres {
        let y = c.y / 0.004;
        s += &format!("({:e} {:e} 0)\n", 6.0 * y * (1.0 - y), -0.2 * y * (1.0 - y));
    }
    s += ");\nboundaryField\n{\n    xmin { type fixedValue; value uniform (1 0 0); }\n    xmax { type zeroGradient; }\n    ymin { type noSlip; }\n    ymax { type noSlip; }\n    zmin { type empty; }\n    zmax { type empty; }\n}\n";
    std::fs::create_dir_all(case.join("0")).unwrap();
    std::fs::write(case.join("0/U"), s).unwrap();
    let text = r#"duration = 0.01
dt = 2.0e-5
record_every = 100
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "openfoam"
case = "case"
[flow.patches]
walls = ["ymin", "ymax"]
outlets = ["xmax"]
inlets = ["xmin"]
wall_model = "rebound"
restitution = 0.9
[drag]
law = "schiller_naumann"
[[groups]]
name = "a"
diameter = 20e-6
density = 2500.0
count = 200
region = { kind = "box", min = [0.001, 0.0005, 0.0001], max = [0.01, 0.0035, 0.0009] }
velocity = [0.0, 0.5, 3.0]
"#;
    std::fs::write(d.path().join("slab.toml"), text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(["check", "slab.toml"])
        .current_dir(d.path())
        .output()
        .unwrap();
    let shown =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(
        shown.contains("a 2-D case") && shown.contains("zmin, zmax"),
        "{shown}"
    );
    let sc = scg::scene::load(&d.path().join("slab.toml"), &[]).unwrap();
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    for p in sim.particles() {
        assert!((0.0..=0.001).contains(&p.position.z), "{p:?} left the slab");
    }
    let fates = scg::cli::fates::fates(&sc, &mut sim);
    let f = &fates[0];
    assert_eq!(f.accounted(), f.entered());
    assert_eq!(f.lost, 0, "none lost through the empty sides");
    for (patch, _, esc, stuck) in &f.patches {
        assert!(
            !patch.starts_with('z') || (*esc == 0 && *stuck == 0),
            "{patch}"
        );
    }
    // frames without the .rrd/.mcap pair
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
        .args([
            "run",
            "slab.toml",
            "--no-record",
            "--frames-csv",
            "csv",
            "--out",
            "rec",
        ])
        .args(["--fates-csv", "fates.csv"])
        .current_dir(d.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let frames = std::fs::read_dir(d.path().join("csv")).unwrap().count();
    assert!(frames >= 5, "{frames} frames");
    assert!(
        !d.path().join("rec").exists(),
        "no recordings with --no-record"
    );
    let csv = std::fs::read_to_string(d.path().join("fates.csv")).unwrap();
    assert!(csv.contains("\na,entered,,200,1e0,"), "{csv}");
    assert!(csv.contains("\na,lost,,0,0e0,"), "{csv}");
}
