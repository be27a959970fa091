//! Domain decomposition of scg runs over MPI ranks (issue 19).
//!
//! * [`decomp`] — the ranks' regions (slabs or boxes by recursive bisection), ownership,
//!   balancing and the merging of what the ranks hold:
//!   pure, tested without MPI, always built;
//! * `comm` and `driver` (feature `mpi`, rsmpi over the system's MPI) — the collectives
//!   and the decomposed driver, `driver::Decomposed`: one simulation over the ranks, what
//!   `mpirun -np N scg run CASE` runs (the command line, scg-cli's `mpi` module, stands
//!   above this crate) and what a library user calls beside the single-rank
//!   `Simulation`.
//!
//! Drag-only scenes give the same bits on any number of ranks: a step moves each particle
//! from its own state alone, the fed particles are drawn identically on every rank, and
//! rank 0 writes frames gathered and sorted by id. Particle contacts are decomposed with
//! ghost particles ([`ghosts`]): copies of the neighbouring regions' particles within the
//! contact reach plus the Verlet skin; such runs agree with one rank statistically, not
//! bit for bit (the force sums run in row order, see [`ghosts`]). In a periodic box the
//! regions tile it and meet across its sides. Contacts are refused with `SCG_MPI_DECOMP=ids`.
//! A decomposed run writes one checkpoint in the single-rank format ([`checkpoint`]) and
//! restarts from one on any number of ranks.

pub mod checkpoint;
pub mod decomp;
pub mod ghosts;

#[cfg(feature = "mpi")]
pub mod comm;
#[cfg(feature = "mpi")]
pub mod driver;
pub mod points;
pub mod timing;

/// Whether this process was started by an MPI launcher (`mpirun`, `mpiexec`, `srun`).
pub fn launched_by_mpi() -> bool {
    [
        "OMPI_COMM_WORLD_SIZE",
        "PMI_SIZE",
        "PMIX_RANK",
        "MPI_LOCALNRANKS",
    ]
    .iter()
    .any(|v| std::env::var_os(v).is_some())
}

/// An initialised MPI environment and its world communicator (MPI is finalised when it
/// is dropped).
#[cfg(feature = "mpi")]
pub struct Mpi {
    /// The world communicator.
    pub comm: comm::Comm,
    _universe: mpi::environment::Universe,
}

/// Initialise MPI (funneled threading: only this thread calls MPI); `None` when it
/// cannot be (or was already).
#[cfg(feature = "mpi")]
pub fn initialize() -> Option<Mpi> {
    let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled)?;
    Some(Mpi {
        comm: comm::Comm::new(universe.world()),
        _universe: universe,
    })
}
