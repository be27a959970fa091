//! The systems of the step, one module per effect. Each module's `plugin` adds its
//! systems to the step ([`crate::step`]) only when the scene declares the effect; the
//! systems stay thin and call the pure laws of [`crate::physics`]. They reach the
//! particles' columns through [`table`], which keeps every particle in one storage table.
pub mod carrier;
pub mod collect;
pub mod contacts;
pub mod erosion;
pub mod feeder;
pub mod flow_series;
pub mod guard;
pub mod impulse_walls;
pub mod mesh_flow;
pub mod motion;
mod move_lanes;
pub mod outlet;
pub mod recording;
pub mod rotational_lift;
pub mod table;
pub mod walls;
