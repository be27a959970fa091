//! `[erosion]`: impacts on the rebound and stick wall patches of a mesh flow, worn into
//! the faces by the scene's model with the original powder's mass each particle stands
//! for. Particles fired ballistically at a wall at 30° hit it once each: the log is
//! Finnie's (and DNV's) formula times the represented mass, to 1e-12; 8 originals, one
//! SCG α = 2 particle and one sampled α = 2 particle wear the same volume; a checkpoint
//! keeps the log; bad tables are refused.

use glam::DVec3;
use scg::core::physics::erosion::ErosionModel;
use scg::core::physics::scaling::sphere_mass;
use scg::core::stages::erosion::{ErosionLog, ErosionSpec};
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{Format, write_case};

const THETA_DEG: f64 = 30.0;

fn case(dir: &std::path::Path) {
    let mesh = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [4, 4, 4])
        .shape(CellShape::Hex)
        .naming(PatchNaming::Sides)
        .build()
        .unwrap();
    let g = scg_mesh::MeshGeometry::new(&mesh).unwrap();
    let field = scg_mesh::CellField::at_cell_centres(&mesh, &g, |_| DVec3::ZERO);
    write_case(dir.join("case"), &mesh, Some(("U", &field)), Format::Ascii).unwrap();
}

/// `groups`: (alpha, law, count) each placed along y at x = 0.05, z = 0.5, all moving at
/// 10 m/s toward the zmin wall at 30°.
fn load(
    dir: &std::path::Path,
    groups: &[(f64, &str, usize)],
    erosion: &str,
) -> Result<scg::scene::Scene, scg::scene::SceneError> {
    let t = THETA_DEG.to_radians();
    let v = [10.0 * t.cos(), 0.0, -10.0 * t.sin()];
    let mut s = format!(
        "duration = 0.105\ndt = 1.0e-3\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\ntime = \"latest\"\nfield = \"U\"\n[flow.patches]\nwalls = [\"zmin\"]\nwall_model = \"rebound\"\nrestitution = 0.5\n{erosion}\n"
    );
    for (k, (alpha, law, n)) in groups.iter().enumerate() {
        let ps: Vec<String> = (0..*n)
            .map(|i| {
                format!(
                    "[0.05, {:.4}, 0.5]",
                    0.1 + 0.8 * (i as f64 + 0.5) / *n as f64
                )
            })
            .collect();
        s += &format!(
            "[[groups]]\nname = \"g{k}\"\ndiameter = 1.0e-4\ndensity = 2000.0\nalpha = {alpha}\nlaw = \"{law}\"\npositions = [{}]\nvelocity = [{}, {}, {}]\n",
            ps.join(", "),
            v[0],
            v[1],
            v[2]
        );
    }
    let path = dir.join("scene.toml");
    std::fs::write(&path, s).unwrap();
    scg::scene::load(&path, &[])
}

fn scene(dir: &std::path::Path, groups: &[(f64, &str, usize)], erosion: &str) -> scg::scene::Scene {
    load(dir, groups, erosion).unwrap_or_else(|e| panic!("{e}"))
}

const FINNIE: &str = "[erosion]\nmodel = \"finnie\"\nflow_stress = 1.0e9";

fn run(scene: &scg::scene::Scene) -> ErosionLog {
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    sim.world.resource::<ErosionLog>().clone()
}

#[test]
fn each_impact_wears_finnies_volume_for_the_mass_it_stands_for() {
    let dir = tempfile::tempdir().unwrap();
    case(dir.path());
    let t = THETA_DEG.to_radians();
    let v = 10.0 * DVec3::new(t.cos(), 0.0, -t.sin());
    let m0 = sphere_mass(1e-4, 2000.0);
    for (model_text, model) in [
        (
            FINNIE,
            ErosionModel::Finnie {
                flow_stress: 1e9,
                psi: 2.0,
                k: 2.0,
            },
        ),
        (
            "[erosion]\nmodel = \"dnv\"\nwall_density = 7800.0",
            ErosionModel::Dnv {
                k: 2e-9,
                n: 2.6,
                wall_density: 7800.0,
            },
        ),
    ] {
        let originals = run(&scene(dir.path(), &[(1.0, "scg", 8)], model_text));
        let impacts: u64 = originals.faces.values().map(|w| w.impacts).sum();
        assert_eq!(impacts, 8, "one impact each");
        let want = 8.0 * model.volume(m0, v, DVec3::Z);
        // and by hand for Finnie: m·v²/(p·ψ·K)·(sin 2θ − 3·sin²θ), tan 30° > 1/3: the
        // other branch, K·cos²θ/6
        if let ErosionModel::Finnie { .. } = model {
            let by_hand = 8.0 * m0 * 100.0 / 4e9 * (2.0 * t.cos().powi(2) / 6.0);
            assert!((want - by_hand).abs() <= 1e-12 * by_hand);
        }
        let got = originals.total_volume();
        assert!((got - want).abs() <= 1e-12 * want, "{got} vs {want}");
        // the log keeps how they struck: 30° at 5 m/s normal, 8.66 m/s tangential
        for w in originals.faces.values() {
            assert!((w.mean_angle() - t).abs() <= 1e-12, "{}", w.mean_angle());
            assert!((w.mean_normal_speed() - 10.0 * t.sin()).abs() <= 1e-12);
            assert!((w.mean_tangential_speed() - 10.0 * t.cos()).abs() <= 1e-12);
        }
        // SCG and sampling, α = 2: one particle standing for 8 originals, the same wear
        // (its own mass would count 2 originals under SCG: a quarter)
        for law in ["scg", "sample", "parcel"] {
            let one = run(&scene(dir.path(), &[(2.0, law, 1)], model_text));
            let w = one.total_volume();
            assert!((w - want).abs() <= 1e-12 * want, "{law}: {w} vs {want}");
            assert_eq!(one.faces.values().map(|w| w.impacts).sum::<u64>(), 1);
        }
    }
}

#[test]
fn the_log_survives_a_checkpoint_and_bad_tables_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    case(dir.path());
    let s = scene(dir.path(), &[(1.0, "scg", 8)], FINNIE);
    let whole = run(&s);
    let mut a = s.build(false);
    a.run(80, |_| true).unwrap();
    let c = a.checkpoint();
    let mut b = s.build(false);
    b.restore(&c).unwrap();
    b.run(s.steps() - 80, |_| true).unwrap();
    assert_eq!(*b.world.resource::<ErosionLog>(), whole);
    // impacts happen at t ≈ 0.1 s: before the checkpoint nothing, after all
    assert!(
        c.erosion
            .as_ref()
            .is_some_and(|e| e.0.is_empty() && e.1.is_empty())
    );
    for (erosion, key) in [
        ("[erosion]\nmodel = \"finnie\"", "erosion.flow_stress"),
        ("[erosion]\nmodel = \"oka\"", "model"),
        (
            "[erosion]\nmodel = \"dnv\"\nwall_density = 7800.0\npsi = 2.0",
            "erosion.psi",
        ),
        (
            "[erosion]\nmodel = \"finnie\"\nflow_stress = 1e9\npatches = [\"xmax\"]",
            "erosion.patches",
        ),
        (
            "[erosion]\nmodel = \"finnie\"\nflow_stress = -1.0",
            "erosion.flow_stress",
        ),
        ("", ""),
    ] {
        match load(dir.path(), &[(1.0, "scg", 1)], erosion) {
            Ok(_) => assert!(key.is_empty(), "{erosion} accepted"),
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    !key.is_empty() && msg.contains(key) && msg.contains("scene.toml"),
                    "{erosion}: {msg}"
                );
            }
        }
    }
    // no mesh flow: refused
    let dir2 = tempfile::tempdir().unwrap();
    let p = dir2.path().join("s.toml");
    std::fs::write(&p, format!("duration = 1.0\ndt = 0.1\n{FINNIE}\n[[groups]]\nname = \"a\"\ndiameter = 1e-4\ndensity = 1000.0\npositions = [[0.0, 0.0, 0.0]]\n")).unwrap();
    let e = scg::scene::load(&p, &[]).expect_err("erosion without a mesh flow");
    assert!(e.to_string().contains("erosion"), "{e}");
}

/// The total's interval resamples particles, the ones that wore nothing as zeros.
#[test]
fn the_total_carries_a_particle_interval() {
    let mut log = ErosionLog::new(ErosionSpec {
        model: ErosionModel::Finnie {
            flow_stress: 1.0,
            psi: 1.0,
            k: 2.0,
        },
        patches: vec![true],
        walls: Vec::new(),
    });
    // two particles, head-on (θ = 90°: f = K·cos²θ/6 = 0): use 30° impacts instead, with
    // masses 1 and 3 (volumes in the ratio 1 : 3)
    let t = 30f64.to_radians();
    let v = DVec3::new(t.cos(), 0.0, -t.sin());
    log.add(vec![(0, v, DVec3::Z, 1.0, 7), (1, v, DVec3::Z, 3.0, 9)]);
    let q1 = log.by_particle[&7];
    assert!((log.by_particle[&9] - 3.0 * q1).abs() < 1e-15);
    // four entered: values q1·[1, 3, 0, 0], mean q1, s² = q1²·(0 + 4 + 1 + 1)/3
    let (total, lo, hi) = log.total_interval(4);
    let se = (2.0f64).sqrt() * q1 * 2.0;
    assert!((total - 4.0 * q1).abs() < 1e-15);
    assert!((hi - (total + 1.96 * se)).abs() < 1e-12 * hi && lo == 0.0);
}

/// The squareBend duct with rebounding walls: SCG α = 2 and 4 (the feed scaled by 1/α³)
/// wear the walls as the originals do, within the intervals of the difference.
#[test]
fn scg_wears_the_bend_as_the_originals_do() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/squarebend.toml");
    let run = |alpha: f64| {
        let set: Vec<String> = [
            "flow.patches.wall_model=\"rebound\"".to_string(),
            "flow.patches.restitution=0.8".into(),
            format!("coarse_grain.alpha={alpha}"),
            format!("feed_scale={}", 1.0 / alpha.powi(3)),
        ]
        .into();
        let mut text = std::fs::read_to_string(&path).unwrap();
        text.push_str("\n[erosion]\nmodel = \"finnie\"\nflow_stress = 1.0e9\n");
        let dir = path.parent().unwrap();
        let s = scg::scene::parse_in(&text, &path.display().to_string(), dir, "squarebend", &set)
            .unwrap_or_else(|e| panic!("{e}"));
        let mut sim = s.build(false);
        sim.run(s.steps(), |_| true).unwrap();
        let fed = sim
            .world
            .resource::<scg::core::state::Tally>()
            .fed
            .iter()
            .sum::<u64>();
        let (t, lo, hi) = sim.world.resource::<ErosionLog>().total_interval(fed);
        (t, (hi - lo) / (2.0 * 1.96))
    };
    let (q1, s1) = run(1.0);
    eprintln!("originals: {q1:.4e} m³ ± {:.2e}", 1.96 * s1);
    for alpha in [2.0, 4.0] {
        let (q, s) = run(alpha);
        let band = 1.96 * (s * s + s1 * s1).sqrt();
        eprintln!(
            "α = {alpha}: {q:.4e} m³ ± {:.2e}; difference {:.2e} within ±{band:.2e}",
            1.96 * s,
            q - q1
        );
        assert!((q - q1).abs() <= band, "α {alpha}: {q} vs {q1} (±{band})");
    }
}

/// `--erosion-vtk`: the logged patch as polygons with the wear per face; its volumes sum
/// to the log's total and its CSV rows are the faces hit.
#[test]
fn the_erosion_map_holds_every_logged_face() {
    let dir = tempfile::tempdir().unwrap();
    case(dir.path());
    let s = scene(dir.path(), &[(1.0, "scg", 8)], FINNIE);
    let mut sim = s.build(false);
    sim.run(s.steps(), |_| true).unwrap();
    let total = sim.world.resource::<ErosionLog>().total_volume();
    let vtk = scg::cli::erosion::vtk(&s, &sim).expect("a map");
    let tok: Vec<&str> = vtk.split_whitespace().collect();
    let at = |w: &str| tok.iter().position(|t| *t == w).unwrap();
    // the zmin patch of a 4 × 4 × 4 box: 16 quads
    assert_eq!(tok[at("CELLS") + 1], "16");
    assert_eq!(tok[at("CELL_TYPES") + 1], "16");
    let i = at("volume_m3") + 5; // double 1 LOOKUP_TABLE default
    let sum: f64 = tok[i..i + 16]
        .iter()
        .map(|v| v.parse::<f64>().unwrap())
        .sum();
    assert!((sum - total).abs() <= 1e-12 * total, "{sum} vs {total}");
    let rows = scg::cli::erosion::rows(&s, &sim).unwrap();
    assert_eq!(rows.iter().map(|r| r.impacts).sum::<u64>(), 8);
    assert!(
        rows.iter()
            .all(|r| r.patch == "zmin" && r.centre[2].abs() < 1e-12)
    );
    let csv = scg::cli::erosion::csv(&rows);
    assert_eq!(csv.lines().count(), rows.len() + 1);
}

/// `[erosion]` on `[[walls]]` that act as impulses, without a mesh flow: particles fired
/// at an analytic plane at 30° (no air, no gravity: they strike at their own velocity)
/// wear it Finnie's volume per impact to 1e-12, as one face without a centre or area;
/// beads dropped into an STL box that sticks wear the triangles they land on, and the
/// wear map and the VTK surface carry the box's triangles; bad `erosion.walls` entries and
/// a scene with nothing to erode are refused naming the key.
#[test]
fn impulse_walls_wear_too_stl_per_triangle() {
    let d = tempfile::tempdir().unwrap();
    let t = THETA_DEG.to_radians();
    let plane = format!(
        "duration = 0.002\ndt = 1.0e-5\n[[walls]]\nname = \"floor\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmodel = \"rebound\"\nrestitution = 0.5\n{FINNIE}\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-4\ndensity = 2000.0\npositions = [[0.0, 0.0, 1.0e-3], [0.0, 1.0e-3, 1.0e-3], [0.0, 2.0e-3, 1.0e-3], [0.0, 3.0e-3, 1.0e-3]]\nvelocity = [{}, 0.0, {}]\n",
        10.0 * t.cos(),
        -10.0 * t.sin()
    );
    let path = d.path().join("plane.toml");
    std::fs::write(&path, &plane).unwrap();
    let sc = scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let log = sim.world.resource::<ErosionLog>().clone();
    let model = ErosionModel::Finnie {
        flow_stress: 1e9,
        psi: 2.0,
        k: 2.0,
    };
    let v = 10.0 * DVec3::new(t.cos(), 0.0, -t.sin());
    let want = 4.0 * model.volume(sphere_mass(1e-4, 2000.0), v, DVec3::Z);
    assert!((log.total_volume() - want).abs() <= 1e-12 * want);
    assert_eq!(log.wall_faces.len(), 1);
    let w = log.wall_faces[&(0, 0)];
    assert_eq!(w.impacts, 4);
    assert!((w.mean_angle() - t).abs() <= 1e-12);
    let rows = scg::cli::erosion::rows(&sc, &sim).unwrap();
    assert_eq!(rows.len(), 1);
    assert!(rows[0].patch == "floor" && rows[0].area.is_nan() && rows[0].centre[0].is_nan());
    let text = scg::cli::erosion::render(&sc, &sim, &rows);
    assert!(
        text.contains("wall `floor`: 4 impacts on 1 faces"),
        "{text}"
    );
    assert!(!text.contains("deepest"), "no area, no depth: {text}");

    // the STL box, beads dropped in, sticking
    let fixture = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/mesh-box.stl");
    let mut text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/mesh-box.toml"
    ))
    .unwrap()
    .replace(
        "file = \"mesh-box.stl\"",
        &format!("file = \"{fixture}\"\nmodel = \"stick\""),
    )
    .replace("duration = 0.02", "duration = 0.1");
    let i = text.find("[material]").unwrap();
    let j = text.find("[[walls]]").unwrap();
    text.replace_range(i..j, &format!("{FINNIE}\n\n"));
    let path = d.path().join("box.toml");
    std::fs::write(&path, &text).unwrap();
    let sc = scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let log = sim.world.resource::<ErosionLog>().clone();
    let hits: u64 = log.wall_faces.values().map(|w| w.impacts).sum();
    assert_eq!(hits, 4, "each bead strikes once, and sticks");
    assert!(log.total_volume() > 0.0);
    let rows = scg::cli::erosion::rows(&sc, &sim).unwrap();
    // the beads drift sideways and stick to the side walls (the one thrown at 0.3 m/s
    // along +y strikes the y = 5 mm side at 0.3 m/s normal)
    assert!(rows.iter().all(|r| r.patch == "box"
        && r.area > 0.0
        && r.centre.iter().all(|c| c.abs() <= 5e-3 + 1e-12)));
    assert!(
        rows.iter()
            .any(|r| r.centre[1] == 5e-3 && (r.normal_speed - 0.3).abs() < 1e-12)
    );
    let map =
        scg::core::stages::erosion::wear_map(&sim.world, sim.step_count(), sim.time()).unwrap();
    assert_eq!(map.patches.len(), 1);
    let p = &map.patches[0];
    let scg::core::physics::wall_shape::WallShape::Mesh(m) = &sc.impulse_walls[0].wall.shape else {
        panic!()
    };
    assert_eq!(
        (p.name.as_str(), p.faces.len()),
        ("box", m.triangles().len())
    );
    let sum: f64 = p.volume.iter().sum();
    assert!((sum - log.total_volume()).abs() <= 1e-12 * sum);
    let vtk = scg::cli::erosion::vtk(&sc, &sim).unwrap();
    assert!(vtk.contains(&format!(
        "CELLS {} {}",
        m.triangles().len(),
        4 * m.triangles().len()
    )));

    // refused: an unknown wall, a wall particles escape through, nothing to erode
    for (edit, key) in [
        ("flow_stress = 1.0e9\nwalls = [\"lid\"]", "erosion.walls"),
        (
            "flow_stress = 1.0e9\npatches = [\"walls\"]",
            "erosion.patches",
        ),
    ] {
        std::fs::write(&path, text.replace("flow_stress = 1.0e9", edit)).unwrap();
        let e = scg::scene::load(&path, &[]).unwrap_err().to_string();
        assert!(e.contains(key), "{e}");
    }
    std::fs::write(
        &path,
        text.replace("model = \"stick\"", "model = \"escape\""),
    )
    .unwrap();
    let e = scg::scene::load(&path, &[]).unwrap_err().to_string();
    assert!(e.contains("nothing to erode"), "{e}");
}
