//! The velocity gradient of a mesh flow's cells (the opt-in forces read it).

use super::MeshFlow;

impl MeshFlow {
    /// The velocity gradient of cell `c` (column k = ∂u/∂x_k, 1/s) by Gauss' theorem,
    /// (1/V)·Σ u ⊗ A over the cell's surface. With a cell-point scheme each face is cut
    /// into the triangles (edge, face centre) of the interpolation's decomposition, each
    /// taking the mean of its three node values: exact for an affine field on any
    /// polyhedral cell. With `cell_value` each face takes one value, the two cells'
    /// weighted by their centres' distances (the boundary's own value on boundary faces).
    /// Computed for every cell at the first call. Zero outside the mesh's cells.
    pub fn cell_gradient(&self, c: u32) -> glam::DMat3 {
        let g = self.gradients.get_or_init(|| self.gauss_gradients());
        g.get(c as usize).copied().unwrap_or(glam::DMat3::ZERO)
    }

    fn gauss_gradients(&self) -> Vec<glam::DMat3> {
        let m = self.mesh();
        let g = self.geometry();
        let nodes = self.interp.node_values();
        let np = m.points.len();
        let ni = m.n_internal_faces();
        let mut grad = vec![glam::DMat3::ZERO; m.n_cells];
        for f in 0..m.n_faces() {
            let o = m.owner[f] as usize;
            let (a, xf) = (g.face_areas[f], g.face_centres[f]);
            let outer = if nodes.len() > np + f {
                // the triangles (p_k, p_k+1, centre), each with its nodes' mean value
                let (uc, face) = (nodes[np + f], m.face(f));
                let mut sum = glam::DMat3::ZERO;
                for k in 0..face.len() {
                    let (p, q) = (face[k] as usize, face[(k + 1) % face.len()] as usize);
                    let at = 0.5 * (m.points[p] - xf).cross(m.points[q] - xf);
                    let ut = (nodes[p] + nodes[q] + uc) / 3.0;
                    sum += glam::DMat3::from_cols(ut * at.x, ut * at.y, ut * at.z);
                }
                sum
            } else if f < ni {
                let uf = self.linear_face_value(f);
                // u_f ⊗ A_f: column k is u_f·A_k
                glam::DMat3::from_cols(uf * a.x, uf * a.y, uf * a.z)
            } else {
                let uf = self.interp.velocity(o as u32, xf);
                glam::DMat3::from_cols(uf * a.x, uf * a.y, uf * a.z)
            };
            grad[o] += outer;
            if f < ni {
                grad[m.neighbour[f] as usize] -= outer;
            }
        }
        for (c, gc) in grad.iter_mut().enumerate() {
            *gc *= 1.0 / g.cell_volumes[c];
        }
        grad
    }
}
