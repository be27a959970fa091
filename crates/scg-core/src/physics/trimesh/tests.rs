use super::*;

/// A flat n×n grid of squares (2n² triangles) over [−l, l]² in the plane z = 0.
fn flat(n: usize, l: f64) -> TriMesh {
    let mut soup = Vec::new();
    let p = |i: usize, j: usize| {
        DVec3::new(
            -l + 2.0 * l * i as f64 / n as f64,
            -l + 2.0 * l * j as f64 / n as f64,
            0.0,
        )
    };
    for i in 0..n {
        for j in 0..n {
            soup.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            soup.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    let (v, t) = weld(&soup);
    TriMesh::new(v, t).unwrap()
}

/// The unit cube [0, 1]³ as 12 outward triangles.
fn cube() -> TriMesh {
    let v: Vec<DVec3> = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    let quads = [
        [0, 2, 3, 1], // z = 0
        [4, 5, 7, 6], // z = 1
        [0, 1, 5, 4], // y = 0
        [2, 6, 7, 3], // y = 1
        [0, 4, 6, 2], // x = 0
        [1, 3, 7, 5], // x = 1
    ];
    let t = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    TriMesh::new(v, t).unwrap()
}

fn contacts(m: &TriMesh, x: DVec3, r: f64) -> Vec<MeshContact> {
    let mut out = Vec::new();
    m.contacts(x, r, &mut MeshScratch::default(), &mut out);
    out
}

#[test]
fn closest_point_regions() {
    let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
    let cp = |p| closest_point_on_triangle(p, a, b, c);
    let (q, f) = cp(DVec3::new(0.2, 0.2, 1.0));
    assert!((q - DVec3::new(0.2, 0.2, 0.0)).length() < 1e-15 && f == Feature::Face);
    assert_eq!(cp(DVec3::new(-1.0, -1.0, 0.5)), (a, Feature::Vertex(0)));
    assert_eq!(cp(DVec3::new(2.0, -0.5, 0.0)), (b, Feature::Vertex(1)));
    assert_eq!(cp(DVec3::new(-0.1, 3.0, 0.0)), (c, Feature::Vertex(2)));
    assert_eq!(
        cp(DVec3::new(0.5, -1.0, 0.3)),
        (DVec3::new(0.5, 0.0, 0.0), Feature::Edge(0))
    );
    assert_eq!(
        cp(DVec3::new(1.0, 1.0, 0.0)),
        (DVec3::new(0.5, 0.5, 0.0), Feature::Edge(1))
    );
    assert_eq!(
        cp(DVec3::new(-2.0, 0.25, 0.0)),
        (DVec3::new(0.0, 0.25, 0.0), Feature::Edge(2))
    );
}

proptest::proptest! {
    /// The closest point is no farther than any of 400 sampled points of the triangle,
    /// lies on the triangle, and on the feature it names.
    #[test]
    fn closest_point_beats_samples(
        c in proptest::array::uniform12(-1.0..1.0_f64),
    ) {
        let (a, b, cc, p) = (
            DVec3::new(c[0], c[1], c[2]), DVec3::new(c[3], c[4], c[5]),
            DVec3::new(c[6], c[7], c[8]), DVec3::new(c[9], c[10], c[11]) * 2.0,
        );
        proptest::prop_assume!((b - a).cross(cc - a).length() > 1e-3);
        let (q, f) = closest_point_on_triangle(p, a, b, cc);
        let dq = (q - p).length();
        for i in 0..=20 {
            for j in 0..=(20 - i) {
                let s = a + (b - a) * (i as f64 / 20.0) + (cc - a) * (j as f64 / 20.0);
                proptest::prop_assert!(dq <= (s - p).length() + 1e-12);
            }
        }
        let corner = [a, b, cc];
        match f {
            Feature::Vertex(k) => proptest::prop_assert_eq!(q, corner[k as usize]),
            Feature::Edge(k) => {
                let (u, w) = (corner[k as usize], corner[(k as usize + 1) % 3]);
                let off = (q - u).cross(w - u).length() / (w - u).length();
                proptest::prop_assert!(off < 1e-12, "off the edge by {off}");
            }
            Feature::Face => {
                let n = (b - a).cross(cc - a).normalize();
                proptest::prop_assert!((q - a).dot(n).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn weld_recovers_topology_and_regions() {
    let m = flat(3, 1.0);
    assert_eq!(
        (m.triangle_count(), m.vertex_count(), m.edge_count()),
        (18, 16, 33)
    );
    assert_eq!(m.region_count(), 1);
    assert!(!m.is_closed());
    // Only the 12 boundary edges are feature edges.
    assert_eq!(m.feature_edges().len(), 12);
    let c = cube();
    assert!(c.is_closed());
    assert_eq!(c.region_count(), 6);
    assert_eq!(c.feature_edges().len(), 12);
    assert_eq!(c.edge_count(), 18);
}

#[test]
fn bad_meshes_are_refused_naming_the_triangle() {
    let e = TriMesh::new(vec![], vec![]).unwrap_err();
    assert!(e.message.contains("no triangles"));
    let v = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::NAN,
    ];
    let e = TriMesh::new(v.clone(), vec![[0, 1, 2], [0, 1, 3]]).unwrap_err();
    assert_eq!(e.triangle, Some(1));
    assert!(e.to_string().starts_with("triangle 1: degenerate"), "{e}");
    let e = TriMesh::new(v.clone(), vec![[0, 1, 4]]).unwrap_err();
    assert_eq!(e.triangle, Some(0));
    assert!(e.message.contains("non-finite"), "{e}");
    let e = TriMesh::new(v.clone(), vec![[0, 1, 1]]).unwrap_err();
    assert!(e.message.contains("degenerate"), "{e}");
    let e = TriMesh::new(v, vec![[0, 1, 9]]).unwrap_err();
    assert!(e.message.contains("out of range"), "{e}");
}

/// A sphere anywhere over a flat region of 2·8² triangles, also exactly above vertices
/// and shared edges, has one contact with the plane's overlap and normal.
#[test]
fn one_contact_on_a_flat_region() {
    let m = flat(8, 1.0);
    let r = 0.3; // larger than a triangle: it reaches many of them
    let h = 0.2;
    let mut xs = vec![
        DVec3::new(0.0, 0.0, h),
        DVec3::new(0.25, 0.0, h),
        DVec3::new(0.25, 0.25, h),
    ];
    for k in 0..200 {
        let t = k as f64 * 0.618_034;
        xs.push(DVec3::new(
            (t * 7.3).sin() * 0.7,
            (t * 3.1).cos() * 0.7,
            if k % 2 == 0 { h } else { -h },
        ));
    }
    for x in xs {
        let c = contacts(&m, x, r);
        assert_eq!(c.len(), 1, "at {x}: {c:?}");
        assert!((c[0].overlap - (r - h)).abs() < 1e-12 * r, "{c:?}");
        assert!(
            (c[0].normal - DVec3::Z * x.z.signum()).length() < 1e-12,
            "{c:?}"
        );
        assert_eq!(c[0].region, 0);
    }
}

/// Inside a cube's corner a sphere touching three faces feels three contacts; outside,
/// over a convex edge it feels one contact along the bisector, over a corner one contact.
#[test]
fn corners_and_convex_edges() {
    let m = cube();
    let r = 0.2;
    let c = contacts(&m, DVec3::new(0.1, 0.15, 0.12), r);
    assert_eq!(c.len(), 3, "{c:?}");
    let mut ov: Vec<f64> = c.iter().map(|c| c.overlap).collect();
    ov.sort_by(f64::total_cmp);
    for (got, want) in ov.iter().zip([0.05, 0.08, 0.1]) {
        assert!((got - want).abs() < 1e-12, "{ov:?}");
    }
    // Over the convex edge x = 1, z = 1 (outside), at distance 0.1·√2 from it.
    let x = DVec3::new(1.1, 0.5, 1.1);
    let c = contacts(&m, x, r);
    assert_eq!(c.len(), 1, "{c:?}");
    assert!((c[0].overlap - (r - 0.1 * 2f64.sqrt())).abs() < 1e-12);
    assert!((c[0].normal - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-12);
    // Over the corner (1, 1, 1).
    let c = contacts(&m, DVec3::splat(1.05), r);
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!(c[0].point, DVec3::ONE);
    // Outside, near a face and far from edges: one face contact.
    let c = contacts(&m, DVec3::new(0.5, 0.4, 1.15), r);
    assert_eq!(c.len(), 1);
    assert_eq!(c[0].feature, Feature::Face);
    assert!((c[0].overlap - 0.05).abs() < 1e-12);
}

proptest::proptest! {
    /// The grid's clearance test never calls a touching sphere clear, and each contact's
    /// overlap is the radius minus the true distance to the mesh (brute force).
    #[test]
    fn surely_clear_never_misses_and_contacts_are_true(
        x in -0.5..1.5_f64, y in -0.5..1.5_f64, z in -0.5..1.5_f64, r in 1e-3..0.4_f64,
    ) {
        let m = cube();
        let p = DVec3::new(x, y, z);
        let c = contacts(&m, p, r);
        if m.surely_clear(p, r) {
            proptest::prop_assert!(c.is_empty());
        }
        let dmin = (0..m.triangle_count() as u32).map(|t| (m.closest(p, t) - p).length_squared()).fold(f64::INFINITY, f64::min).sqrt();
        if dmin < r * (1.0 - 1e-9) {
            proptest::prop_assert!(!c.is_empty());
            let deepest = c.iter().map(|c| c.overlap).fold(0.0, f64::max);
            proptest::prop_assert!((deepest - (r - dmin)).abs() < 1e-12);
        } else {
            proptest::prop_assert!(c.iter().all(|c| c.overlap < 1e-9 * r));
        }
    }
}

#[test]
fn the_grid_is_fine_enough_to_clear_most_of_the_inside() {
    // A closed box of 2·20² triangles per face: points in the middle are clear.
    let m = cube();
    let (h, dims) = m.grid_shape();
    assert!(dims.iter().all(|&d| d >= 8), "{dims:?}");
    assert!(m.surely_clear(DVec3::splat(0.5), 0.5 - 2.0 * h));
    assert!(!m.surely_clear(DVec3::splat(0.5), 0.5 + 1e-9));
}

/// The outline draws every feature edge exactly once, chained: a cube's 12 edges.
#[test]
fn outline_draws_each_feature_edge_once() {
    for m in [cube(), flat(3, 1.0)] {
        let strips = m.outline();
        let mut segs: Vec<[[u64; 3]; 2]> = strips
            .iter()
            .flat_map(|s| {
                s.windows(2).map(|w| {
                    let k = |p: [f64; 3]| p.map(f64::to_bits);
                    let (a, b) = (k(w[0]), k(w[1]));
                    if a < b { [a, b] } else { [b, a] }
                })
            })
            .collect();
        let n = segs.len();
        segs.sort();
        segs.dedup();
        assert_eq!(
            (n, segs.len()),
            (m.feature_edges().len(), m.feature_edges().len())
        );
        assert!(
            strips.len() < n,
            "chained: {} strips for {n} edges",
            strips.len()
        );
    }
}

/// Extreme but finite coordinates give a mesh or an error, never a panic.
#[test]
fn extreme_coordinates_do_not_panic() {
    for s in [1e-300, 1e-12, 1e12, 1e300, f64::MAX / 4.0] {
        let v = vec![
            DVec3::ZERO,
            DVec3::X * s,
            DVec3::Y * s,
            DVec3::new(-s, -s, s),
        ];
        let t = vec![[0, 1, 2], [0, 2, 3], [0, 3, 1]];
        if let Ok(m) = TriMesh::new(v, t) {
            let _ = contacts(&m, DVec3::splat(0.1 * s), 0.5 * s);
            let _ = m.surely_clear(DVec3::splat(-0.1 * s), 0.01 * s);
            let _ = m.outline();
        }
    }
}
