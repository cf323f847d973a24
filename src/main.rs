use clap::Parser;

fn main() {
    // Mesa prints a conformance warning for lavapipe on every device creation; it is noise
    // on a command line whose output other tools parse.
    if std::env::var_os("MESA_VK_IGNORE_CONFORMANCE_WARNING").is_none() {
        std::env::set_var("MESA_VK_IGNORE_CONFORMANCE_WARNING", "1");
    }
    let cli = vklens::internal::cli::Cli::parse();
    if let Err(e) = vklens::internal::cli::run(cli) {
        eprintln!("vklens: {e}");
        std::process::exit(vklens::internal::cli::exit_code(&e));
    }
}
