//! The `crowdtouch` command: the daemon and its tools.
#![forbid(unsafe_code)]

mod cli;

fn main() {
    std::process::exit(cli::main());
}
