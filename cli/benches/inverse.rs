//! `cargo bench --bench inverse`: the same table as `vklens bench inverse` — error and time of
//! every inverse method on the shared reference cameras, CPU f64 and GPU f32/f64, beside
//! OpenCV's own `undistortPoints` errors. Set VKLENS_BENCH_JSON=1 for JSON lines.

use vklens::host::Context;
use vklens_cli::bench::inverse::{self, InverseBenchOptions};

fn main() {
    let reference = match vklens::io::reference::load_reference() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let ctx = match Context::from_env() {
        Ok(c) => Some(c),
        Err(e) => {
            eprintln!("no Vulkan device ({e}); CPU rows only");
            None
        }
    };
    let rows = inverse::run(
        &reference,
        ctx.as_ref(),
        &InverseBenchOptions::default(),
        |w| eprintln!("measuring {w}"),
    )
    .unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1);
    });
    if std::env::var_os("VKLENS_BENCH_JSON").is_some() {
        for r in &rows {
            println!("{}", serde_json::to_string(r).expect("serializable"));
        }
    } else {
        println!("{}", inverse::table(&rows));
    }
}
