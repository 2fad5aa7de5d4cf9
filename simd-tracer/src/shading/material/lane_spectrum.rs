//! What a BSDF hands the transport per lane: a spectral factor
//! `constant + scale · X`, `X` a scene spectrum, a texture lookup, the
//! environment map in a direction or an angular spectrum at `cos θ`
//! ([`SpectralRef`]); the transport evaluates
//! `X` in its own representation.

use crate::ids::{AngularId, SpectrumId, TextureId};

/// Where a lane's spectral factor comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpectralRef {
    /// A scene spectrum.
    Scene(SpectrumId),
    /// A spectral texture at `(u, v)`.
    Texture {
        /// Texture.
        texture: TextureId,
        /// Coordinate u.
        u: f32,
        /// Coordinate v.
        v: f32,
    },
    /// The scene's environment map at map coordinates `(u, v)`.
    Environment {
        /// Map coordinates `[u, v]`.
        uv: [f32; 2],
    },
    /// An angular spectrum at `cos θ` (and a film thickness in [0, 1]).
    Angular {
        /// Angular spectrum.
        id: AngularId,
        /// `cos θ`.
        cos: f32,
        /// Film thickness within its range (0 otherwise).
        thickness: f32,
    },
}

/// A lane's spectral factor: `constant + scale · of`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneSpectrum {
    /// Spectrally flat part.
    pub constant: f32,
    /// Weight of `of`.
    pub scale: f32,
    /// The spectral part.
    pub of: Option<SpectralRef>,
}

impl LaneSpectrum {
    /// Zero.
    pub const ZERO: Self = Self {
        constant: 0.0,
        scale: 0.0,
        of: None,
    };
    /// One.
    pub const ONE: Self = Self {
        constant: 1.0,
        scale: 0.0,
        of: None,
    };

    /// `X`.
    pub fn of(x: SpectralRef) -> Self {
        Self {
            constant: 0.0,
            scale: 1.0,
            of: Some(x),
        }
    }

    /// `scale · X`.
    pub fn scaled(scale: f32, x: SpectralRef) -> Self {
        Self {
            constant: 0.0,
            scale,
            of: Some(x),
        }
    }

    /// `1 − X`.
    pub fn complement(x: SpectralRef) -> Self {
        Self {
            constant: 1.0,
            scale: -1.0,
            of: Some(x),
        }
    }

    /// A scene spectrum.
    pub fn scene(id: SpectrumId) -> Self {
        Self::of(SpectralRef::Scene(id))
    }
}
