//! Unstructured CFD meshes and the flow fields on them, for one-way coupling.
//!
//! [`PolyMesh`] holds a mesh in OpenFOAM's face-based layout (points, faces, owner,
//! neighbour, boundary patches); every reader produces one, whatever the cell shapes
//! (hexahedra, tetrahedra, prisms, pyramids, arbitrary polyhedra). Lengths are in metres,
//! velocities in m/s.

pub mod build;
pub mod error;
pub mod geometry;
pub mod interp;
pub mod locate;
pub mod polymesh;

pub use error::MeshError;
pub use polymesh::{CellField, Patch, PolyMesh};
