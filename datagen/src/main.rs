//! `cargo run --release -p datagen`: rewrites `spectral-core/src/data/tables.rs`
//! from `data/*.csv` and refits `spectral-core/src/data/srgb_sigmoid.bin`.

use std::process::ExitCode;

fn write(path: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn run() -> Result<(), String> {
    let text = datagen::generate(&datagen::data_dir())?;
    write(&datagen::output_path(), text.as_bytes())?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let table = datagen::generate_sigmoid_table(threads)?;
    write(&datagen::sigmoid_table_path(), &table)
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("datagen: {message}");
            ExitCode::from(2)
        }
    }
}
