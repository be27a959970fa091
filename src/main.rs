//! The `scg` binary.
fn main() {
    std::process::exit(scg_cli::main());
}
