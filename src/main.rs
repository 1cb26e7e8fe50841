fn main() {
    std::process::exit(scansurf::cli::run());
}
