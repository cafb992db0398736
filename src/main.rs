fn main() -> anyhow::Result<()> {
    mazearena::cli::run()
}
