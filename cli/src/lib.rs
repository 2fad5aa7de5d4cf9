//! The library behind the `fspec` binary: argument handling, loaders and
//! reports, kept here so integration tests and fuzz targets can call them.

pub mod coeffs;
pub mod error;
pub mod image_out;
pub mod spectrum_cmd;
pub mod spectrum_file;

pub use error::CliError;
