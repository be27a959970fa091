//! `scg bench`: throughput benchmarks (particle-steps per second).

use std::time::Instant;

use clap::{Args, ValueEnum};

use crate::EXIT_BAD_INPUT;

/// What to benchmark.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum BenchKind {
    /// Drag only (Stokes, exponential scheme) in the paper's vortex flow, no recording.
    Drag,
    /// A dilute cloud (solid fraction 0.01) in a periodic box: Stokes drag in still air and
    /// Hertz–Mindlin contacts (neighbour lists built, few contacts).
    Dilute,
    /// A dense chute-like bed: simple cubic packing on a floor, gravity tilted by 26°,
    /// periodic in x and y, Hertz–Mindlin contacts everywhere.
    Dense,
    /// Drag only (Stokes, exponential scheme, cell_point) in the paper's vortex sampled at
    /// the cell centres of a perturbed tetrahedral box generated in memory (`--cells`),
    /// walls all round: the engine path of `flow.kind = "openfoam"`.
    Mesh,
    /// Neighbour-list builds alone (`--steps` each): 100 µm spheres at random, in index
    /// order unrelated to their places, spread at solid fraction 10^-6 (a coarse grid),
    /// in eight packed clusters far apart (hashed cells) and packed at 0.5 (a dense grid),
    /// skin 10 µm. Last line: `particle-builds/s` of the packed cloud.
    Neighbours,
    /// A scene file (`scg bench case SCENE`, `--set` edits it): its whole duration (or
    /// `--steps`) without recording, then the time of each system of its step and what
    /// building the scene took.
    Case,
}

/// The dispersion model a benchmark runs with (`--dispersion`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchDispersion {
    /// No dispersion: the mean flow alone.
    None,
    /// OpenFOAM's StochasticDispersionRAS (`model = "stochastic_ras"`).
    StochasticRas,
    /// The drift-corrected normalised Langevin walk (`model = "langevin"`).
    Langevin,
}

/// The cells of the mesh benchmark's box (`--shape`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchShape {
    /// Six tetrahedra per hexahedron (the tracker's short path: one record per face).
    Tet,
    /// Hexahedra, as blockMesh and snappyHexMesh make (24 tetrahedra each in the
    /// tracker's records).
    Hex,
}

/// Arguments of `scg bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Benchmark.
    pub kind: BenchKind,
    /// Number of particles.
    #[arg(long, default_value_t = 1_000_000)]
    pub particles: u64,
    /// Number of timed steps (after 5 warm-up steps; default 200, `case`: the scene's
    /// whole duration, no warm-up).
    #[arg(long)]
    pub steps: Option<u64>,
    /// `case`: the scene file.
    #[arg(value_name = "SCENE")]
    pub scene: Option<std::path::PathBuf>,
    /// `case`: edit the scene (`key=value`, as `scg run --set`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// `mesh`: about this many cells.
    #[arg(long, default_value_t = 100_000)]
    pub cells: u64,
    /// `mesh`: the cells' shape.
    #[arg(long, value_enum, default_value_t = BenchShape::Tet)]
    pub shape: BenchShape,
    /// Write the benchmark's scene (TOML; `dilute` and `dense` `--steps` + 5 steps long,
    /// `drag` 1 s) to this file instead of running it (not `mesh`: built in memory), e.g.
    /// to run it over MPI ranks with `scg run` (bench/mpi.sh).
    #[arg(long, value_name = "FILE")]
    pub scene_out: Option<std::path::PathBuf>,
    /// `drag` and `mesh`: with turbulent dispersion (docs/dispersion.md), eddies of about
    /// 100 steps; `mesh` reads k and ε per cell (k = 10^-4 m²/s² varying by ±50 % across
    /// the box, ε = 0.1 m²/s³) as a CFD case's fields, `drag` a uniform k and ε. The cost
    /// of dispersion is the difference from the same run without it.
    #[arg(long, value_enum, default_value_t = BenchDispersion::None)]
    pub dispersion: BenchDispersion,
}

/// Turns on `dispersion` in a benchmark's `scene`: per cell on a mesh flow (k varying by
/// ±50 % along x, ε uniform, ∇σ by the cells' centres), uniform otherwise; k/ε = 1 ms,
/// 100 steps of the benchmarks' dt = 10 µs.
pub fn with_dispersion(scene: &mut scg_scene::Scene, dispersion: BenchDispersion) {
    use scg_core::physics::dispersion::{CellTurbulence, Model, Turbulence, sigma_of};
    let model = match dispersion {
        BenchDispersion::None => return,
        BenchDispersion::StochasticRas => Model::StochasticRas,
        BenchDispersion::Langevin => Model::Langevin {
            c0: 2.1,
            csanady: None,
        },
    };
    let (k0, epsilon) = (1.0e-4, 0.1);
    let turbulence = match &scene.mesh_flow {
        Some(m) => {
            let (w, _) = MESH_BENCH_BOX;
            let centres = &m.flow.geometry().cell_centres;
            let k: Vec<f64> = centres.iter().map(|c| k0 * (1.0 + 0.5 * c.x / w)).collect();
            // σ = √(2k/3) with dk/dx = 0.5 k0 / w: ∂σ/∂x = (dk/dx)/(3σ)
            let grad_sigma = k
                .iter()
                .map(|&k| glam::DVec3::X * (0.5 * k0 / w) / (3.0 * sigma_of(k)))
                .collect();
            Turbulence::Cells(std::sync::Arc::new(CellTurbulence {
                epsilon: vec![epsilon; k.len()],
                k,
                grad_sigma,
            }))
        }
        None => Turbulence::Uniform { k: k0, epsilon },
    };
    scene.dispersion = Some(scg_core::stages::carrier::Dispersion {
        model,
        turbulence,
        seed: scene.seed,
        mask: glam::DVec3::ONE,
        own_pass: false,
    });
}

/// The mesh benchmark's box: half-width in x and y and height, m (the vortex's axis is z
/// through the origin).
pub const MESH_BENCH_BOX: (f64, f64) = (1.0e-3, 1.0e-3);

/// The mesh benchmark: `n` 10 µm particles in a cylinder inside a perturbed box of about
/// `cells` cells of `shape` holding the paper's vortex (ω = 31.4 rad/s, k = 0.1) sampled
/// at the cell centres; every boundary patch a wall.
pub fn mesh_scene(n: u64, cells: u64, shape: BenchShape) -> Result<scg_scene::Scene, String> {
    use glam::DVec3;
    use scg_core::physics::mesh_flow::{MeshFlow, PatchRole};
    use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
    let (w, h) = MESH_BENCH_BOX;
    // nx × nx × nx/2 hexahedra, each 6 tetrahedra or itself
    let per_hex = match shape {
        BenchShape::Tet => 6.0,
        BenchShape::Hex => 1.0,
    };
    let nx = ((2.0 * cells as f64 / per_hex).cbrt().round() as usize).max(2);
    let mesh = BoxMesh::new(
        DVec3::new(-w, -w, 0.0),
        DVec3::new(w, w, h),
        [nx, nx, (nx / 2).max(1)],
    )
    .shape(match shape {
        BenchShape::Tet => CellShape::Tet,
        BenchShape::Hex => CellShape::Hex,
    })
    .naming(PatchNaming::Sides)
    .perturbed(0.2, 11)
    .build()
    .map_err(|e| e.to_string())?;
    let geom = scg_mesh::MeshGeometry::new(&mesh).map_err(|e| e.to_string())?;
    let vortex = scg_core::physics::flow::Vortex {
        center: DVec3::ZERO,
        axis: DVec3::Z,
        omega: 31.4,
        inflow_ratio: 0.1,
    };
    let field = scg_mesh::CellField::at_cell_centres(&mesh, &geom, |c| vortex.velocity(c));
    let roles = vec![PatchRole::Wall; mesh.patches.len()];
    let flow = MeshFlow::new(mesh, &field, scg_mesh::Interpolation::CellPoint, roles)
        .map_err(|e| e.to_string())?;
    let text = format!(
        r#"
name = "bench-mesh"
duration = 1.0
dt = 1.0e-5
seed = 7
[fluid]
density = 1.2
viscosity = 1.8e-5
[drag]
law = "stokes"
[[groups]]
name = "p"
diameter = 10.0e-6
density = 1000.0
count = {n}
region = {{ kind = "cylinder", radius_max = {r:e}, height = [{h0:e}, {h1:e}] }}
"#,
        r = 0.9 * w,
        h0 = 0.05 * h,
        h1 = 0.95 * h,
    );
    let mut scene = scg_scene::parse(&text, "<bench>", "bench", &[]).map_err(|e| e.to_string())?;
    scene.mesh_flow = Some(scg_scene::SceneMeshFlow {
        flow: std::sync::Arc::new(flow),
        source: format!(
            "<generated {shape:?} box, {nx}×{nx}×{} hexahedra{}>",
            (nx / 2).max(1),
            if shape == BenchShape::Tet {
                " × 6"
            } else {
                ""
            }
        ),
        field: "U".into(),
        sort_every: scg_core::stages::mesh_flow::SORT_EVERY,
        reader: None,
        rotors: Vec::new(),
        series: None,
    });
    Ok(scene)
}

/// The drag benchmark scene: `n` 10 µm particles spread over the paper's vortex vessel.
pub fn drag_scene(n: u64) -> String {
    format!(
        r#"
name = "bench-drag"
duration = 1.0
dt = 1.0e-5
seed = 7
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "vortex"
rpm = 300.0
inflow_ratio = 0.1
[drag]
law = "stokes"
[[groups]]
name = "p"
diameter = 10.0e-6
density = 1000.0
count = {n}
region = {{ kind = "cylinder", radius_max = 5.0e-4, height = [0.0, 1.0e-3] }}
"#
    )
}

/// Diameter (m), density (kg/m³), Young's modulus (Pa), Poisson ratio, restitution,
/// friction and time step (s) shared by the contact benchmarks and their LIGGGHTS and LAMMPS
/// twins (bench/liggghts/in.*, bench/lammps/in.*, bench/peers.py; run by bench/vs-peers.sh).
pub const CONTACT_BENCH: (f64, f64, f64, f64, f64, f64, f64) =
    (1e-3, 2500.0, 1e8, 0.3, 0.9, 0.5, 1e-6);

fn material_toml() -> String {
    let (_, _, e, nu, rest, mu, _) = CONTACT_BENCH;
    format!(
        "[material]\nyoungs_modulus = {e:e}\npoisson_ratio = {nu}\nrestitution = {rest}\nfriction = {mu}\n"
    )
}

fn positions_toml(ps: &[[f64; 3]]) -> String {
    let items: Vec<String> = ps
        .iter()
        .map(|p| format!("[{:e}, {:e}, {:e}]", p[0], p[1], p[2]))
        .collect();
    format!("[{}]", items.join(", "))
}

/// The dilute benchmark: `n` particles on a jittered cubic lattice (no initial overlaps)
/// at solid fraction 0.01 in a periodic cube, random velocities in ±0.1 m/s.
pub fn dilute_scene(n: u64, steps: u64) -> String {
    use rand::{Rng, SeedableRng};
    let (d, rho, _, _, _, _, dt) = CONTACT_BENCH;
    let phi = 0.01;
    let side = (n as f64).cbrt().ceil() as u64;
    let l = (n as f64 * std::f64::consts::PI / 6.0 * d * d * d / phi).cbrt();
    let a = l / side as f64;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let jitter = 0.45 * (a - d);
    let (mut ps, mut vs) = (Vec::new(), Vec::new());
    'fill: for i in 0..side {
        for j in 0..side {
            for k in 0..side {
                if ps.len() as u64 == n {
                    break 'fill;
                }
                let c = |q: u64| (q as f64 + 0.5) * a;
                let mut jit = || rng.random_range(-jitter..=jitter);
                ps.push([c(i) + jit(), c(j) + jit(), c(k) + jit()]);
                vs.push([
                    rng.random_range(-0.1..=0.1),
                    rng.random_range(-0.1..=0.1),
                    rng.random_range(-0.1..=0.1),
                ]);
            }
        }
    }
    format!(
        "name = \"bench-dilute\"\nduration = {dur:e}\ndt = {dt:e}\nseed = 7\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[flow]\nkind = \"still\"\n[drag]\nlaw = \"stokes\"\n{mat}[contacts]\nskin = {skin:e}\nperiodic = [{l:e}, {l:e}, {l:e}]\n[[groups]]\nname = \"p\"\ndiameter = {d:e}\ndensity = {rho}\npositions = {p}\nvelocities = {v}\n",
        dur = (steps + 5) as f64 * dt,
        mat = material_toml(),
        skin = 0.1 * d,
        p = positions_toml(&ps),
        v = positions_toml(&vs),
    )
}

/// The dense benchmark: `n` particles in a simple cubic packing (spacing d, solid fraction
/// 0.52) 40 × 40 wide on a floor, periodic in x and y, gravity 9.81 m/s² tilted 26°.
pub fn dense_scene(n: u64, steps: u64) -> String {
    let (d, rho, _, _, _, _, dt) = CONTACT_BENCH;
    let w = 40u64;
    let layers = n.div_ceil(w * w);
    let mut ps = Vec::new();
    'fill: for k in 0..layers {
        for j in 0..w {
            for i in 0..w {
                if ps.len() as u64 == n {
                    break 'fill;
                }
                ps.push([
                    (i as f64 + 0.5) * d,
                    (j as f64 + 0.5) * d,
                    (k as f64 + 0.5) * d,
                ]);
            }
        }
    }
    let l = w as f64 * d;
    let lz = 4.0 * layers as f64 * d + 10.0 * d;
    let theta = 26f64.to_radians();
    format!(
        "name = \"bench-dense\"\nduration = {dur:e}\ndt = {dt:e}\nseed = 7\n[gravity]\nacceleration = [{gx:e}, 0.0, {gz:e}]\n{mat}[contacts]\nskin = {skin:e}\nperiodic = [{l:e}, {l:e}, {lz:e}]\n[[walls]]\nname = \"floor\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n[[groups]]\nname = \"p\"\ndiameter = {d:e}\ndensity = {rho}\npositions = {p}\n",
        dur = (steps + 5) as f64 * dt,
        gx = 9.81 * theta.sin(),
        gz = -9.81 * theta.cos(),
        mat = material_toml(),
        skin = 0.1 * d,
        p = positions_toml(&ps),
    )
}

/// `scg bench neighbours`: `builds` builds of the list of `n` spheres at random, spread,
/// clustered and packed; prints each layout's time per build, grid and pairs, and last
/// `particle-builds/s: <packed>`.
fn bench_neighbours(n: u64, builds: u64) -> i32 {
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    use scg_core::physics::neighbour::NeighbourList;
    let (d, skin) = (100e-6, 10e-6);
    let volume = n as f64 * std::f64::consts::PI / 6.0 * d * d * d;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let unit: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()))
        .collect();
    let radius = vec![0.5 * d; n as usize];
    let mut rate = 0.0;
    for (layout, fraction) in [("spread", 1e-6), ("clustered", 0.5), ("packed", 0.5)] {
        let side = (volume / fraction).cbrt();
        let pos: Vec<DVec3> = if layout == "clustered" {
            // Eight packed clusters at the corners of a cube 1000 times their size.
            (unit.iter().enumerate())
                .map(|(k, u)| {
                    let corner =
                        DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64, (k >> 2 & 1) as f64);
                    (*u * 0.5 + corner * 1000.0) * side
                })
                .collect()
        } else {
            unit.iter().map(|u| *u * side).collect()
        };
        let mut list = NeighbourList::new(skin, None);
        let t0 = Instant::now();
        for _ in 0..builds {
            list.build(&pos, &radius);
        }
        let per = t0.elapsed().as_secs_f64() / builds as f64;
        let place = if layout == "clustered" {
            format!(
                "in eight {:.3} m cubes {:.1} m apart",
                0.5 * side,
                1000.0 * side
            )
        } else {
            format!("in a {side:.3} m cube")
        };
        println!(
            "{layout}: {n} particles {place} (solid fraction {fraction:e}): \
             {per:.4} s a build on a {:?} grid, {} pairs",
            list.grid,
            list.pairs.len()
        );
        rate = n as f64 / per;
    }
    println!("particle-builds/s: {rate:.4e}");
    0
}

/// Run a benchmark; the last line printed is `particle-steps/s: <number>`
/// (`particle-builds/s` for `neighbours`).
pub fn bench(a: BenchArgs) -> i32 {
    if let BenchKind::Case = a.kind {
        return bench_case(&a);
    }
    if a.scene.is_some() || !a.set.is_empty() {
        eprintln!("error: a scene file and --set are for `scg bench case` only");
        return EXIT_BAD_INPUT;
    }
    let steps = a.steps.unwrap_or(200);
    if a.particles == 0 || steps == 0 {
        eprintln!("error: --particles and --steps must be ≥ 1");
        return EXIT_BAD_INPUT;
    }
    if let BenchKind::Neighbours = a.kind {
        if a.scene_out.is_some() {
            eprintln!("error: --scene-out: the neighbours benchmark has no scene");
            return EXIT_BAD_INPUT;
        }
        return bench_neighbours(a.particles, steps);
    }
    let text = match a.kind {
        BenchKind::Drag => drag_scene(a.particles),
        BenchKind::Dilute => dilute_scene(a.particles, steps),
        BenchKind::Dense => dense_scene(a.particles, steps),
        BenchKind::Mesh | BenchKind::Neighbours | BenchKind::Case => String::new(),
    };
    if let Some(path) = &a.scene_out {
        if text.is_empty() {
            eprintln!("error: --scene-out: the mesh benchmark's scene is built in memory");
            return EXIT_BAD_INPUT;
        }
        if let Err(e) = std::fs::write(path, &text) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return EXIT_BAD_INPUT;
        }
        eprintln!("wrote {}", path.display());
        return 0;
    }
    let scene = match a.kind {
        BenchKind::Mesh => {
            let t = Instant::now();
            let s = mesh_scene(a.particles, a.cells, a.shape);
            if let Ok(s) = &s
                && let Some(m) = &s.mesh_flow
            {
                println!(
                    "mesh: {} {:?} cells, {} faces, {} points, {}, built in {:.2} s",
                    m.flow.mesh().n_cells,
                    a.shape,
                    m.flow.mesh().n_faces(),
                    m.flow.mesh().points.len(),
                    scg_scene::check::tracker_records(&m.flow),
                    t.elapsed().as_secs_f64()
                );
            }
            s
        }
        _ => scg_scene::parse(&text, "<bench>", "bench", &[]).map_err(|e| e.to_string()),
    };
    let mut scene = match scene {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    if a.dispersion != BenchDispersion::None {
        if !matches!(a.kind, BenchKind::Drag | BenchKind::Mesh) {
            eprintln!("error: --dispersion: only the drag and mesh benchmarks take it");
            return EXIT_BAD_INPUT;
        }
        with_dispersion(&mut scene, a.dispersion);
        println!("dispersion: {:?}", a.dispersion);
    }
    let mut sim = scene.build(false);
    for _ in 0..5 {
        if let Err(e) = sim.step() {
            eprintln!("error: {e}");
            return 1;
        }
    }
    let ps0 = sim.particle_steps();
    let t0 = Instant::now();
    if let Err(e) = sim.run(steps, |_| true) {
        eprintln!("error: {e}");
        return 1;
    }
    let wall = t0.elapsed().as_secs_f64();
    let ps = (sim.particle_steps() - ps0) as f64;
    let threads = scg_core::exec::settings().team_size();
    println!(
        "bench {:?}: {} particles × {} steps in {:.3} s on {} threads ({:.3e} s per particle-step; {} kernels)",
        a.kind,
        a.particles,
        steps,
        wall,
        threads,
        wall / ps,
        if scg_core::exec::lanes() {
            "four-lane AVX2"
        } else {
            "portable"
        }
    );
    if std::env::var_os("SCG_BENCH_PLAN").is_some() {
        print!("{}", sim.plan().render());
    }
    for (set, d) in sim.timers().by_set() {
        if d.as_nanos() > 0 {
            println!("  {:<18} {:>9.3} s", set.name(), d.as_secs_f64());
        }
    }
    if let Some(c) = sim
        .world
        .get_resource::<scg_core::stages::contacts::ContactState>()
    {
        println!("  neighbour list: {}", c.summary());
    }
    println!("particle-steps/s: {:.4e}", ps / wall);
    0
}

/// `scg bench case SCENE`: the scene's run (no recording, no end tables), its
/// particle-steps per second and where the time went: building the scene, then each
/// system of the step (`StageTimers::by_system`); the last line is
/// `particle-steps/s: <number>`.
fn bench_case(a: &BenchArgs) -> i32 {
    let Some(path) = &a.scene else {
        eprintln!("error: `scg bench case` needs a scene file (scg bench case SCENE)");
        return EXIT_BAD_INPUT;
    };
    let t = Instant::now();
    let scene = match scg_scene::load(path, &a.set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let mut sim = scene.build(false);
    let build = t.elapsed().as_secs_f64();
    let steps = a.steps.unwrap_or_else(|| scene.steps());
    let t0 = Instant::now();
    if let Err(e) = sim.run(steps, |_| true) {
        eprintln!("error: {e}");
        return 1;
    }
    let wall = t0.elapsed().as_secs_f64();
    let ps = sim.particle_steps() as f64;
    println!(
        "bench case {}: {steps} steps, {ps:.0} particle-steps in {wall:.3} s on {} threads \
         ({:.3e} s per particle-step); scene read and built in {build:.3} s",
        path.display(),
        scg_core::exec::settings().team_size(),
        wall / ps.max(1.0),
    );
    let timers = sim.timers();
    let total = timers.sum().as_secs_f64().max(1e-12);
    for (s, d) in timers.by_system(sim.plan()) {
        println!(
            "  {:<12} {:<24} {:<28} {:>8.3} s {:>5.1} %",
            s.set.name(),
            s.system.name(),
            format!("[{}]", s.effect),
            d.as_secs_f64(),
            100.0 * d.as_secs_f64() / total
        );
    }
    let inner: f64 = timers.rows.iter().map(|d| d.as_secs_f64()).sum();
    println!(
        "  {:<66} {:>8.3} s {:>5.1} %",
        "(the step's own bookkeeping: schedule, timer marks)",
        total - inner,
        100.0 * (total - inner) / total
    );
    println!("particle-steps/s: {:.4e}", ps / wall);
    0
}
