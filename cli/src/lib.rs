//! The library behind the `fspec` binary: argument handling, loaders and
//! reports, kept here so integration tests and fuzz targets can call them.

pub mod coefficient_choice;
pub mod coeffs;
pub mod error;
pub mod experiment;
pub mod hdr_image;
pub mod image_out;
pub mod merge_cmd;
pub mod neural_report;
pub mod partial_file;
pub mod render_cmd;
pub mod scene_file;
pub mod scene_source;
pub mod sensor_file;
pub mod spectral_image;
pub mod spectrum_cmd;
pub mod spectrum_file;
pub mod texture_cmd;
pub mod texture_file;
pub mod train;
pub mod view;

pub use error::CliError;
