use clap::Parser;

/// mimalloc keeps memory freed by one stage for the next (the tool load frees the file's bytes and
/// parsed statements before the mesh checks and the BVH ask for as much), where glibc's allocator
/// hands large blocks back to the kernel, so every stage paid for fresh pages again.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let cli = drape::cli::Cli::parse();
    if let Err(failure) = drape::cli::run(cli) {
        eprintln!("error: {}", failure.message());
        std::process::exit(failure.exit_code());
    }
}
