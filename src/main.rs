use clap::Parser;

/// mimalloc keeps memory freed by one stage for the next (the tool load frees the file's bytes and
/// parsed statements before the mesh checks and the BVH ask for as much), where glibc's allocator
/// hands large blocks back to the kernel, so every stage paid for fresh pages again. Without
/// transparent huge pages (`no_thp`): with them the load was faster at best but 2-4 times slower
/// in one run out of three (the kernel clearing 2 MB pages), here more so under load.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let cli = drape::cli::Cli::parse();
    if let Err(failure) = drape::cli::run(cli) {
        eprintln!("error: {}", failure.message());
        std::process::exit(failure.exit_code());
    }
}
