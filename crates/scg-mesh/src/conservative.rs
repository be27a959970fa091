//! A volume-conserving velocity from a cell field: face fluxes made divergence-free, then
//! one constant velocity per tetrahedron of the [`crate::locate`] decomposition that
//! carries exactly those fluxes.
//!
//! A CFD solver's cell velocities conserve volume only through its face fluxes (Rhie–Chow);
//! any interpolation of the cell values alone ([`crate::Interpolation::CellPoint`],
//! OpenFOAM's `cellPoint`) converges in some places and diverges in others, and fluid
//! tracers carried by it collect where it converges: their mean residence is no longer
//! V/Q. [`crate::Interpolation::Conservative`] removes that error in three steps:
//!
//! 1. **Face fluxes** ([`face_fluxes`]): φ_f = u_f·A_f with u_f linear between the two
//!    cells' values on an internal face (as OpenFOAM's `linear` interpolation of U), the
//!    field's boundary value on a boundary face, zero on constraint patches (`empty`,
//!    `symmetry`, `symmetryPlane`, `wedge`).
//! 2. **Projection**: the smallest correction that balances every cell, φ_f − a_f·(p_N −
//!    p_P) with a_f = |A_f|²/(A_f·d_PN) (OpenFOAM's `snGrad` coefficient), p from the
//!    Laplace equation Σ_f a_f (p_P − p_Q) = −Σ_f φ_f solved by conjugate gradients. The
//!    fluxes through the *outflow* patches are free (p = 0 there, as at a pressure
//!    outlet); every other boundary face keeps its flux (inlets their inflow, walls zero).
//!    Without outflow patches the domain must be closed and one cell's p is pinned.
//! 3. **Inside each cell** ([`tet_velocities`]): every face flux is shared among the face's
//!    triangles (by the cell-point field's flux through each, corrected in proportion to
//!    area), then the fluxes through the cell's inner triangles (cell centre and an edge
//!    of the surface triangulation) are the cell-point field's, corrected by the smallest
//!    area-weighted amount that balances every tetrahedron (a Laplacian on the
//!    tetrahedra, solved densely per cell). A tetrahedron's velocity is then the constant
//!    vector whose flux through each of its four faces is the face's: the lowest-order
//!    Raviart–Thomas field with zero divergence. Its normal component is continuous
//!    across every face of the decomposition, so no volume is created or lost anywhere,
//!    at the price of tangential jumps between tetrahedra (first order, as `cell`).
//!
//! The result is piecewise constant: its gradient is not used (the forces that need
//! ∇u take the cell's Gauss gradient of the cell-point field).

use glam::{DMat3, DVec3};

use crate::geometry::MeshGeometry;
use crate::{CellField, MeshError, PolyMesh};

/// What the projection of step 2 changed (printed by `scg check`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Projection {
    /// Σ over cells of |Σ_f φ_f| before the projection, m³/s.
    pub imbalance_before: f64,
    /// The same after it (rounding), m³/s.
    pub imbalance_after: f64,
    /// Flow in through the boundary faces whose flux is kept, m³/s.
    pub inflow: f64,
    /// Flow out through the outflow patches before the projection, m³/s.
    pub outflow_before: f64,
    /// Flow out through them after it, m³/s.
    pub outflow_after: f64,
    /// Largest change of a face's normal velocity |Δφ_f|/|A_f|, m/s.
    pub max_change: f64,
    /// Area-weighted mean of that change over the faces, m/s.
    pub mean_change: f64,
    /// Conjugate-gradient iterations.
    pub iterations: usize,
    /// Cells whose tetrahedra could not be balanced (degenerate): they take their cell
    /// value in every tetrahedron.
    pub unbalanced_cells: usize,
}

/// The face fluxes of `field` (step 1) made divergence-free (step 2), m³/s, out of each
/// face's owner; `outflow[p]` marks the patches whose fluxes are free.
pub fn face_fluxes(
    mesh: &PolyMesh,
    geom: &MeshGeometry,
    field: &CellField,
    outflow: &[bool],
) -> Result<(Vec<f64>, Projection), MeshError> {
    crate::interp::check_field(mesh, field)?;
    if outflow.len() != mesh.patches.len() {
        return Err(MeshError::invalid(
            "<mesh>",
            "patches",
            format!(
                "{} outflow flags for {} patches",
                outflow.len(),
                mesh.patches.len()
            ),
        ));
    }
    let ni = mesh.n_internal_faces();
    let nf = mesh.n_faces();
    // the patch of every boundary face, and whether its flux is free
    let mut free = vec![false; nf];
    let mut phi = vec![0.0; nf];
    let mut inflow = 0.0;
    let mut outflow_before = 0.0;
    for (pi, p) in mesh.patches.iter().enumerate() {
        let vals = field.patches[pi].as_ref();
        // constraint patches carry nothing through (a 2-D case's front and back, mirrors)
        let closed = p.is_constraint();
        for (i, f) in (p.start..p.start + p.size).enumerate() {
            let u = vals.map_or(field.cells[mesh.owner[f] as usize], |v| v[i]);
            phi[f] = if closed && !outflow[pi] {
                0.0
            } else {
                u.dot(geom.face_areas[f])
            };
            free[f] = outflow[pi];
            if outflow[pi] {
                outflow_before += phi[f];
            } else {
                inflow -= phi[f];
            }
        }
    }
    for (f, q) in phi.iter_mut().enumerate().take(ni) {
        *q = linear_face_value(mesh, geom, &field.cells, f).dot(geom.face_areas[f]);
    }
    let div = divergence(mesh, &phi);
    let imbalance_before = div.iter().map(|d| d.abs()).sum();
    // the Laplacian's face coefficients
    let coeff = |f: usize, x_other: DVec3| {
        let a = geom.face_areas[f];
        let d = x_other - geom.cell_centres[mesh.owner[f] as usize];
        let den = a.dot(d);
        if den > 0.0 {
            a.length_squared() / den
        } else {
            a.length() / d.length().max(1e-300)
        }
    };
    let mut a = vec![0.0; nf];
    for (f, af) in a.iter_mut().enumerate().take(ni) {
        *af = coeff(f, geom.cell_centres[mesh.neighbour[f] as usize]);
    }
    let any_free = free.iter().any(|&x| x);
    for f in ni..nf {
        if free[f] {
            a[f] = coeff(f, geom.face_centres[f]);
        }
    }
    if !any_free {
        let net: f64 = div.iter().sum();
        let scale: f64 = phi.iter().map(|p| p.abs()).sum::<f64>().max(1e-300);
        if net.abs() > 1e-9 * scale {
            return Err(MeshError::invalid(
                "<field>",
                "boundaryField",
                format!(
                    "the conservative interpolation needs an outflow patch: no patch takes \
                     the net {net:.4e} m³/s the boundary values carry in"
                ),
            ));
        }
    }
    if let Some(f) = (0..nf).find(|&f| !(phi[f].is_finite() && a[f].is_finite())) {
        return Err(MeshError::invalid(
            "<mesh>",
            format!("face {f}"),
            "the conservative interpolation: a face flux or coefficient is not finite \
             (the mesh or the field beyond floating-point range)",
        ));
    }
    let rhs: Vec<f64> = div.iter().map(|d| -d).collect();
    // converged when the residual is 1e-14 of the imbalance, or rounding of the fluxes
    let floor = 1e-15 * phi.iter().map(|q| q.abs()).sum::<f64>();
    let (p, iterations) = solve_laplacian(mesh, &a, &rhs, !any_free, floor);
    let Some(p) = p else {
        return Err(MeshError::invalid(
            "<mesh>",
            "cells",
            format!(
                "the conservative interpolation: the flux balance did not converge in \
                 {iterations} conjugate-gradient iterations"
            ),
        ));
    };
    let mut max_change: f64 = 0.0;
    let (mut change_area, mut area) = (0.0, 0.0);
    for f in 0..nf {
        let dp = if f < ni {
            p[mesh.neighbour[f] as usize] - p[mesh.owner[f] as usize]
        } else if free[f] {
            -p[mesh.owner[f] as usize]
        } else {
            continue;
        };
        let delta = -a[f] * dp;
        phi[f] += delta;
        let s = geom.face_areas[f].length();
        if s > 0.0 {
            max_change = max_change.max(delta.abs() / s);
            change_area += delta.abs();
            area += s;
        }
    }
    let after = divergence(mesh, &phi);
    let outflow_after = (ni..nf).filter(|&f| free[f]).map(|f| phi[f]).sum();
    Ok((
        phi,
        Projection {
            imbalance_before,
            imbalance_after: after.iter().map(|d| d.abs()).sum(),
            inflow,
            outflow_before,
            outflow_after,
            max_change,
            mean_change: if area > 0.0 { change_area / area } else { 0.0 },
            iterations,
            unbalanced_cells: 0,
        },
    ))
}

/// The cell values `cells` at internal face `f`'s centre, linear between its two cells
/// (weighted by the distances of their centres to the face), as OpenFOAM's `linear`
/// interpolation.
pub fn linear_face_value(mesh: &PolyMesh, geom: &MeshGeometry, cells: &[DVec3], f: usize) -> DVec3 {
    let (o, n) = (mesh.owner[f] as usize, mesh.neighbour[f] as usize);
    let xf = geom.face_centres[f];
    let (dof, dnf) = (
        (xf - geom.cell_centres[o]).length(),
        (geom.cell_centres[n] - xf).length(),
    );
    let w = dnf / (dof + dnf);
    cells[o] * w + cells[n] * (1.0 - w)
}

/// Net outflow of every cell, Σ_f ±φ_f, m³/s.
fn divergence(mesh: &PolyMesh, phi: &[f64]) -> Vec<f64> {
    let mut div = vec![0.0; mesh.n_cells];
    for (f, &q) in phi.iter().enumerate() {
        div[mesh.owner[f] as usize] += q;
        if let Some(&n) = mesh.neighbour.get(f) {
            div[n as usize] -= q;
        }
    }
    div
}

/// Solve Σ_f a_f (p_P − p_Q) = rhs_P (p_Q = 0 across a boundary face with a_f > 0) by
/// conjugate gradients with a Jacobi preconditioner, to rounding; with `pin` (no free
/// face) p of cell 0 is held at 0. Returns p (`None` when the residual did not fall to
/// 1e-14 of the right-hand side, or to `floor`, within the iteration cap, or went
/// non-finite) and the iterations.
fn solve_laplacian(
    mesh: &PolyMesh,
    a: &[f64],
    rhs: &[f64],
    pin: bool,
    floor: f64,
) -> (Option<Vec<f64>>, usize) {
    let nc = mesh.n_cells;
    let ni = mesh.n_internal_faces();
    let mut diag = vec![0.0; nc];
    for (f, &af) in a.iter().enumerate() {
        diag[mesh.owner[f] as usize] += af;
        if f < ni {
            diag[mesh.neighbour[f] as usize] += af;
        }
    }
    let apply = |x: &[f64], y: &mut [f64]| {
        for (c, yc) in y.iter_mut().enumerate() {
            *yc = diag[c] * x[c];
        }
        for (f, &af) in a.iter().enumerate().take(ni) {
            let (o, n) = (mesh.owner[f] as usize, mesh.neighbour[f] as usize);
            y[o] -= af * x[n];
            y[n] -= af * x[o];
        }
        if pin {
            y[0] = x[0];
        }
    };
    let inv: Vec<f64> = diag
        .iter()
        .enumerate()
        .map(|(c, &d)| {
            if (pin && c == 0) || d <= 0.0 {
                1.0
            } else {
                1.0 / d
            }
        })
        .collect();
    let mut b = rhs.to_vec();
    if pin {
        b[0] = 0.0;
    }
    let bnorm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut x = vec![0.0; nc];
    if bnorm <= floor {
        return (Some(x), 0);
    }
    if !bnorm.is_finite() {
        return (None, 0);
    }
    let mut r = b;
    let mut z: Vec<f64> = r.iter().zip(&inv).map(|(r, i)| r * i).collect();
    let mut d = z.clone();
    let mut q = vec![0.0; nc];
    let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
    // CG on a mesh Laplacian needs O(n^(1/3)) iterations times a modest factor (393 on the
    // 30 819-cell cyclone); the cap only stops a run that will not converge
    let max_iter = 20_000.min(20 * nc + 100);
    let mut it = 0;
    let mut converged = false;
    while it < max_iter {
        it += 1;
        apply(&d, &mut q);
        let dq: f64 = d.iter().zip(&q).map(|(a, b)| a * b).sum();
        if dq.is_nan() || dq <= 0.0 {
            break;
        }
        let alpha = rz / dq;
        for c in 0..nc {
            x[c] += alpha * d[c];
            r[c] -= alpha * q[c];
        }
        let rnorm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        if rnorm <= (1e-14 * bnorm).max(floor) {
            converged = true;
            break;
        }
        if !rnorm.is_finite() {
            break;
        }
        for c in 0..nc {
            z[c] = r[c] * inv[c];
        }
        let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let beta = rz_new / rz;
        rz = rz_new;
        for c in 0..nc {
            d[c] = z[c] + beta * d[c];
        }
    }
    (converged.then_some(x), it)
}

/// The constant velocity of every tetrahedron of the decomposition (step 3), m/s: per cell
/// in [`MeshGeometry::faces_of`] order, per face its triangles in the locator's fan order
/// (a triangular face one, a polygon one per edge). `node_value(n)` is the cell-point
/// field at node `n` (a mesh point, or `n_points + f` for face f's centre); `phi` the
/// balanced face fluxes. Returns the offsets of every cell-face entry (one per entry of
/// [`MeshGeometry::cell_faces`], plus one) into the velocities, and the count of cells
/// left unbalanced (degenerate tetrahedra; their tetrahedra take the cell value).
pub fn tet_velocities(
    mesh: &PolyMesh,
    geom: &MeshGeometry,
    cells: &[DVec3],
    node_value: impl Fn(u32) -> DVec3,
    phi: &[f64],
) -> (Vec<u32>, Vec<DVec3>, usize) {
    let np = mesh.points.len() as u32;
    let node = |n: u32| {
        if n < np {
            mesh.points[n as usize]
        } else {
            geom.face_centres[(n - np) as usize]
        }
    };
    // the flux of every face triangle (out of the face's owner)
    let mut tri_start = vec![0usize; mesh.n_faces() + 1];
    for f in 0..mesh.n_faces() {
        let k = mesh.face(f).len();
        tri_start[f + 1] = tri_start[f] + if k == 3 { 1 } else { k };
    }
    let mut tri_flux = vec![0.0; tri_start[mesh.n_faces()]];
    for f in 0..mesh.n_faces() {
        let pts = mesh.face(f);
        let out = &mut tri_flux[tri_start[f]..tri_start[f + 1]];
        if pts.len() == 3 {
            out[0] = phi[f];
            continue;
        }
        let xf = geom.face_centres[f];
        let uf = node_value(np + f as u32);
        let (mut sum, mut area) = (0.0, 0.0);
        let n = pts.len();
        for i in 0..n {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let s = 0.5 * (node(a) - xf).cross(node(b) - xf);
            out[i] = s.dot(uf + node_value(a) + node_value(b)) / 3.0;
            sum += out[i];
            area += s.length();
        }
        for (i, q) in out.iter_mut().enumerate() {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let s = 0.5 * (node(a) - xf).cross(node(b) - xf);
            *q += if area > 0.0 {
                (phi[f] - sum) * s.length() / area
            } else {
                (phi[f] - sum) / n as f64
            };
        }
    }
    let mut offsets = Vec::with_capacity(geom.cell_faces.len() + 1);
    let mut vel = Vec::with_capacity(tri_flux.len() * 2);
    let mut unbalanced = 0;
    let mut cell = CellTets::default();
    for (c, &uc) in cells.iter().enumerate().take(mesh.n_cells) {
        let cc = geom.cell_centres[c];
        cell.clear();
        for &f in geom.faces_of(c) {
            offsets.push(vel.len() as u32 + cell.tets.len() as u32);
            let fi = f as usize;
            let pts = mesh.face(fi);
            let owner = mesh.owner[fi] as usize == c;
            let sign = if owner { 1.0 } else { -1.0 };
            if pts.len() == 3 {
                let (a, b) = if owner {
                    (pts[1], pts[2])
                } else {
                    (pts[2], pts[1])
                };
                cell.push([pts[0], a, b], sign * tri_flux[tri_start[fi]]);
            } else {
                let n = pts.len();
                for i in 0..n {
                    let (pa, pb) = (pts[i], pts[(i + 1) % n]);
                    let (a, b) = if owner { (pa, pb) } else { (pb, pa) };
                    cell.push([np + f, a, b], sign * tri_flux[tri_start[fi] + i]);
                }
            }
        }
        if !cell.solve(cc, uc, &node, &node_value) {
            unbalanced += 1;
            cell.velocity.clear();
            cell.velocity.resize(cell.tets.len(), uc);
        }
        vel.extend_from_slice(&cell.velocity);
    }
    offsets.push(vel.len() as u32);
    (offsets, vel, unbalanced)
}

/// The tetrahedra of one cell and the work space of their balance.
#[derive(Default)]
struct CellTets {
    /// Outer triangle nodes (oriented out of the cell) and outward flux.
    tets: Vec<([u32; 3], f64)>,
    /// Inner triangles (cell centre and an edge of the outer triangles).
    inner: Vec<Inner>,
    velocity: Vec<DVec3>,
}

/// An inner triangle: the flux is out of tetrahedron `plus` into `minus`, through `area`
/// (out of `plus`); the prior flux, then the balanced one.
#[derive(Clone, Copy)]
struct Inner {
    plus: usize,
    minus: usize,
    area: DVec3,
    flux: f64,
}

impl CellTets {
    fn clear(&mut self) {
        self.tets.clear();
        self.inner.clear();
        self.velocity.clear();
    }

    fn push(&mut self, nodes: [u32; 3], flux: f64) {
        self.tets.push((nodes, flux));
    }

    /// Balance the tetrahedra and set their velocities; false when degenerate.
    fn solve(
        &mut self,
        cc: DVec3,
        uc: DVec3,
        node: &impl Fn(u32) -> DVec3,
        value: &impl Fn(u32) -> DVec3,
    ) -> bool {
        let nt = self.tets.len();
        // inner triangles (cc, x, y) for every edge (x, y) of the outer triangles
        let mut edges: Vec<((u32, u32), usize, usize)> = Vec::with_capacity(3 * nt);
        for (t, (n, _)) in self.tets.iter().enumerate() {
            for k in 0..3 {
                let (x, y) = (n[k], n[(k + 1) % 3]);
                edges.push(((x.min(y), x.max(y)), t, k));
            }
        }
        edges.sort_unstable();
        let mut i = 0;
        while i < edges.len() {
            if i + 1 >= edges.len() || edges[i + 1].0 != edges[i].0 {
                return false; // an edge of one triangle only: not a closed surface
            }
            if i + 2 < edges.len() && edges[i + 2].0 == edges[i].0 {
                return false;
            }
            let (_, t, k) = edges[i];
            let (x, y) = (self.tets[t].0[k], self.tets[t].0[(k + 1) % 3]);
            // the inner triangle (cc, x, y), area vector out of tetrahedron t: its
            // opposite vertex is t's third outer node
            let third = self.tets[t].0[(k + 2) % 3];
            let (px, py) = (node(x), node(y));
            let mut s = 0.5 * (px - cc).cross(py - cc);
            if s.dot(node(third) - cc) > 0.0 {
                s = -s;
            }
            let prior = s.dot(uc + value(x) + value(y)) / 3.0;
            self.inner.push(Inner {
                plus: t,
                minus: edges[i + 1].1,
                area: s,
                flux: prior,
            });
            i += 2;
        }
        // r_t = −(outer flux + Σ prior inner fluxes out of t)
        let mut r: Vec<f64> = self.tets.iter().map(|(_, q)| -q).collect();
        for e in &self.inner {
            r[e.plus] -= e.flux;
            r[e.minus] += e.flux;
        }
        // (A W Aᵀ) λ = r with λ_0 = 0: the Laplacian of the tetrahedra, weights |area|
        let m = nt - 1;
        if m > 0 {
            let mut l = vec![0.0; m * m];
            for e in &self.inner {
                let w = e.area.length();
                for (a, b) in [(e.plus, e.minus), (e.minus, e.plus)] {
                    if a > 0 {
                        l[(a - 1) * m + (a - 1)] += w;
                        if b > 0 {
                            l[(a - 1) * m + (b - 1)] -= w;
                        }
                    }
                }
            }
            let mut lam: Vec<f64> = r[1..].to_vec();
            if !cholesky_solve(&mut l, &mut lam, m) {
                return false;
            }
            for e in &mut self.inner {
                let lp = if e.plus > 0 { lam[e.plus - 1] } else { 0.0 };
                let lm = if e.minus > 0 { lam[e.minus - 1] } else { 0.0 };
                e.flux += e.area.length() * (lp - lm);
            }
        }
        // each tetrahedron's constant velocity: least squares over its four faces
        let mut ss = vec![DMat3::ZERO; nt];
        let mut sq = vec![DVec3::ZERO; nt];
        for (t, (n, q)) in self.tets.iter().enumerate() {
            let (a, b, c) = (node(n[0]), node(n[1]), node(n[2]));
            let s = 0.5 * (b - a).cross(c - a);
            ss[t] += outer(s);
            sq[t] += s * *q;
        }
        for e in &self.inner {
            // out of `minus`: area −s, flux −q; (−s)(−s)ᵀ = ssᵀ and (−s)(−q) = s·q
            for t in [e.plus, e.minus] {
                ss[t] += outer(e.area);
                sq[t] += e.area * e.flux;
            }
        }
        self.velocity.clear();
        for t in 0..nt {
            let det = ss[t].determinant();
            if !(det.is_finite() && det > 0.0) {
                return false;
            }
            self.velocity.push(ss[t].inverse() * sq[t]);
        }
        true
    }
}

/// s ⊗ s.
fn outer(s: DVec3) -> DMat3 {
    DMat3::from_cols(s * s.x, s * s.y, s * s.z)
}

/// Solve the symmetric positive definite system `l x = b` (`l` row-major n×n, factored in
/// place); false when it is not positive definite.
fn cholesky_solve(l: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = l[j * n + j];
        for k in 0..j {
            d -= l[j * n + k] * l[j * n + k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        l[j * n + j] = d;
        for i in j + 1..n {
            let mut s = l[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            l[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
    true
}

#[cfg(test)]
mod tests;
