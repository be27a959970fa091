//! scg: a DEM simulator for dilute particle-laden flows, built around the simpler
//! coarse-grain (SCG) model of Kushimoto et al. (Processes 2021, 9, 1098).
//!
//! This facade re-exports the workspace crates: [`core`] (physics and ECS systems),
//! [`scene`] (scene files), [`record`] (recordings) and [`cli`].
//!
//! # Use as a library
//!
//! A scene written in code, run, its frames received through a
//! [`FrameSink`](core::frame::FrameSink) — here an original 1 mm particle and its
//! coarse-grained twin (α = 2, the SCG law keeps ρ·d², so both relax toward the air at
//! the same rate):
//!
//! ```
//! use scg::core::frame::{Frame, FrameSink};
//! use std::sync::{Arc, Mutex};
//!
//! let text = r#"
//! duration = 0.5
//! dt = 1.0e-3
//! record_every = 100
//! [fluid]
//! density = 1.2
//! viscosity = 1.8e-5
//! [flow]
//! kind = "uniform"
//! velocity = [1.0, 0.0, 0.0]
//! [drag]
//! law = "stokes"
//! [checks]
//! allow = ["stokes_reynolds", "light_particles"]
//! [[groups]]
//! name = "original"
//! diameter = 1.0e-3
//! density = 1000.0
//! positions = [[0.0, 0.0, 0.0]]
//! [[groups]]
//! name = "scg_2mm"
//! diameter = 1.0e-3
//! density = 1000.0
//! alpha = 2.0
//! law = "scg"
//! positions = [[0.0, 0.02, 0.0]]
//! "#;
//! let scene = scg::scene::parse(text, "in-code.toml", "in-code", &[])?;
//!
//! /// Keeps the x velocity of every particle at every frame.
//! struct Speeds(Arc<Mutex<Vec<Vec<f64>>>>);
//! impl FrameSink for Speeds {
//!     fn write_frame(&mut self, f: &Frame) -> Result<(), String> {
//!         self.0.lock().unwrap().push(f.velocity.iter().map(|v| v[0]).collect());
//!         Ok(())
//!     }
//!     fn finish(&mut self) -> Result<(), String> {
//!         Ok(())
//!     }
//! }
//!
//! let speeds = Arc::new(Mutex::new(Vec::new()));
//! let mut sim = scene.build(true);
//! sim.add_recorder(Box::new(Speeds(Arc::clone(&speeds))));
//! sim.run(scene.steps(), |_| true)?;
//! sim.finish_recorders()?;
//!
//! let frames = speeds.lock().unwrap();
//! assert_eq!(frames.len(), 5); // every 100 steps of 500
//! let last = frames.last().unwrap();
//! // Stokes relaxation from rest, τ = ρ·d²/(18·μ) = 3.09 s, after 0.5 s:
//! let tau = 1000.0 * 1e-6 / (18.0 * 1.8e-5);
//! assert!((last[0] - (1.0 - (-0.5_f64 / tau).exp())).abs() < 1e-12);
//! // The 2 mm SCG particle has the original's response time: the same velocity.
//! assert!((last[0] - last[1]).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub use scg_cli as cli;
pub use scg_core as core;
/// The decomposed driver over MPI ranks (feature `mpi`): `mpi::driver::Decomposed`.
#[cfg(feature = "mpi")]
pub use scg_mpi as mpi;
pub use scg_record as record;
pub use scg_scene as scene;
