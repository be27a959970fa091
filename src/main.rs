//! The `scg` binary (with the `mpi` feature, `mpirun -np N scg run CASE` runs over N ranks).
fn main() {
    std::process::exit(scg_cli::main());
}
