//! Interpolation accuracy against analytic fields: the paper's affine vortex, and the
//! Lamb–Oseen vortex (not affine) on meshes of cell size h, h/2, h/4, both as sampled
//! values and along single-particle trajectories.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scg_mesh::build::{BoxMesh, CellShape};
use scg_mesh::geometry::MeshGeometry;
use scg_mesh::interp::{Interpolation, Interpolator};
use scg_mesh::locate::{Location, Locator};
use scg_mesh::{CellField, PolyMesh};

/// The paper's vortex about the z axis: u = ω(ẑ × r − k r), r the radial vector, ω =
/// 100 rad/s, k = 0.1 (affine in x).
fn paper_vortex(x: DVec3) -> DVec3 {
    let r = DVec3::new(x.x, x.y, 0.0);
    100.0 * (DVec3::Z.cross(r) - 0.1 * r)
}

/// Lamb–Oseen vortex about the z axis: u_θ = Γ/(2πr)(1 − exp(−r²/r_c²)), Γ = 2π m²/s,
/// r_c = 0.4 m.
fn lamb_oseen(x: DVec3) -> DVec3 {
    let r2 = x.x * x.x + x.y * x.y;
    let rc2 = 0.16;
    if r2 < 1e-300 {
        return DVec3::ZERO;
    }
    // Γ/(2π r) · (1 − e^{−r²/rc²}) along θ̂ = (−y, x)/r
    let f = (1.0 - (-r2 / rc2).exp()) / r2;
    DVec3::new(-x.y * f, x.x * f, 0.0)
}

/// Cell values at the cell centres and face values at the boundary face centres.
fn sample(m: &PolyMesh, g: &MeshGeometry, u: fn(DVec3) -> DVec3) -> CellField {
    CellField {
        cells: g.cell_centres.iter().map(|&c| u(c)).collect(),
        patches: m
            .patches
            .iter()
            .map(|p| {
                Some(
                    (p.start..p.start + p.size)
                        .map(|f| u(g.face_centres[f]))
                        .collect(),
                )
            })
            .collect(),
    }
}

fn mesh(shape: CellShape, n: usize, perturb: f64, lo: DVec3, hi: DVec3) -> PolyMesh {
    let ext = hi - lo;
    let m = ext / ext.min_element();
    let nn = [0, 1, 2].map(|a| (n as f64 * m[a]).round() as usize);
    BoxMesh::new(lo, hi, nn)
        .shape(shape)
        .perturbed(perturb, 9)
        .build()
        .unwrap()
}

/// Max and RMS interpolation error over `n` random points in `lo..hi`, relative to the
/// largest speed there.
fn errors(
    loc: &Locator,
    it: &Interpolator,
    u: fn(DVec3) -> DVec3,
    lo: DVec3,
    hi: DVec3,
    n: usize,
) -> (f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (mut max, mut sq, mut umax) = (0.0f64, 0.0, 0.0f64);
    for _ in 0..n {
        let x = lo + (hi - lo) * DVec3::new(rng.random(), rng.random(), rng.random());
        let c = loc.find_cell(x).expect("inside");
        let e = (it.velocity(c, x) - u(x)).length();
        max = max.max(e);
        sq += e * e;
        umax = umax.max(u(x).length());
    }
    (max / umax, (sq / n as f64).sqrt() / umax)
}

const SHAPES: [(&str, CellShape); 3] = [
    ("hex", CellShape::Hex),
    ("tet", CellShape::Tet),
    ("poly", CellShape::Poly { refine: 0.3 }),
];

/// The paper's vortex is affine. Linear-exact cell-point reproduces it to rounding away
/// from the box's boundary (the point weights are exact for affine fields, and so are the
/// face-centre values and the tetrahedra); at boundary points whose exact weights would
/// be negative (every edge and corner of the box: the point lies outside its neighbours'
/// hull) the weights are clipped so that no value overshoots its sources, and there the
/// error is O(h·|∇u|), printed and bounded. OpenFOAM's IDW cell-point reproduces it at interior points
/// of unperturbed hex and tet meshes (the cells about each point are symmetric) but not at
/// box edges (IDW over boundary faces of two patches) nor at hanging nodes or on perturbed
/// meshes, where the error is O(h·|∇u|): it is printed, and its order in h must be ≥ 0.8.
#[test]
fn paper_vortex_affine() {
    let (lo, hi) = (DVec3::new(-0.1, -0.1, 0.0), DVec3::new(0.1, 0.1, 0.1));
    let (ilo, ihi) = (DVec3::new(-0.08, -0.08, 0.02), DVec3::new(0.08, 0.08, 0.08));
    for (name, shape) in SHAPES {
        for perturb in [0.0, 0.2] {
            let m = mesh(shape, 6, perturb, lo, hi);
            let g = MeshGeometry::new(&m).unwrap();
            let loc = Locator::new(&m, &g).unwrap();
            let f = sample(&m, &g, paper_vortex);
            let exact = Interpolator::new(&loc, &f, Interpolation::CellPoint).unwrap();
            let idw = Interpolator::new(&loc, &f, Interpolation::CellPointIdw).unwrap();
            let (e_edges, _) = errors(&loc, &exact, paper_vortex, lo, hi, 2000);
            let (e_exact, _) = errors(&loc, &exact, paper_vortex, ilo, ihi, 2000);
            let (e_box, _) = errors(&loc, &idw, paper_vortex, lo, hi, 2000);
            let (e_inner, _) = errors(&loc, &idw, paper_vortex, ilo, ihi, 2000);
            println!(
                "paper vortex, {name} perturb {perturb}, {} cells: max relative error linear-exact {e_edges:.1e} (box), {e_exact:.1e} (interior); IDW {e_box:.1e} (box), {e_inner:.1e} (interior)",
                m.n_cells
            );
            assert!(e_exact < 1e-11, "{name}: {e_exact}");
            assert!(
                e_edges < 0.1 && e_edges <= e_box * 1.5,
                "{name}: {e_edges} vs IDW {e_box}"
            );
            if perturb == 0.0 && !matches!(shape, CellShape::Poly { .. }) {
                assert!(e_inner < 1e-12, "{name}: {e_inner}");
            }
        }
        let mut prev = f64::NAN;
        for n in [6, 12, 24] {
            let m = mesh(shape, n, 0.2, lo, hi);
            let g = MeshGeometry::new(&m).unwrap();
            let loc = Locator::new(&m, &g).unwrap();
            let f = sample(&m, &g, paper_vortex);
            let it = Interpolator::new(&loc, &f, Interpolation::CellPointIdw).unwrap();
            let (max, rms) = errors(&loc, &it, paper_vortex, ilo, ihi, 2000);
            let order = (prev / rms).log2();
            println!(
                "paper vortex, {name} perturb 0.2, IDW, n = {n}: interior max {max:.2e}, rms {rms:.2e} (order {order:.2})"
            );
            if n > 6 {
                assert!(order > 0.8, "{name}: {order}");
            }
            prev = rms;
        }
    }
}

/// Interpolation errors of the Lamb–Oseen vortex at 4000 random points away from the
/// boundary, on meshes of h = 0.25, 0.125, 0.0625 m (8, 16, 32 cells across the 2 m box;
/// the vortex core radius is 0.4 m). Asserted on the RMS error of each refinement:
/// linear-exact cell-point order ≥ 1.8 on all meshes; OpenFOAM's IDW cell-point ≥ 1.8 on
/// unperturbed hex and tet meshes and ≥ 1.0 on the others (IDW point values are first
/// order where the cells about a point are not symmetric); cell value 0.8–1.3.
#[test]
fn lamb_oseen_convergence() {
    let (lo, hi) = (DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.25));
    let (ilo, ihi) = (DVec3::new(-0.7, -0.7, 0.05), DVec3::new(0.7, 0.7, 0.2));
    for (name, shape, perturb, ns) in [
        ("hex", CellShape::Hex, 0.0, [2, 4, 8]),
        ("tet", CellShape::Tet, 0.0, [2, 4, 8]),
        ("poly", CellShape::Poly { refine: 0.3 }, 0.0, [2, 4, 8]),
        ("hex", CellShape::Hex, 0.2, [2, 4, 8]),
        ("tet", CellShape::Tet, 0.2, [2, 4, 8]),
        ("poly", CellShape::Poly { refine: 0.3 }, 0.2, [2, 4, 8]),
    ] {
        for scheme in [
            Interpolation::CellPoint,
            Interpolation::CellPointIdw,
            Interpolation::CellValue,
            Interpolation::Conservative,
        ] {
            let mut prev = (f64::NAN, f64::NAN);
            for n in ns {
                let m = mesh(shape, n, perturb, lo, hi);
                let g = MeshGeometry::new(&m).unwrap();
                let loc = Locator::new(&m, &g).unwrap();
                let f = sample(&m, &g, lamb_oseen);
                // every side free: the vortex crosses them
                let free = vec![true; m.patches.len()];
                let it = Interpolator::with_outflow(&loc, &f, scheme, &free).unwrap();
                let (max, rms) = errors(&loc, &it, lamb_oseen, ilo, ihi, 4000);
                let order = ((prev.0 / max).log2(), (prev.1 / rms).log2());
                println!(
                    "lamb-oseen {name} perturb {perturb} {scheme:?} n = {n} ({} cells): max {max:.3e} rms {rms:.3e} order max {:.2} rms {:.2}",
                    m.n_cells, order.0, order.1
                );
                if n != ns[0] {
                    let min = match scheme {
                        Interpolation::CellPoint | Interpolation::CellPointLinearExact => 1.8,
                        Interpolation::CellPointIdw
                            if perturb == 0.0 && !matches!(shape, CellShape::Poly { .. }) =>
                        {
                            1.8
                        }
                        Interpolation::CellPointIdw => 1.0,
                        Interpolation::CellValue | Interpolation::Conservative => 0.8,
                    };
                    assert!(
                        order.1 >= min,
                        "{name} {perturb} {scheme:?}: order {}",
                        order.1
                    );
                    if matches!(
                        scheme,
                        Interpolation::CellValue | Interpolation::Conservative
                    ) {
                        assert!(
                            order.1 <= 1.3,
                            "{name} {perturb} {scheme:?}: order {}",
                            order.1
                        );
                    }
                }
                prev = (max, rms);
            }
        }
    }
}

/// Integrate dv/dt = (u(x) − v)/τ, dx/dt = v (τ = 0.05 s) for 1.5 s with dt = 1 ms by the
/// exponential scheme v ← u + (v − u)e^{−dt/τ}, x ← x + v·dt, in the given field; returns
/// the positions at every step. `field` gives u at x, tracking the particle as needed.
fn trajectory(x0: DVec3, mut field: impl FnMut(DVec3) -> DVec3) -> Vec<DVec3> {
    let (tau, dt, steps): (f64, f64, usize) = (0.05, 1e-3, 1500);
    let decay = (-dt / tau).exp();
    let mut x = x0;
    let mut v = field(x);
    let mut out = Vec::with_capacity(steps);
    for _ in 0..steps {
        let u = field(x);
        v = u + (v - u) * decay;
        x += v * dt;
        out.push(x);
    }
    out
}

/// Single-particle trajectories in the Lamb–Oseen vortex from 4 starts (r = 0.2–0.6 m,
/// about 0.3–1 turn): the largest distance between the trajectory in the interpolated
/// field and in the analytic field, over 4 particles and the whole time, on meshes of
/// h = 0.25, 0.125, 0.0625 m. Asserted: order ≥ 1.8 for linear-exact cell-point on
/// perturbed tet and polyhedral meshes and for IDW cell-point on the unperturbed hex mesh;
/// the cell-value orders are printed.
#[test]
fn lamb_oseen_trajectories() {
    let (lo, hi) = (DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.25));
    let starts = [
        DVec3::new(0.2, 0.0, 0.125),
        DVec3::new(0.0, 0.35, 0.1),
        DVec3::new(-0.5, 0.1, 0.15),
        DVec3::new(0.3, -0.5, 0.125),
    ];
    let exact: Vec<Vec<DVec3>> = starts
        .iter()
        .map(|&x0| trajectory(x0, lamb_oseen))
        .collect();
    for (name, shape, perturb, scheme, min_order) in [
        (
            "hex",
            CellShape::Hex,
            0.0,
            Interpolation::CellPointIdw,
            Some(1.8),
        ),
        ("hex", CellShape::Hex, 0.0, Interpolation::CellValue, None),
        (
            "tet",
            CellShape::Tet,
            0.2,
            Interpolation::CellPoint,
            Some(1.8),
        ),
        (
            "tet",
            CellShape::Tet,
            0.2,
            Interpolation::CellPointIdw,
            None,
        ),
        (
            "poly",
            CellShape::Poly { refine: 0.3 },
            0.2,
            Interpolation::CellPoint,
            Some(1.8),
        ),
        (
            "poly",
            CellShape::Poly { refine: 0.3 },
            0.2,
            Interpolation::CellValue,
            None,
        ),
    ] {
        let mut prev = f64::NAN;
        for n in [2, 4, 8] {
            let m = mesh(shape, n, perturb, lo, hi);
            let g = MeshGeometry::new(&m).unwrap();
            let loc = Locator::new(&m, &g).unwrap();
            let f = sample(&m, &g, lamb_oseen);
            let it = Interpolator::new(&loc, &f, scheme).unwrap();
            let mut err = 0.0f64;
            for (x0, want) in starts.iter().zip(&exact) {
                let mut hit = loc.find(*x0).unwrap();
                let got = trajectory(*x0, |x| {
                    match loc.track_from(&hit, x) {
                        Location::Inside(h) => hit = h,
                        other => panic!("{other:?} at {x}"),
                    }
                    it.at(&hit)
                });
                for (a, b) in got.iter().zip(want) {
                    err = err.max((*a - *b).length());
                }
            }
            let order = (prev / err).log2();
            println!(
                "trajectory {name} perturb {perturb} {scheme:?} n = {n} ({} cells): max deviation {err:.3e} m, order {order:.2}",
                m.n_cells
            );
            if let Some(min) = min_order
                && n > 2
            {
                assert!(order >= min, "{name} {scheme:?}: order {order}");
            }
            prev = err;
        }
    }
}

/// Cell-point is continuous across faces: at random points on the triangles of internal
/// faces of a perturbed polyhedral mesh, the value interpolated in the owner and in the
/// neighbour agree to rounding (they share the face's nodes and their values), while cell
/// values jump by O(h·|∇u|).
#[test]
fn cell_point_is_continuous_across_faces() {
    let (lo, hi) = (DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.5));
    let m = mesh(CellShape::Poly { refine: 0.3 }, 3, 0.2, lo, hi);
    let g = MeshGeometry::new(&m).unwrap();
    let loc = Locator::new(&m, &g).unwrap();
    let f = sample(&m, &g, lamb_oseen);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for scheme in [
        Interpolation::CellPointIdw,
        Interpolation::CellPoint,
        Interpolation::CellValue,
    ] {
        let it = Interpolator::new(&loc, &f, scheme).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..2000 {
            let face = rng.random_range(0..m.n_internal_faces());
            let pts = m.face(face);
            let i = rng.random_range(0..pts.len());
            let a = m.points[pts[i] as usize];
            let b = m.points[pts[(i + 1) % pts.len()] as usize];
            let c = if pts.len() == 3 {
                m.points[pts[(i + 2) % 3] as usize]
            } else {
                g.face_centres[face]
            };
            let (s, t) = (rng.random::<f64>(), rng.random::<f64>());
            let (s, t) = if s + t > 1.0 {
                (1.0 - s, 1.0 - t)
            } else {
                (s, t)
            };
            let x = c + s * (a - c) + t * (b - c);
            let uo = it.velocity(m.owner[face], x);
            let un = it.velocity(m.neighbour[face], x);
            worst = worst.max((uo - un).length());
        }
        println!("{scheme:?}: largest jump across a face {worst:.2e} m/s");
        if scheme == Interpolation::CellValue {
            assert!(worst > 1e-2, "cell values do jump");
        } else {
            assert!(worst < 1e-12, "{scheme:?}: {worst}");
        }
    }
}

/// Where a no-slip wall patch meets an inlet, the boundary values jump. Here the air
/// enters at u_z = 1 through the inlet (z = 0, type `patch`), the walls (type `wall`) hold
/// 0, and the cells carry u_z = 1.2 (the stream accelerates past the inlet). A linear fit
/// over an inlet-edge point's neighbours (one or two cells, inlet and wall faces) gives
/// u_in + u_wall − u_cell = −0.2 there: back-flow out of the inlet along its edges, which
/// blew inlet-fed particles straight back out. The default cell-point must keep every
/// junction point within its neighbours' range, so u_z ≥ 0 everywhere just inside the
/// inlet; points away from the junctions stay linear-exact (`paper_vortex_affine`).
#[test]
fn no_back_flow_where_walls_meet_the_inlet() {
    use scg_mesh::build::PatchNaming;
    let (lo, hi) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.1, 0.1, 0.2));
    for (name, shape, perturb) in [
        ("hex", CellShape::Hex, 0.0),
        ("tet", CellShape::Tet, 0.2),
        ("poly", CellShape::Poly { refine: 0.3 }, 0.2),
    ] {
        let m = BoxMesh::new(lo, hi, [5, 5, 10])
            .shape(shape)
            .naming(PatchNaming::InletOutletWalls { axis: 2 })
            .perturbed(perturb, 4)
            .build()
            .unwrap();
        let g = MeshGeometry::new(&m).unwrap();
        let loc = Locator::new(&m, &g).unwrap();
        let f = CellField {
            cells: vec![DVec3::new(0.0, 0.0, 1.2); m.n_cells],
            patches: m
                .patches
                .iter()
                .map(|p| {
                    let u = match p.name.as_str() {
                        "inlet" => DVec3::Z,
                        "walls" => DVec3::ZERO,
                        _ => DVec3::new(0.0, 0.0, 1.2),
                    };
                    Some(vec![u; p.size])
                })
                .collect(),
        };
        let it = Interpolator::new(&loc, &f, Interpolation::CellPoint).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut min = f64::INFINITY;
        for _ in 0..20_000 {
            let x = DVec3::new(
                0.1 * rng.random::<f64>(),
                0.1 * rng.random::<f64>(),
                1e-3 * rng.random::<f64>(),
            );
            let c = loc.find_cell(x).expect("inside");
            min = min.min(it.velocity(c, x).z);
        }
        println!("{name}: least u_z just inside the inlet {min:.3e}");
        assert!(min >= -1e-12, "{name}: back-flow {min} at the inlet");
    }
}
