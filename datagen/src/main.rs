//! `cargo run -p datagen`: rewrites `spectral-core/src/data/tables.rs` from `data/*.csv`.

use std::process::ExitCode;

fn main() -> ExitCode {
    let text = match datagen::generate(&datagen::data_dir()) {
        Ok(text) => text,
        Err(message) => {
            eprintln!("datagen: {message}");
            return ExitCode::from(2);
        }
    };
    let path = datagen::output_path();
    if let Err(e) = std::fs::write(&path, text) {
        eprintln!("datagen: {}: {e}", path.display());
        return ExitCode::from(2);
    }
    println!("wrote {}", path.display());
    ExitCode::SUCCESS
}
