//! Textures of a scene under construction: image files, loaded once per
//! file, use and sampling, and checkerboards of two scene spectra.
//!
//! The sampling (UV transform, wrap mode, filter) belongs to the texture
//! (`simd_tracer::spectra::texture`), so the same file with two samplings
//! is two textures; a file is read again for each sampling it is used
//! with, which keeps the builder's textures independent of each other.
//! A checkerboard holds copies of its two prepared spectra; as an albedo,
//! each is checked like a spectrum albedo (a warning where it exceeds 1).

use super::Construction;
use crate::error::CliError;
use crate::scene_file::source::Spot;
use crate::texture_file::{TextureUse, load_texture};
use simd_tracer::ids::{SpectrumId, TextureId};
use simd_tracer::spectra::texture::{FilterMode, Texture, TextureSampling, WrapMode};
use std::path::{Path, PathBuf};

/// What identifies a loaded image texture: its file, use and sampling (the
/// UV matrix by its bits, f32 having no `Eq`; −0 as +0, so that a table
/// of default values shares the texture of the plain file name).
pub(super) type TextureKey = (PathBuf, TextureUse, WrapMode, FilterMode, [[u32; 3]; 2]);

fn texture_key(path: &Path, usage: TextureUse, sampling: TextureSampling) -> TextureKey {
    (
        path.to_path_buf(),
        usage,
        sampling.wrap,
        sampling.filter,
        sampling
            .uv
            .matrix()
            .map(|row| row.map(|m| (m + 0.0).to_bits())),
    )
}

impl Construction<'_> {
    /// The texture of the file `path` for `usage`, looked up with
    /// `sampling`; loaded once per file, use and sampling.
    pub(crate) fn texture(
        &mut self,
        at: &Spot,
        path: &Path,
        usage: TextureUse,
        sampling: TextureSampling,
    ) -> Result<TextureId, CliError> {
        let key = texture_key(path, usage, sampling);
        if let Some(&id) = self.textures.get(&key) {
            return Ok(id);
        }
        let texture =
            load_texture(path, usage, self.range).map_err(|e| self.src.error_at(at, e))?;
        let id = self.builder.add_texture(texture.with_sampling(sampling));
        self.textures.insert(key, id);
        Ok(id)
    }

    /// Adds a texture made by the front end (no file cache).
    pub(crate) fn add_texture(&mut self, texture: Texture) -> TextureId {
        self.builder.add_texture(texture)
    }

    /// A checkerboard (Mitsuba 3's `checkerboard`: `colors[0]` where the
    /// halves of the unit cell agree) of two spectra added before, each
    /// with the spot it was given at, for the texture at `at`. As an albedo
    /// each spectrum gets the warning of a spectrum albedo above 1; as a
    /// thickness each square's value is its spectrum's mean.
    pub(crate) fn checkerboard(
        &mut self,
        at: &Spot,
        colors: [(Spot, SpectrumId); 2],
        usage: TextureUse,
        sampling: TextureSampling,
    ) -> Result<TextureId, CliError> {
        if usage == TextureUse::Normals {
            return Err(self
                .src
                .error_at(at, "a normal map must be an image file, not a checkerboard"));
        }
        if usage == TextureUse::Albedo {
            for (spot, id) in &colors {
                self.warn_reflectance_above_one(spot, *id);
            }
        }
        let [(_, id0), (_, id1)] = colors;
        let (Some(color0), Some(color1)) = (self.builder.spectrum(id0), self.builder.spectrum(id1))
        else {
            return Err(self
                .src
                .error_at(at, "a checkerboard spectrum was not added to the scene"));
        };
        let texture = Texture::checkerboard(color0, color1, self.range)
            .map_err(|e| self.src.error_at(at, format!("invalid texture: {e}")))?;
        Ok(self.builder.add_texture(texture.with_sampling(sampling)))
    }
}
