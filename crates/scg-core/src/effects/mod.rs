//! Effects: each module adds its systems to the step (see [`crate::step`]) only when the
//! scene declares it. Systems stay thin; the physics they call lives in pure modules.
pub mod contacts;
pub mod feeder;
pub mod guard;
pub mod motion;
pub mod outlet;
pub mod recording;
pub mod scaling;
pub mod walls;
