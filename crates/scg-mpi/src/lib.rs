//! Domain decomposition of scg runs over MPI ranks (issue 19).
//!
//! * [`decomp`] — slabs, ownership, balancing and the merging of what the ranks hold:
//!   pure, tested without MPI, always built;
//! * `comm` and `run` (feature `mpi`, rsmpi over the system's MPI) — the collectives and
//!   `scg run` over N ranks: `mpirun -np N scg run CASE`.
//!
//! Drag-only scenes give the same bits on any number of ranks: a step moves each particle
//! from its own state alone, the fed particles are drawn identically on every rank, and
//! rank 0 writes frames gathered and sorted by id. Particle contacts are decomposed with
//! ghost particles ([`ghosts`]): copies of the neighbouring slabs' particles within the
//! contact reach plus the Verlet skin; such runs agree with one rank statistically, not
//! bit for bit (the force sums run in row order, see [`ghosts`]). In a periodic box the
//! slabs wrap round it along their axis. Contacts are refused with `SCG_MPI_DECOMP=ids`.
//! A decomposed run writes one checkpoint in the single-rank format ([`checkpoint`]) and
//! restarts from one on any number of ranks.

pub mod checkpoint;
pub mod decomp;
pub mod ghosts;

#[cfg(feature = "mpi")]
pub mod comm;
pub mod points;
#[cfg(feature = "mpi")]
pub mod run;
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

/// The `scg` command line of an MPI build. Started by an MPI launcher with more than one
/// rank, `scg run` runs one simulation over the ranks, each with its share of the cores
/// (unless `--threads` or `SCG_THREADS` says otherwise); `scg cost` and `scg study`
/// spread their independent points (cost points, study variants) over the ranks, each
/// with its share of the cores, and rank 0 writes the outputs; the other subcommands run
/// on rank 0 alone. Otherwise it is the ordinary `scg` (MPI is not even initialised).
#[cfg(feature = "mpi")]
pub fn main() -> i32 {
    if !launched_by_mpi() {
        return scg_cli::main();
    }
    let Some((universe, _)) = mpi::initialize_with_threading(mpi::Threading::Funneled) else {
        eprintln!("error: MPI could not be initialised");
        return 1;
    };
    let comm = comm::Comm::new(universe.world());
    // One rank is the ordinary run, unless the per-step counts are asked for (the
    // reference of the tests) or the driver itself (SCG_MPI_DRIVER=1: what it costs).
    if comm.size() == 1
        && std::env::var_os("SCG_MPI_COUNTS").is_none()
        && std::env::var_os("SCG_MPI_DRIVER").is_none()
    {
        return scg_cli::main();
    }
    let local: usize = std::env::var("OMPI_COMM_WORLD_LOCAL_SIZE")
        .or_else(|_| std::env::var("MPI_LOCALNRANKS"))
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(comm.size())
        .max(1);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    scg_cli::main_with(&scg_cli::Launch {
        run: &|a| run::run(&comm, a),
        points: &points::RankPoints { comm: &comm },
        others: comm.rank() == 0,
        threads: (cores / local).max(1),
    })
}
