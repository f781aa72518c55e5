//! `siftlab`: the lab's `run_odometry.py`, natively.

fn main() {
    std::process::exit(siftlab_core::cli::main());
}
