use clap::Parser;

fn main() {
    // Mesa prints a conformance warning for lavapipe on every device creation; it is noise
    // on a command line whose output other tools parse.
    if std::env::var_os("MESA_VK_IGNORE_CONFORMANCE_WARNING").is_none() {
        std::env::set_var("MESA_VK_IGNORE_CONFORMANCE_WARNING", "1");
    }
    // SIGINT and SIGTERM: remove the temporary files of writes in progress, then exit 130, so
    // an interrupted command leaves nothing half-done behind (outputs are renamed into place
    // only when complete).
    let _ = ctrlc::set_handler(|| {
        vklens_cli::commands::progress_clear();
        eprintln!("vklens: interrupted; no output was left half-written");
        vklens::imaging::file::remove_pending_and_exit(130);
    });
    let cli = vklens_cli::commands::Cli::parse();
    if let Err(e) = vklens_cli::commands::run(cli) {
        vklens_cli::commands::progress_clear();
        eprintln!("vklens: {}", vklens_cli::commands::describe(&e));
        std::process::exit(vklens_cli::commands::exit_code(&e));
    }
}
