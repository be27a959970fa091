//! Pure physics: laws and kernels as functions of their inputs, with units and equations
//! in their docs, unit-tested without a World.
//!
//! * [`scaling`] — coarse-graining laws (SCG, none, mass-equivalent, parcel);
//! * [`size_distribution`] — Rosin–Rammler, log-normal and tabulated size distributions;
//! * [`drag`] — drag laws (Stokes, Schiller–Naumann) and response times;
//! * [`erosion`] — wall wear per impact (Finnie, DNV RP-O501);
//! * [`flow`] — the prescribed fluid flow fields;
//! * [`forces`] — opt-in forces besides drag (Cunningham slip), for the original particle;
//! * [`carrier`] — the carrier-velocity seam (the fluid velocity a particle sees, its
//!   modifiers) and the one per-particle step of every scheme;
//! * [`dispersion`] — turbulent dispersion (OpenFOAM's stochastic eddy model, a Langevin
//!   random walk);
//! * [`random`] — counter-based random numbers keyed by (seed, particle, step);
//! * [`mesh_flow`] — flow fields on CFD meshes (location, interpolation, patch roles);
//! * [`inlet`] — feeding on a mesh patch: uniform-by-area sampling, the flow through it;
//! * [`integrate`] — the exponential and explicit schemes, kicks;
//! * [`elementary`] — ln, exp and e^x − 1 in plain arithmetic (a loop of them runs in
//!   lanes);
//! * [`drag_factors`] — a Reynolds-dependent step's τ and exponential factors, one
//!   particle or a block in AVX2 lanes;
//! * [`lane`] — one formula for one particle or four AVX2 lanes (the flows use it);
//! * [`contact`] — normal, tangential and rolling laws, and the pair kernel;
//! * [`wall_shape`] — wall geometry (planes, cylinders, meshes) and touch tests;
//! * [`wall_function`] — the log law of the wall in wall-adjacent cells of a mesh flow;
//! * [`wall_motion`] — prescribed rigid wall motion: pose at t, surface velocity;
//! * [`trimesh`] — triangle-mesh walls: closest points, topology, bin grid, contacts;
//! * [`neighbour`] — the Verlet neighbour list;
//! * [`periodic`] — orthogonal periodic boxes (minimum image).
pub mod carrier;
pub mod contact;
pub mod dispersion;
pub mod drag;
pub mod drag_factors;
pub mod elementary;
pub mod erosion;
pub mod flow;
pub mod forces;
pub mod inlet;
pub mod integrate;
pub mod lane;
pub mod mesh_flow;
pub mod neighbour;
pub mod patch_interaction;
pub mod periodic;
pub mod random;
pub mod scaling;
pub mod size_distribution;
pub mod trimesh;
pub mod wall_function;
pub mod wall_motion;
pub mod wall_shape;
