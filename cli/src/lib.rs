//! The `vklens` command line, built on the `vklens` library: each subcommand in [`commands`],
//! the benchmarks behind `vklens bench` in [`bench`]. `main.rs` parses the arguments and
//! reports the error, if any, with the exit code its kind calls for.

// `!(x > 0.0)` is how vklens says "x is positive and not NaN" (see the library's root).
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![deny(unsafe_op_in_unsafe_fn)]

pub mod bench;
pub mod commands;

/// The repository the binary was built from: where `vklens bench` finds the example scenes,
/// lenses and documents it reads and writes.
pub fn repo_root() -> std::path::PathBuf {
    let cli = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    cli.parent().unwrap_or(cli).to_path_buf()
}
