//! How far a mesh flow's cell field is from conserving volume ([`MeshFlow::cell_imbalance`]).

use glam::DVec3;

use super::MeshFlow;

impl MeshFlow {
    /// How far the cell field is from conserving volume: Σ over cells of |Σ_f u_f·A_f|
    /// (m³/s), with u_f linear between the two cells' values on an internal face
    /// (weighted by the distances of their centres to the face) and the interpolated
    /// value at a boundary face's centre. Half of it is the volume flow into the cells
    /// where the field converges, where fluid tracers collect: to compare with the flow
    /// through the domain. A CFD solver's cell velocities conserve volume only through
    /// its face fluxes (Rhie–Chow), so this is never zero, but it should be small.
    pub fn cell_imbalance(&self) -> f64 {
        let m = self.mesh();
        let g = self.geometry();
        let ni = m.n_internal_faces();
        let mut net = vec![0.0f64; m.n_cells];
        for f in 0..m.n_faces() {
            let o = m.owner[f] as usize;
            let (a, xf) = (g.face_areas[f], g.face_centres[f]);
            let q = if f < ni {
                let uf = self.linear_face_value(f);
                net[m.neighbour[f] as usize] -= uf.dot(a);
                uf.dot(a)
            } else {
                self.velocity(o as u32, xf).0.dot(a)
            };
            net[o] += q;
        }
        net.iter().map(|q| q.abs()).sum()
    }

    /// The cell field at internal face `f`'s centre, linear between its two cells' values
    /// ([`scg_mesh::conservative::linear_face_value`]), m/s.
    pub(super) fn linear_face_value(&self, f: usize) -> DVec3 {
        scg_mesh::conservative::linear_face_value(
            self.mesh(),
            self.geometry(),
            self.interp.cell_values(),
            f,
        )
    }
}
