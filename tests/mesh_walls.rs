//! Walls from STL meshes against the analytic walls, with the real wall systems in a tiny
//! World: a tilted plane, a shared edge, a corner, a faceted cylinder; bad STL files; a
//! mesh scene through the command line.

use std::process::Command;
use std::sync::Arc;

use glam::DVec3;
use scg::core::components::{Force, ParticleId, Position, Velocity, WallHistory};
use scg::core::physics::contact::{Material, NormalLaw};
use scg::core::physics::flow::FlowField;
use scg::core::physics::integrate::Integrator;
use scg::core::physics::scaling::CoarseGrainLaw;
use scg::core::physics::trimesh::{TriMesh, weld};
use scg::core::physics::wall_shape::WallShape;
use scg::core::stages::walls::{Wall, WallSet};
use scg::core::{ParticleSpec, SimConfig, Simulation};
use scg::scene::stl;

const D: f64 = 1e-3;
const RHO: f64 = 2500.0;

fn material(e: f64, friction: f64) -> Material {
    Material {
        youngs_modulus: 1e8,
        poisson_ratio: 0.3,
        restitution: e,
        friction,
    }
}

/// A mesh wall through the STL path: the soup is written as binary STL (f32), read
/// back, welded and placed as a scene's `scale`, `rotate` (degrees), `translate` do.
fn mesh(soup: &[[DVec3; 3]], rotate: DVec3, translate: DVec3) -> WallShape {
    let read = stl::parse(&stl::write_binary(soup)).unwrap();
    let (v, t) = weld(&read);
    let v = stl::place(v, 1.0, rotate, translate);
    WallShape::Mesh(Arc::new(TriMesh::new(v, t).unwrap()))
}

/// The same through an ASCII STL, whose coordinates keep every f64 digit (Rust prints
/// the shortest text that reads back to the same f64).
fn mesh_f64(soup: &[[DVec3; 3]]) -> WallShape {
    let mut text = String::from("solid t\n");
    for t in soup {
        text.push_str("facet normal 0 0 0\nouter loop\n");
        for v in t {
            text.push_str(&format!("vertex {:e} {:e} {:e}\n", v.x, v.y, v.z));
        }
        text.push_str("endloop\nendfacet\n");
    }
    text.push_str("endsolid t\n");
    let read = stl::parse(text.as_bytes()).unwrap();
    assert_eq!(read, soup);
    let (v, t) = weld(&read);
    WallShape::Mesh(Arc::new(TriMesh::new(v, t).unwrap()))
}

/// A square [−l, l]² in z = 0 as 2·n² triangles.
fn square(l: f64, n: usize) -> Vec<[DVec3; 3]> {
    let p = |i: usize, j: usize| {
        DVec3::new(
            -l + 2.0 * l * i as f64 / n as f64,
            -l + 2.0 * l * j as f64 / n as f64,
            0.0,
        )
    };
    let mut soup = Vec::new();
    for i in 0..n {
        for j in 0..n {
            soup.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            soup.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    soup
}

#[derive(Clone, Debug)]
struct Sample {
    x: DVec3,
    v: DVec3,
    f: DVec3,
    hist: Vec<(u32, DVec3)>,
}

/// One particle against `shapes`; a sample after every step.
fn run(
    shapes: Vec<WallShape>,
    mat: Material,
    gravity: Option<DVec3>,
    dt: f64,
    x0: DVec3,
    v0: DVec3,
    steps: usize,
) -> Vec<Sample> {
    let mut sim = Simulation::new(SimConfig {
        dt,
        integrator: Integrator::Exponential,
        drag: None,
        fluid: None,
        flow: FlowField::Still,
        mesh_flow: None,
        gravity,
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        contacts: None,
        walls: Some(WallSet {
            walls: shapes
                .into_iter()
                .enumerate()
                .map(|(i, shape)| Wall {
                    name: format!("w{i}"),
                    shape,
                    motion: Default::default(),
                })
                .collect(),
            law: NormalLaw::hertz(mat.restitution),
            material: mat,
        }),
        record_every: None,
        groups: vec!["p".into()],
        carrier: None,
    });
    sim.spawn(&ParticleSpec {
        group: 0,
        diameter: D,
        density: RHO,
        alpha: 1.0,
        law: CoarseGrainLaw::Scg,
        position: x0,
        velocity: v0,
    });
    let mut q = sim.world.query::<(
        &ParticleId,
        &Position,
        &Velocity,
        &Force,
        Option<&WallHistory>,
    )>();
    (0..steps)
        .map(|_| {
            sim.step().unwrap();
            let (_, x, v, f, h) = q.single(&sim.world).unwrap();
            Sample {
                x: x.0,
                v: v.0,
                f: f.0,
                hist: h.map(|h| h.0.clone()).unwrap_or_default(),
            }
        })
        .collect()
}

/// Largest differences of force, velocity and position over two runs, relative to the
/// largest force, velocity and (for positions) the diameter.
fn worst(a: &[Sample], b: &[Sample]) -> (f64, f64, f64) {
    let fmax = a.iter().map(|s| s.f.length()).fold(0.0, f64::max);
    let vmax = a.iter().map(|s| s.v.length()).fold(0.0, f64::max);
    let (mut df, mut dv, mut dx) = (0.0_f64, 0.0_f64, 0.0_f64);
    for (p, q) in a.iter().zip(b) {
        df = df.max((p.f - q.f).length() / fmax);
        dv = dv.max((p.v - q.v).length() / vmax);
        dx = dx.max((p.x - q.x).length() / D);
    }
    (df, dv, dx)
}

/// An oblique bounce on a 40 mm square of two triangles tilted 30° (`rotate = [30, 0, 0]`)
/// follows the analytic plane: force, velocity and position within 1e-9 relative, at
/// every step, with friction (the tangential spring and its history in play). The
/// sphere lands on the square's diagonal, the shared edge.
#[test]
fn tilted_stl_plane_matches_the_analytic_plane() {
    let rot = DVec3::new(30.0, 0.0, 0.0);
    let origin = DVec3::new(1e-3, -2e-3, 3e-3);
    let normal = stl::rotation(rot) * DVec3::Z;
    let plane = WallShape::Plane {
        point: origin,
        normal,
    };
    let tilted = mesh(&square(0.02, 1), rot, origin);
    // Along the tilted square's diagonal direction, approaching at 0.5 m/s obliquely.
    let along = stl::rotation(rot) * DVec3::new(1.0, 1.0, 0.0).normalize();
    let x0 = origin + normal * (0.5 * D + 2e-5) - along * 1e-4;
    let v0 = -0.5 * normal + 0.3 * along;
    let mat = material(0.7, 0.3);
    let a = run(vec![plane], mat, None, 2e-7, x0, v0, 800);
    let b = run(vec![tilted], mat, None, 2e-7, x0, v0, 800);
    let touched = a.iter().filter(|s| s.f != DVec3::ZERO).count();
    assert!(
        touched > 100 && a.last().unwrap().f == DVec3::ZERO,
        "{touched} contact steps, no rebound"
    );
    let (df, dv, dx) = worst(&a, &b);
    println!(
        "tilted plane: max |ΔF|/F_max {df:.2e}, |Δv|/v_max {dv:.2e}, |Δx|/d {dx:.2e} over {touched} contact steps"
    );
    assert!(df < 1e-9 && dv < 1e-9 && dx < 1e-9, "{df:e} {dv:e} {dx:e}");
    // Sliding and sticking both happened: a tangential history was kept.
    assert!(b.iter().any(|s| s.hist.iter().any(|h| h.1 != DVec3::ZERO)));
}

/// A sphere rolling down a 10° incline (gravity tilted, the plane z = 0 of two triangles
/// split along y = x) across the shared edge: static friction holds a tangential
/// spring. One contact at every step (never two), the plane's force at every step (1e-9
/// relative), and the same tangential history as on the analytic plane across the edge.
#[test]
fn rolling_across_a_shared_edge_keeps_one_contact_and_its_history() {
    let plane = WallShape::Plane {
        point: DVec3::ZERO,
        normal: DVec3::Z,
    };
    let two = mesh(&square(0.01, 1), DVec3::ZERO, DVec3::ZERO);
    let down = DVec3::new(1.0, -1.0, 0.0).normalize();
    let beta = 10f64.to_radians();
    let g = Some(9.81 * (down * beta.sin() - DVec3::Z * beta.cos()));
    let x0 = DVec3::new(-0.2e-3, 0.2e-3, 0.5 * D - 1e-7);
    let v0 = 0.03 * down;
    let mat = material(0.3, 0.3);
    let steps = 100_000;
    let a = run(vec![plane], mat, g, 2e-7, x0, v0, steps);
    let b = run(vec![two], mat, g, 2e-7, x0, v0, steps);
    // It crossed the diagonal y = x, the edge shared by the two triangles.
    assert!(x0.y > x0.x && b.last().unwrap().x.y < b.last().unwrap().x.x);
    let cross = b.iter().position(|s| s.x.y < s.x.x).unwrap();
    for (k, (p, q)) in a.iter().zip(&b).enumerate() {
        assert!(q.hist.len() <= 1, "step {k}: {} contacts", q.hist.len());
        assert_eq!(p.hist.len(), q.hist.len(), "step {k}");
    }
    let hmax = a
        .iter()
        .flat_map(|s| s.hist.iter().map(|h| h.1.length()))
        .fold(0.0, f64::max);
    let dh = a
        .iter()
        .zip(&b)
        .flat_map(|(p, q)| {
            p.hist
                .iter()
                .zip(&q.hist)
                .map(|(u, w)| (u.1 - w.1).length())
        })
        .fold(0.0, f64::max)
        / hmax;
    let (df, dv, dx) = worst(&a, &b);
    let at_cross = b[cross].hist[0].1.length();
    println!(
        "shared edge: crossed at step {cross} with |ξ| = {at_cross:.3e} m (max {hmax:.3e}); max |ΔF|/F {df:.2e}, |Δv|/v {dv:.2e}, |Δx|/d {dx:.2e}, |Δξ|/ξ_max {dh:.2e}"
    );
    // Static friction holds a spring of about a nanometre while it rolls; the mesh carries
    // it over the edge unchanged (a reset would show as |Δξ| ≈ |ξ|).
    assert!(at_cross > 1e-10, "no history to carry at the crossing");
    for k in cross - 5..cross + 5 {
        let (u, w) = (a[k].hist[0].1, b[k].hist[0].1);
        assert!(
            (u - w).length() <= 1e-9 * u.length(),
            "step {k}: {u} vs {w}"
        );
    }
    // One key for the whole flat region, before and after the edge.
    assert_eq!(b[cross - 1].hist[0].0, b[cross + 1].hist[0].0);
    assert!(
        df < 1e-9 && dv < 1e-9 && dx < 1e-9 && dh < 1e-9,
        "{df:e} {dv:e} {dx:e} {dh:e}"
    );
}

/// A sphere thrown into the 90° corner of two STL faces (floor z = 0, wall x = 0, one
/// mesh) feels two contacts at once, equal to two analytic planes (1e-9 relative).
#[test]
fn corner_of_two_faces_gives_two_contacts_like_two_planes() {
    let l = 0.01;
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let soup = vec![
        // Floor z = 0, x ∈ [0, l].
        [p(0.0, -l, 0.0), p(l, -l, 0.0), p(l, l, 0.0)],
        [p(0.0, -l, 0.0), p(l, l, 0.0), p(0.0, l, 0.0)],
        // Wall x = 0, z ∈ [0, l].
        [p(0.0, -l, 0.0), p(0.0, l, 0.0), p(0.0, l, l)],
        [p(0.0, -l, 0.0), p(0.0, l, l), p(0.0, -l, l)],
    ];
    let corner = mesh(&soup, DVec3::ZERO, DVec3::ZERO);
    let planes = vec![
        WallShape::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Z,
        },
        WallShape::Plane {
            point: DVec3::ZERO,
            normal: DVec3::X,
        },
    ];
    let x0 = DVec3::new(0.5 * D + 1e-5, 1e-4, 0.5 * D + 1.2e-5);
    let v0 = DVec3::new(-0.4, 0.1, -0.4);
    let mat = material(0.6, 0.3);
    let a = run(planes, mat, None, 2e-7, x0, v0, 800);
    let b = run(vec![corner], mat, None, 2e-7, x0, v0, 800);
    let both = b.iter().filter(|s| s.hist.len() == 2).count();
    assert!(both > 50, "two contacts at once for {both} steps only");
    for (p, q) in a.iter().zip(&b) {
        assert_eq!(p.hist.len(), q.hist.len());
    }
    let (df, dv, dx) = worst(&a, &b);
    println!(
        "corner: {both} steps with two contacts; max |ΔF|/F {df:.2e}, |Δv|/v {dv:.2e}, |Δx|/d {dx:.2e}"
    );
    assert!(df < 1e-9 && dv < 1e-9 && dx < 1e-9, "{df:e} {dv:e} {dx:e}");
}

/// The inside of a cylinder of radius r_c as n flat facets (2 triangles each), vertices on
/// the circle, z ∈ [−h, h].
fn faceted_cylinder(rc: f64, h: f64, n: usize) -> Vec<[DVec3; 3]> {
    let p = |k: usize, z: f64| {
        let a = std::f64::consts::TAU * (k % n) as f64 / n as f64;
        DVec3::new(rc * a.cos(), rc * a.sin(), z)
    };
    (0..n)
        .flat_map(|k| {
            [
                [p(k, -h), p(k + 1, -h), p(k + 1, h)],
                [p(k, -h), p(k + 1, h), p(k, h)],
            ]
        })
        .collect()
}

/// A radial impact at 0.5 m/s on the inside of a cylinder (R = 10 mm) made of n = 32,
/// 64, 128 facets (coordinates kept in f64) against the analytic cylinder, aimed at a
/// facet's middle, where the facet lies a sagitta s = R(1 − cos(π/n)) inside the circle.
/// * Against the analytic cylinder of radius R·cos(π/n), tangent to the facet there, the
///   run is the same to 1e-9 (position / d, velocity / V): the faceted wall is exact.
/// * Against radius R the rebound starts s early, so shortly after it the sphere is
///   (1 + e)·s ahead: |Δx| = (1 + e)·s within 2 %, which falls as 1/n² (×4 per doubling);
///   the speed differs only by the restitution's dependence on where in a time step the
///   contact starts (< 1e-3·V; measured 3·10⁻⁵ to 2.5·10⁻⁴).
/// * Aimed off the middle (0.3 of a facet from a vertex) the facet's normal is off the
///   radius by θ = 0.2·2π/n and the rebound velocity by (1 + e)·V·2 sin(θ/2) ≈
///   (1 + e)·V·θ: between 0.9 and 1.01 of it.
///
/// Compare s with the Hertz maximum overlap δ_max ≈ 9 µm here: s = 48, 12, 3 µm.
#[test]
fn faceted_cylinder_rebound_within_the_faceting_error() {
    let (rc, v, e) = (0.01, 0.5, 0.8);
    let mat = material(e, 0.0);
    let cylinder = |radius| WallShape::CylinderInside {
        center: DVec3::ZERO,
        axis: DVec3::Z,
        radius,
        extent: None,
    };
    let dt = 2e-7;
    // To the wall, then 2000 steps (0.4 ms, several contact times) on.
    let steps = ((rc - 0.5 * D) / v / dt) as usize + 2000;
    let mut last = f64::INFINITY;
    for n in [32usize, 64, 128] {
        let facets = mesh_f64(&faceted_cylinder(rc, 0.02, n));
        let half = std::f64::consts::PI / n as f64;
        let sagitta = rc * (1.0 - half.cos());
        let go = |shape: &WallShape, at: f64| {
            let phi = std::f64::consts::TAU * at / n as f64;
            let dir = DVec3::new(phi.cos(), phi.sin(), 0.0);
            let s = run(
                vec![shape.clone()],
                mat,
                None,
                dt,
                DVec3::ZERO,
                v * dir,
                steps,
            );
            assert!(s.last().unwrap().v.dot(dir) < 0.0, "n = {n}: no rebound");
            s.last().unwrap().clone()
        };
        // Facet 3's middle.
        let m = go(&facets, 3.5);
        let tangent = go(&cylinder(rc * half.cos()), 3.5);
        let (dx0, dv0) = (
            (m.x - tangent.x).length() / D,
            (m.v - tangent.v).length() / v,
        );
        let round = go(&cylinder(rc), 3.5);
        let dx = (m.x - round.x).length();
        let dv = (m.v - round.v).length() / v;
        let ratio = dx / ((1.0 + e) * sagitta);
        // Off the middle.
        let dv2 = (go(&facets, 3.3).v - go(&cylinder(rc), 3.3).v).length() / v;
        let theta = 0.2 * std::f64::consts::TAU / n as f64;
        println!(
            "n = {n:3}: sagitta {sagitta:.3e} m; facet middle vs tangent cylinder |Δx|/d {dx0:.1e}, |Δv|/V {dv0:.1e}; vs R: |Δx| {dx:.3e} m = {ratio:.4}·(1+e)s, |Δv|/V {dv:.1e}; off the middle: |Δv|/V {dv2:.3e} (bound (1+e)θ = {:.3e})",
            (1.0 + e) * theta
        );
        assert!(dx0 < 1e-9 && dv0 < 1e-9, "n = {n}: {dx0:e} {dv0:e}");
        assert!((ratio - 1.0).abs() < 0.02, "n = {n}: |Δx| = {ratio}·(1+e)s");
        assert!(dv < 1e-3, "n = {n}: |Δv|/V = {dv:e}");
        let bound = (1.0 + e) * theta;
        assert!(dv2 > 0.9 * bound && dv2 < 1.01 * bound, "n = {n}: {dv2:e}");
        assert!(
            dx < last / 3.5,
            "n = {n}: the error must fall about 4× per doubling"
        );
        last = dx;
    }
}

/// Gzip `bytes` with a minimal encoder-free member: a stored (uncompressed) deflate
/// stream, which every gzip reader accepts.
fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut out = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 255];
    let mut chunks = bytes.chunks(65535).peekable();
    while let Some(c) = chunks.next() {
        out.push(u8::from(chunks.peek().is_none()));
        let n = c.len() as u16;
        out.extend_from_slice(&n.to_le_bytes());
        out.extend_from_slice(&(!n).to_le_bytes());
        out.extend_from_slice(c);
    }
    // CRC-32 (IEEE) and the size.
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    out.extend_from_slice(&(!crc).to_le_bytes());
    out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    out
}

/// History keys: analytic wall i → i; mesh walls' flat regions after the last wall.
#[test]
fn history_keys_number_mesh_regions_after_the_walls() {
    use scg::core::stages::walls::history_keys;
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    // An open box: 5 flat regions.
    let text = std::fs::read(FIXTURE.replace(".toml", ".stl")).unwrap();
    let (v, t) = weld(&stl::parse(&text).unwrap());
    let open_box = WallShape::Mesh(Arc::new(TriMesh::new(v, t).unwrap()));
    let one = mesh(
        &[[p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)]],
        DVec3::ZERO,
        DVec3::ZERO,
    );
    let plane = WallShape::Plane {
        point: DVec3::ZERO,
        normal: DVec3::Z,
    };
    let walls: Vec<Wall> = [plane.clone(), open_box, plane, one]
        .into_iter()
        .map(|shape| Wall {
            name: "w".into(),
            shape,
            motion: Default::default(),
        })
        .collect();
    assert_eq!(history_keys(&walls), vec![0, 4, 2, 9]);
}

fn scg() -> Command {
    Command::new(env!("CARGO_BIN_EXE_scg"))
}

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/mesh-box.toml");

/// `scg check` describes the mesh; `scg run` runs it, the beads stay in the box.
#[test]
fn mesh_scene_runs_end_to_end() {
    let out = scg().args(["check", FIXTURE]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains(
            "wall `box`: mesh of 10 triangles, 8 vertices, 17 edges, open, 5 flat regions"
        ),
        "{text}"
    );
    // The same file gzip-compressed (`.stl.gz`) gives the same mesh.
    let gz_dir = tempfile::tempdir().unwrap();
    let stl_bytes = std::fs::read(FIXTURE.replace(".toml", ".stl")).unwrap();
    std::fs::write(gz_dir.path().join("box.stl.gz"), gzip(&stl_bytes)).unwrap();
    let scene = std::fs::read_to_string(FIXTURE).unwrap();
    let gz_case = gz_dir.path().join("gz.toml");
    std::fs::write(&gz_case, scene.replace("mesh-box.stl", "box.stl.gz")).unwrap();
    let out = scg().arg("check").arg(&gz_case).output().unwrap();
    let gz_text = String::from_utf8_lossy(&out.stdout);
    let line = |t: &str| {
        t.lines()
            .find(|l| l.starts_with("wall `box`"))
            .map(str::to_owned)
    };
    assert!(
        out.status.success() && line(&gz_text) == line(&text),
        "{gz_text}"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = scg()
        .args(["run", FIXTURE, "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for ext in ["rrd", "mcap"] {
        assert!(dir.path().join(format!("mesh-box.{ext}")).is_file());
    }
    // The MCAP keeps the wall's feature edges (12, chained) and its triangles (the .rrd
    // logs them as `geometry/box` line strips and a `geometry/box/surface` Mesh3D).
    let rec = scg::record::read_mcap(&dir.path().join("mesh-box.mcap")).unwrap();
    let o = &rec.meta.outlines[0];
    let segments: usize = o.strips.iter().map(|s| s.len() - 1).sum();
    assert_eq!((o.name.as_str(), segments), ("box", 12));
    assert_eq!((o.vertices.len(), o.triangles.len()), (8, 10));
    // The same scene in a World: after 0.02 s every bead is inside the box (without the
    // mesh each would have fallen below the floor by then).
    let scene = scg::scene::load(std::path::Path::new(FIXTURE), &[]).unwrap();
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    for p in sim.particles() {
        let x = p.position;
        assert!(x.z > 0.45e-3 && x.z < 4e-3, "{x}");
        assert!(x.x.abs() < 4.6e-3 && x.y.abs() < 4.6e-3, "{x}");
    }
}

/// Bad STL files and mesh keys: exit status 2, a message naming the scene file, the key
/// and its line, and the STL file (and triangle), never a panic.
#[test]
fn bad_stl_files_are_errors_naming_file_key_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/mesh-box.stl"
    ))
    .unwrap();
    let bin = stl::write_binary(&square(1.0, 2));
    let ascii = String::from_utf8(good.clone()).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "truncated.stl",
            bin[..bin.len() - 20].to_vec(),
            "triangle 7: binary STL declares 8 triangles",
        ),
        (
            "garbage.stl",
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2 oops\n".to_vec(),
            "triangle 0: line 4: expected a number, found `oops`",
        ),
        (
            "noise.stl",
            (0..200u32).map(|i| (i * 37 % 251) as u8).collect(),
            "triangle 2: binary STL declares 991358151 triangles",
        ),
        (
            "nan.stl",
            ascii
                .replacen("vertex 10 10 0", "vertex nan 10 0", 1)
                .into_bytes(),
            "triangle 0: non-finite corner",
        ),
        ("empty.stl", Vec::new(), "empty file"),
        (
            "zero.stl",
            stl::write_binary(&[]),
            "the mesh has no triangles",
        ),
        (
            "flat.stl",
            ascii
                .replacen("vertex 10 10 0", "vertex 0 20 0", 1)
                .into_bytes(),
            "triangle 0: degenerate",
        ),
    ];
    let scene = std::fs::read_to_string(FIXTURE).unwrap();
    for (name, bytes, want) in cases {
        std::fs::write(dir.path().join(name), bytes).unwrap();
        let case = dir.path().join("s.toml");
        std::fs::write(&case, scene.replace("mesh-box.stl", name)).unwrap();
        let out = scg().args(["check"]).arg(&case).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains("s.toml:22: key `walls[0].file`"),
            "{name}: {err}"
        );
        assert!(err.contains(&format!("{name}: {want}")), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
    // A missing file, a missing key, a bad scale.
    for (set, want) in [
        ("walls.0.file=\"nowhere.stl\"", "nowhere.stl: cannot read"),
        ("walls.0.scale=-1.0", "key `walls[0].scale`"),
        ("walls.0.rotate=[0.0, nan, 0.0]", "key `walls[0].rotate`"),
    ] {
        let out = scg()
            .args(["check", FIXTURE, "--set", set])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(want), "{set}: {err}");
    }
}

/// A closed vessel (R = 30 mm, H = 60 mm) as n·rows·2 side triangles and two fans.
fn vessel(rc: f64, h: f64, n: usize, rows: usize) -> Vec<[DVec3; 3]> {
    let p = |k: usize, z: f64| {
        let a = std::f64::consts::TAU * (k % n) as f64 / n as f64;
        DVec3::new(rc * a.cos(), rc * a.sin(), z)
    };
    let z = |j: usize| h * j as f64 / rows as f64;
    let mut soup = Vec::new();
    for k in 0..n {
        for j in 0..rows {
            soup.push([p(k, z(j)), p(k + 1, z(j)), p(k + 1, z(j + 1))]);
            soup.push([p(k, z(j)), p(k + 1, z(j + 1)), p(k, z(j + 1))]);
        }
        soup.push([DVec3::ZERO, p(k + 1, 0.0), p(k, 0.0)]);
        soup.push([DVec3::new(0.0, 0.0, h), p(k, h), p(k + 1, h)]);
    }
    soup
}

/// Cost of the wall forces, 10^5 particles (d = 0.3 mm, random in the vessel, random
/// velocities ±0.5 m/s, friction on) in a vessel of ≈ 10^4 triangles against the same
/// vessel as an analytic cylinder and two planes: seconds per particle-step of the
/// forces set (the walls are its only system here), on one thread, best of three
/// alternating runs. Prints both and their ratio.
/// `cargo test --release --test mesh_walls -- --ignored --nocapture wall_cost`
#[test]
#[ignore = "timing (about a minute): cargo test --release --test mesh_walls -- --ignored --nocapture"]
fn wall_cost_mesh_vs_analytic() {
    // One thread (`SCG_COST_THREADS` to change): per-particle costs, less sensitive to a
    // shared machine than two threads.
    let threads = std::env::var("SCG_COST_THREADS").map_or(1, |t| t.parse().unwrap_or(1));
    scg::core::exec::configure(scg::core::exec::ExecSettings {
        threads,
        ..Default::default()
    });
    let (rc, h) = (0.03, 0.06);
    let soup = vessel(rc, h, 128, 39);
    let mesh = mesh_f64(&soup);
    let WallShape::Mesh(m) = &mesh else {
        unreachable!()
    };
    println!(
        "mesh: {} triangles, grid {:?}",
        m.triangle_count(),
        m.grid_shape()
    );
    let analytic = vec![
        WallShape::CylinderInside {
            center: DVec3::ZERO,
            axis: DVec3::Z,
            radius: rc,
            extent: Some((0.0, h)),
        },
        WallShape::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Z,
        },
        WallShape::Plane {
            point: DVec3::new(0.0, 0.0, h),
            normal: -DVec3::Z,
        },
    ];
    let (n, steps, d) = (100_000usize, 200u64, 0.3e-3);
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut specs = Vec::new();
    while specs.len() < n {
        let x = DVec3::new(2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, rnd());
        if x.x * x.x + x.y * x.y > 1.0 {
            continue;
        }
        let pos = DVec3::new(x.x * (rc - d), x.y * (rc - d), d + x.z * (h - 2.0 * d));
        let vel = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
        specs.push((pos, vel));
    }
    let unsure = |shapes: &[WallShape]| {
        specs
            .iter()
            .filter(|(x, _)| !shapes.iter().all(|w| w.surely_clear(*x, 0.5 * d)))
            .count()
    };
    println!(
        "not surely clear at the start: analytic {}, mesh {} of {n}",
        unsure(&analytic),
        unsure(std::slice::from_ref(&mesh))
    );
    // The pure kernels alone, one thread, 20 passes.
    let t0 = std::time::Instant::now();
    let mut clear = 0usize;
    for _ in 0..20 {
        for (x, _) in &specs {
            clear += usize::from(mesh.surely_clear(*x, 0.5 * d));
        }
    }
    let t_clear = t0.elapsed().as_secs_f64() / (20.0 * n as f64);
    let mut scratch = scg::core::physics::trimesh::MeshScratch::default();
    let mut found = Vec::new();
    let t0 = std::time::Instant::now();
    let mut touching = 0usize;
    for _ in 0..20 {
        for (x, _) in &specs {
            m.contacts(*x, 0.5 * d, &mut scratch, &mut found);
            touching += found.len();
        }
    }
    let t_query = t0.elapsed().as_secs_f64() / (20.0 * n as f64);
    let t0 = std::time::Instant::now();
    let mut clear_a = 0usize;
    for _ in 0..20 {
        for (x, _) in &specs {
            clear_a += usize::from(analytic.iter().all(|w| w.surely_clear(*x, 0.5 * d)));
        }
    }
    let t_clear_a = t0.elapsed().as_secs_f64() / (20.0 * n as f64);
    println!(
        "kernels: mesh surely_clear {t_clear:.2e} s ({clear} clear), full query {t_query:.2e} s ({touching} contacts), analytic surely_clear {t_clear_a:.2e} s ({clear_a})"
    );
    let mut best = [f64::INFINITY; 2];
    for round in 0..3 {
        for (which, (name, shapes)) in
            [("analytic", analytic.clone()), ("mesh", vec![mesh.clone()])]
                .into_iter()
                .enumerate()
        {
            let mat = material(0.8, 0.3);
            let mut sim = Simulation::new(SimConfig {
                dt: 1e-6,
                integrator: Integrator::Exponential,
                drag: None,
                fluid: None,
                flow: FlowField::Still,
                mesh_flow: None,
                gravity: None,
                buoyancy: false,
                scg_at_original: false,
                extra_forces: Default::default(),
                contacts: None,
                walls: Some(WallSet {
                    walls: shapes
                        .into_iter()
                        .map(|shape| Wall {
                            name: "w".into(),
                            shape,
                            motion: Default::default(),
                        })
                        .collect(),
                    law: NormalLaw::hertz(0.8),
                    material: mat,
                }),
                record_every: None,
                groups: vec!["p".into()],
                carrier: None,
            });
            for (pos, vel) in &specs {
                sim.spawn(&ParticleSpec {
                    group: 0,
                    diameter: d,
                    density: RHO,
                    alpha: 1.0,
                    law: CoarseGrainLaw::Scg,
                    position: *pos,
                    velocity: *vel,
                });
            }
            sim.run(steps, |_| true).unwrap();
            let forces = sim.timers().total[scg::core::step::StepSet::Forces.index()].as_secs_f64();
            let per = forces / (n as f64 * steps as f64);
            println!("round {round}, {name}: forces {forces:.3} s, {per:.3e} s per particle-step");
            best[which] = best[which].min(per);
        }
    }
    println!(
        "best of 3: analytic {:.3e}, mesh {:.3e} s per particle-step; mesh / analytic {:.2}",
        best[0],
        best[1],
        best[1] / best[0]
    );
}
