use clap::Parser;

fn main() {
    let cli = drape::cli::Cli::parse();
    if let Err(failure) = drape::cli::run(cli) {
        eprintln!("error: {}", failure.message());
        std::process::exit(failure.exit_code());
    }
}
