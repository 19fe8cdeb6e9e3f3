//! Writes the flatland figures (paper Fig. 9, 10, 16 and 17) as CSV + SVG into `out/flatland/`
//! (or the directory given as the first argument) and prints the measured errors.

fn main() -> anyhow::Result<()> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out/flatland".to_string());
    let summary = gradtrace::flatland::write_figures(std::path::Path::new(&dir))?;
    print!(
        "{}",
        std::fs::read_to_string(std::path::Path::new(&dir).join("summary.txt"))?
    );
    for f in &summary.files {
        println!("wrote {}", f.display());
    }
    // Fig. 16-17: analytic-gradient vs numerical adaptive sampling of chirped bumps.
    let sampling =
        gradtrace::flatland::sampling::write_sampling_figures(std::path::Path::new(&dir))?;
    print!(
        "{}",
        std::fs::read_to_string(std::path::Path::new(&dir).join("sampling_summary.txt"))?
    );
    for f in &sampling.files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
