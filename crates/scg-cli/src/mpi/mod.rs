//! `scg` over MPI ranks (feature `mpi`): started by an MPI launcher with more than one
//! rank, `scg run` runs one simulation over the ranks through the decomposed driver
//! ([`scg_mpi::driver::Decomposed`]), each rank with its share of the cores (unless
//! `--threads` or `SCG_THREADS` says otherwise); `scg cost` and `scg study` spread their
//! independent points over the ranks ([`points::RankPoints`]) and rank 0 writes the
//! outputs; the other subcommands run on rank 0 alone. Otherwise it is the ordinary
//! `scg` (MPI is not even initialised).

mod checkpoints;
pub mod points;
mod run;

/// The `scg` command line of an MPI build (see the module documentation).
pub fn main() -> i32 {
    if !scg_mpi::launched_by_mpi() {
        return crate::local_main();
    }
    let Some(mpi) = scg_mpi::initialize() else {
        eprintln!("error: MPI could not be initialised");
        return 1;
    };
    let comm = &mpi.comm;
    // One rank is the ordinary run, unless the per-step counts are asked for (the
    // reference of the tests) or the driver itself (SCG_MPI_DRIVER=1: what it costs).
    if comm.size() == 1
        && std::env::var_os("SCG_MPI_COUNTS").is_none()
        && std::env::var_os("SCG_MPI_DRIVER").is_none()
    {
        return crate::local_main();
    }
    let local: usize = std::env::var("OMPI_COMM_WORLD_LOCAL_SIZE")
        .or_else(|_| std::env::var("MPI_LOCALNRANKS"))
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(comm.size())
        .max(1);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    crate::main_with(&crate::Launch {
        run: &|a| run::run(comm, a),
        points: &points::RankPoints { comm },
        others: comm.rank() == 0,
        threads: (cores / local).max(1),
    })
}
