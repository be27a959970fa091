//! Unstructured CFD meshes and the flow fields on them, for one-way coupling.
//!
//! [`PolyMesh`] holds a mesh in OpenFOAM's face-based layout (points, faces, owner,
//! neighbour, boundary patches); every reader produces one, whatever the cell shapes
//! (hexahedra, tetrahedra, prisms, pyramids, arbitrary polyhedra). Lengths are in metres,
//! velocities in m/s.
//!
//! Readers and writers:
//! * [`foam`]: OpenFOAM cases — [`foam::read_mesh`], [`foam::read_vector_field`] (a time
//!   directory chosen by [`foam::TimeSel`], listed by [`foam::time_dirs`]),
//!   [`foam::write_case`] and [`foam::write_vector_field`]; ASCII, binary and gzipped files.
//! * [`vtk`]: VTK unstructured grids — [`vtk::read`] (legacy `.vtk`, XML `.vtu`) and
//!   [`vtk::write_legacy`].

pub mod error;
pub mod foam;
pub mod polymesh;
pub mod vtk;

pub use error::MeshError;
pub use polymesh::{CellField, Patch, PolyMesh};
