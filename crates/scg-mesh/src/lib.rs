//! Unstructured CFD meshes and the flow fields on them, for one-way coupling.
//!
//! [`PolyMesh`] holds a mesh in OpenFOAM's face-based layout (points, faces, owner,
//! neighbour, boundary patches); every reader produces one, whatever the cell shapes
//! (hexahedra, tetrahedra, prisms, pyramids, arbitrary polyhedra). Lengths are in metres,
//! velocities in m/s.
//!
//! * [`build`]: box meshes for tests and benchmarks (hexahedra, tetrahedra, polyhedra with
//!   hanging nodes; patches by side or inlet/outlet/walls; seeded perturbation).
//! * [`geometry`]: [`MeshGeometry`], derived once (face centres and areas, cell centres and
//!   volumes by OpenFOAM's formulas, bounding boxes, cell–face and point–cell lists).
//! * [`locate`]: [`Locator`]: first location through a bin grid, tracking by walking
//!   across faces, boundary crossings reported with their patch.
//! * [`interp`]: [`Interpolator`]: cell value and cell-point interpolation of a
//!   [`CellField`]; [`conservative`]: its volume-conserving scheme.
//! * [`table`]: [`CellTable`]: per-cell records of what locating a point in a known cell
//!   and interpolating there reads (the hot path of particle tracking).
//! * [`shared`]: [`Shared`]: borrowed or `Arc`-owned; [`Locator::owned`] and
//!   [`Interpolator::owned`] hold their mesh without borrowing it.
//! * [`surface`]: boundary patches as triangles (face-centre or first-point fans) for
//!   contact walls and drawings.
//!
//! Readers and writers:
//! * [`foam`]: OpenFOAM cases — [`foam::read_mesh`], [`foam::read_vector_field`] and
//!   [`foam::read_scalar_field`] (a time directory chosen by [`foam::TimeSel`], listed by
//!   [`foam::time_dirs`]), [`foam::write_case`], [`foam::write_vector_field`] and
//!   [`foam::write_scalar_field`]; ASCII, binary and gzipped files.
//! * [`vtk`]: VTK unstructured grids — [`vtk::read`] and [`vtk::read_scalar`] (legacy
//!   `.vtk`, XML `.vtu`) and [`vtk::write_legacy`].

pub mod build;
pub mod conservative;
pub mod error;
pub mod foam;
pub mod geometry;
pub mod interp;
pub mod locate;
pub mod polymesh;
pub mod prefetch;
pub mod shared;
pub mod surface;
pub mod table;
pub mod vtk;

pub use error::MeshError;
pub use geometry::MeshGeometry;
pub use interp::{Interpolation, Interpolator};
pub use locate::{Hit, Location, Locator};
pub use polymesh::{CellField, Patch, PolyMesh, ScalarField};
pub use shared::Shared;
pub use table::{CellTable, NO_TET, TableWalk};
