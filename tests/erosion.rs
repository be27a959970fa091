//! `[erosion]`: impacts on the rebound and stick wall patches of a mesh flow, worn into
//! the faces by the scene's model with the original powder's mass each particle stands
//! for. Particles fired ballistically at a wall at 30° hit it once each: the log is
//! Finnie's (and DNV's) formula times the represented mass, to 1e-12; 8 originals, one
//! SCG α = 2 particle and one sampled α = 2 particle wear the same volume; a checkpoint
//! keeps the log; bad tables are refused.

use glam::DVec3;
use scg::core::physics::erosion::ErosionModel;
use scg::core::physics::scaling::sphere_mass;
use scg::core::stages::erosion::ErosionLog;
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
    let mut log = ErosionLog::new(
        ErosionModel::Finnie {
            flow_stress: 1.0,
            psi: 1.0,
            k: 2.0,
        },
        vec![true],
    );
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
