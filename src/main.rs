//! The `scg` binary (with the `mpi` feature, `mpirun -np N scg run CASE` runs over N ranks).
fn main() {
    #[cfg(feature = "mpi")]
    std::process::exit(scg_mpi::main());
    #[cfg(not(feature = "mpi"))]
    std::process::exit(scg_cli::main());
}
