//! A fraction in `[0, 1]` that a BSDF reads at the hit: a mask's opacity,
//! a blend's weight. Either one value or a scalar texture's value at the
//! hit's texture coordinates (grey images), as Mitsuba's float textures
//! (`Texture::eval_1`) give them.

use super::MaterialTables;
use crate::ids::TextureId;
use glam::Vec2;

/// A fraction in `[0, 1]`, constant or from a scalar texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fraction {
    /// One value for the whole surface (finite; clamped to `[0, 1]`).
    Constant(f32),
    /// A scalar texture ([`crate::spectra::texture::Texture::scalar_at`]).
    Texture(TextureId),
}

impl Fraction {
    /// The value at `uv`, clamped to `[0, 1]`; an unknown texture or a NaN
    /// reads as 1 (for a mask: opaque, the nested BSDF, never a silent
    /// hole).
    pub fn at(self, tables: &MaterialTables<'_>, uv: Vec2) -> f32 {
        let value = match self {
            Self::Constant(alpha) => alpha,
            Self::Texture(id) => tables
                .textures
                .get(id.index())
                .map_or(1.0, |t| t.scalar_at(uv.x, uv.y)),
        };
        if value.is_nan() {
            1.0
        } else {
            value.clamp(0.0, 1.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::texture::Texture;
    use spectral_core::SpectralRange;

    const TABLES: MaterialTables<'static> = crate::shading::material::NO_TABLES;

    #[test]
    fn fractions_are_clamped_and_textures_read_per_texel() {
        assert_eq!(Fraction::Constant(1.7).at(&TABLES, Vec2::ZERO), 1.0);
        assert_eq!(Fraction::Constant(-0.2).at(&TABLES, Vec2::ZERO), 0.0);
        assert_eq!(Fraction::Constant(f32::NAN).at(&TABLES, Vec2::ZERO), 1.0);
        // A 2 × 1 texture: 0.25 on the left half, 0.75 on the right
        // (nearest texel at the texel centres).
        let texture =
            Texture::scalar(2, 1, vec![0.25, 0.75], SpectralRange::VISIBLE).expect("valid");
        let textures = [texture];
        let tables = MaterialTables {
            textures: &textures,
            ..TABLES
        };
        let opacity = Fraction::Texture(TextureId(0));
        assert!((opacity.at(&tables, Vec2::new(0.25, 0.5)) - 0.25).abs() < 1e-6);
        assert!((opacity.at(&tables, Vec2::new(0.75, 0.5)) - 0.75).abs() < 1e-6);
        // An unknown texture is opaque.
        assert_eq!(Fraction::Texture(TextureId(3)).at(&tables, Vec2::ZERO), 1.0);
    }
}
