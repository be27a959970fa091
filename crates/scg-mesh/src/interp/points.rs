//! Point and face-centre values of a cell field (the nodes of the cell-point schemes).

use glam::DVec3;

use super::check_field;
use crate::geometry::{MeshGeometry, face_centre_weights};
use crate::{CellField, MeshError, PolyMesh};

/// Point values of a cell field by inverse-distance weighting, as OpenFOAM's
/// `volPointInterpolation`: an interior point takes Σ u_c/|x_p − x_c| / Σ 1/|x_p − x_c|
/// over the cells using it; a point on the boundary the same over the boundary faces using
/// it, with the patch's face value where the field gives one and the owner cell's value
/// otherwise (zero gradient). An error if `field` fails [`check_field`].
pub fn point_values(
    mesh: &PolyMesh,
    geom: &MeshGeometry,
    field: &CellField,
) -> Result<Vec<DVec3>, MeshError> {
    check_field(mesh, field)?;
    let np = mesh.points.len();
    let mut sum = vec![DVec3::ZERO; np];
    let mut wsum = vec![0.0; np];
    // boundary points first
    let ni = mesh.n_internal_faces();
    for (pi, patch) in mesh.patches.iter().enumerate() {
        let vals = field.patches.get(pi).and_then(|v| v.as_ref());
        for (i, f) in (patch.start..patch.start + patch.size).enumerate() {
            if f < ni || f >= mesh.n_faces() {
                continue;
            }
            let u = match vals {
                Some(v) => v[i],
                None => field.cells[mesh.owner[f] as usize],
            };
            let fc = geom.face_centres[f];
            for &p in mesh.face(f) {
                let w = 1.0 / (mesh.points[p as usize] - fc).length().max(1e-300);
                sum[p as usize] += w * u;
                wsum[p as usize] += w;
            }
        }
    }
    for p in 0..np {
        if wsum[p] > 0.0 {
            sum[p] /= wsum[p];
            continue;
        }
        let x = mesh.points[p];
        let (mut s, mut ws) = (DVec3::ZERO, 0.0);
        for &c in geom.cells_of_point(p) {
            let w = 1.0 / (x - geom.cell_centres[c as usize]).length().max(1e-300);
            s += w * field.cells[c as usize];
            ws += w;
        }
        sum[p] = if ws > 0.0 { s / ws } else { DVec3::ZERO };
    }
    Ok(sum)
}

/// Point values by inverse-distance weights corrected to be exact for affine fields, the
/// pseudo-Laplacian of Holmes & Connell (1989) applied to inverse-distance base weights:
/// over the neighbours i of a point p (the cells using it, and the boundary faces using
/// it with the values [`point_values`] gives them), w_i = (1 + λ·R_i)/|R_i| with
/// R_i = x_i − x_p, λ chosen so that Σ w_i R_i = 0. Where the 3×3 system is singular the
/// point keeps its [`point_values`] value; where any weight would be negative they are
/// clipped as Holmes & Connell's and OpenFOAM's `pointLinear`-style corrections are:
/// w_i = clamp(1 + λ·R_i, 0, 2)/|R_i|, a positive, bounded average (no longer exact for
/// affine fields there). So every point value is a convex combination of the cell and
/// boundary-face values around it, and interpolation never overshoots them.
///
/// Negative weights arise exactly where the point lies outside the hull of its neighbours'
/// centres: on an edge or corner of the boundary (two walls meeting: the fit extrapolates
/// from the cells through the zero face values, and the edge took a velocity *opposite* to
/// its cells', which ran particles upstream along the edges of a duct), and at distorted
/// cells. On a flat wall every neighbouring cell centre lies on one side, so the affine fit
/// gives the cells zero total weight and the point takes the wall faces' values, exactly.
///
/// Where a wall patch (type `wall`) meets another patch (an inlet or outlet) the boundary
/// values jump (no-slip against through-flow), and a linear fit over a corner's few
/// neighbours extrapolates across the jump: at the cyclone's inlet corners it gave
/// +10 m/s between a −10 m/s inflow and the 0 of the walls, and blew particles back out.
/// So at such junction points the value must lie within its neighbours' range (each
/// component); one that does not takes the clipped weights, which always do. Nothing
/// on a single stencil tells a jump from a steep gradient, so the rule uses the patch
/// types: points where patches of one kind meet (a box of `patch` sides) stay
/// linear-exact. An error if `field` fails [`check_field`].
pub fn point_values_linear_exact(
    mesh: &PolyMesh,
    geom: &MeshGeometry,
    field: &CellField,
) -> Result<Vec<DVec3>, MeshError> {
    let mut out = point_values(mesh, geom, field)?;
    let np = mesh.points.len();
    // boundary faces of every point (CSR)
    let ni = mesh.n_internal_faces();
    let mut offs = vec![0u32; np + 1];
    for f in ni..mesh.n_faces() {
        for &p in mesh.face(f) {
            offs[p as usize + 1] += 1;
        }
    }
    for p in 0..np {
        offs[p + 1] += offs[p];
    }
    let mut fill = offs.clone();
    let mut pfaces = vec![0u32; offs[np] as usize];
    for f in ni..mesh.n_faces() {
        for &p in mesh.face(f) {
            pfaces[fill[p as usize] as usize] = f as u32;
            fill[p as usize] += 1;
        }
    }
    let mut face_value = vec![DVec3::ZERO; mesh.n_faces() - ni];
    let mut face_on_wall = vec![false; mesh.n_faces() - ni];
    for (pi, patch) in mesh.patches.iter().enumerate() {
        let vals = field.patches.get(pi).and_then(|v| v.as_ref());
        for (i, f) in (patch.start..patch.start + patch.size).enumerate() {
            if f >= ni && f < mesh.n_faces() {
                face_value[f - ni] = match vals {
                    Some(v) => v[i],
                    None => field.cells[mesh.owner[f] as usize],
                };
                face_on_wall[f - ni] = patch.kind == "wall";
            }
        }
    }
    let mut nb: Vec<(DVec3, DVec3)> = Vec::new();
    let mut dropped: Vec<usize> = Vec::new();
    for (p, value) in out.iter_mut().enumerate() {
        let x = mesh.points[p];
        nb.clear();
        for &c in geom.cells_of_point(p) {
            nb.push((geom.cell_centres[c as usize] - x, field.cells[c as usize]));
        }
        for &f in &pfaces[offs[p] as usize..offs[p + 1] as usize] {
            nb.push((
                geom.face_centres[f as usize] - x,
                face_value[f as usize - ni],
            ));
        }
        let Some(lambda) = affine_fit(&nb, &[]) else {
            continue;
        };
        let faces = &pfaces[offs[p] as usize..offs[p + 1] as usize];
        let junction = faces.iter().any(|&f| face_on_wall[f as usize - ni])
            && faces.iter().any(|&f| !face_on_wall[f as usize - ni]);
        // Holmes & Connell's weights; where one is negative, the neighbour with the most
        // negative weight is dropped and the fit repeated on the others (an active set),
        // which finds convex weights exact for affine fields wherever the point lies inside
        // its remaining neighbours' hull (an interior point of a distorted mesh).
        dropped.clear();
        let mut accepted = false;
        let mut fit = Some(lambda);
        while let Some(l) = fit {
            let (mut s, mut ws, mut neg) = (DVec3::ZERO, 0.0, 0.0);
            let mut worst = (0.0, usize::MAX);
            for (i, &(d, u)) in nb.iter().enumerate() {
                if dropped.contains(&i) {
                    continue;
                }
                let c = 1.0 + l.dot(d);
                let w = c / d.length().max(1e-300);
                s += w * u;
                ws += w;
                if w < 0.0 {
                    neg -= w;
                    if c < worst.0 {
                        worst = (c, i);
                    }
                }
            }
            // weights that are zero but for rounding (a flat wall's cells) keep the fit
            if neg <= CONVEX_TOLERANCE * ws {
                if ws > 0.0 && s.is_finite() {
                    let v = s / ws;
                    if !junction || within_range(v, &nb) {
                        *value = v;
                        accepted = true;
                    }
                }
                break;
            }
            dropped.push(worst.1);
            fit = if nb.len() - dropped.len() >= 4 {
                affine_fit(&nb, &dropped)
            } else {
                None
            };
        }
        if accepted {
            continue;
        }
        // a negative weight (the point outside its neighbours' hull: an edge or corner of
        // the boundary, a distorted cell) or ill-conditioned: clipped weights
        let (mut s, mut ws) = (DVec3::ZERO, 0.0);
        for &(d, u) in &nb {
            let w = (1.0 + lambda.dot(d)).clamp(0.0, 2.0) / d.length().max(1e-300);
            s += w * u;
            ws += w;
        }
        if ws > 0.0 && s.is_finite() {
            *value = s / ws;
        }
    }
    Ok(out)
}

/// λ of the pseudo-Laplacian over the neighbours `nb` (offset from the point, value) but
/// those listed in `dropped`: Σ w_i R_i = 0 with w_i = (1 + λ·R_i)/|R_i|; `None` where the
/// system is singular.
fn affine_fit(nb: &[(DVec3, DVec3)], dropped: &[usize]) -> Option<DVec3> {
    let (mut r, mut m) = (DVec3::ZERO, glam::DMat3::ZERO);
    for (i, &(d, _)) in nb.iter().enumerate() {
        if dropped.contains(&i) {
            continue;
        }
        let w = 1.0 / d.length().max(1e-300);
        r += w * d;
        m += glam::DMat3::from_cols(w * d.x * d, w * d.y * d, w * d.z * d);
    }
    let scale = (m.x_axis.x + m.y_axis.y + m.z_axis.z) / 3.0;
    let det = m.determinant();
    if det.is_nan() || det.abs() <= 1e-9 * scale * scale * scale {
        return None;
    }
    Some(-(m.inverse() * r))
}

/// How large the negative linear-exact weights may be together, as a fraction of the sum
/// of all weights, for rounding, and the fit still count as convex: an overshoot of at
/// most this fraction of the values' spread.
pub const CONVEX_TOLERANCE: f64 = 1e-9;

/// Whether every component of `v` lies within the range of the neighbours' values.
fn within_range(v: DVec3, nb: &[(DVec3, DVec3)]) -> bool {
    let (lo, hi) = nb.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &(_, u)| (lo.min(u), hi.max(u)),
    );
    v.cmpge(lo).all() && v.cmple(hi).all()
}

/// Values at the face centres from point values, exact for fields affine in space.
pub fn face_centre_values(mesh: &PolyMesh, point_values: &[DVec3]) -> Vec<DVec3> {
    let mut w = Vec::new();
    (0..mesh.n_faces())
        .map(|f| {
            let face = mesh.face(f);
            face_centre_weights(&mesh.points, face, &mut w);
            face.iter()
                .zip(&w)
                .map(|(&p, &w)| w * point_values[p as usize])
                .sum()
        })
        .collect()
}
