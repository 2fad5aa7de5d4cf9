//! The cone of a spot light: a point light whose intensity falls off with
//! the angle from its axis.
//!
//! # Profile
//!
//! Mitsuba 3's `spot` emitter (`src/emitters/spot.cpp`, `falloff_curve`),
//! which the importer of its scene files must reproduce: with `θ` the angle
//! between the axis and the direction of emission, `β` the beam width and
//! `c` the cutoff angle (`0 ≤ β ≤ c`),
//!
//! ```text
//! f(θ) = 1                  θ ≤ β
//!        (c − θ) / (c − β)  β < θ < c
//!        0                  θ ≥ c
//! ```
//!
//! linear in the angle, not in its cosine (pbrt-v4's spot light ramps with a
//! smoothstep of `cos θ` instead; the two differ inside the transition).
//! The light's intensity in direction `θ` is `I(λ) · f(θ)`: the profile is
//! the same at every wavelength, so every transport applies it as a scalar
//! factor.
//!
//! As in Mitsuba, the direction is taken into the light's own frame by the
//! inverse of its `to_world` transform's linear part and normalised, and
//! `cos θ` is its `z`: a scaled transform squeezes the cone as Mitsuba's does.
//!
//! # Power
//!
//! The power of intensity `I` through the cone, which the light sampler
//! uses to choose among lights, is `I · 2π ∫₀^π f(θ) sin θ dθ`; integrating
//! the ramp by parts gives the closed form
//!
//! ```text
//! Φ / I = 2π (1 − (sin c − sin β) / (c − β)),
//! ```
//!
//! whose limit for `β → c` is `2π (1 − cos c)`, the solid angle of a sharp
//! cone. (For a transform that is not a rotation the cone is squeezed and
//! this is an estimate; the sampler needs only a positive weight, not the
//! exact power, to stay unbiased.)

use glam::{Mat3, Vec3};

/// The largest cutoff angle in degrees: a cone of 180° is a whole sphere.
pub const MAX_CUTOFF_DEG: f64 = 180.0;

/// Below this transition width (radians) the power uses the sharp cone's
/// limit: `(sin c − sin β)/(c − β)` loses its digits to cancellation there.
const SHARP_TRANSITION_RAD: f64 = 1e-4;

/// The angular profile of a spot light (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotCone {
    /// World directions into the light's frame, whose `+z` is the axis.
    world_to_local: Mat3,
    /// Cutoff angle `c` (radians).
    cutoff_rad: f32,
    /// `cos c`.
    cos_cutoff: f32,
    /// `cos β`.
    cos_beam: f32,
    /// `1/(c − β)`, 0 for a sharp cone (the ramp is then never evaluated).
    inv_transition_per_rad: f32,
    /// `Φ / I` (module docs), in steradians.
    solid_angle_sr: f32,
}

/// Why a spot cone cannot be made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpotConeError {
    /// The cutoff angle (degrees) is not in (0, [`MAX_CUTOFF_DEG`]].
    CutoffAngle(f64),
    /// The beam width (degrees) is not in [0, cutoff].
    BeamWidth {
        /// The beam width given.
        beam_width_deg: f64,
        /// The cutoff angle it must not exceed.
        cutoff_deg: f64,
    },
    /// The frame is not finite or not invertible.
    Frame,
}

impl core::fmt::Display for SpotConeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::CutoffAngle(cutoff_deg) => write!(
                f,
                "cutoff angle {cutoff_deg}°: must be above 0 and at most {MAX_CUTOFF_DEG}"
            ),
            Self::BeamWidth {
                beam_width_deg,
                cutoff_deg,
            } => write!(
                f,
                "beam width {beam_width_deg}°: must be at least 0 and at most the cutoff angle {cutoff_deg}°"
            ),
            Self::Frame => f.write_str("the spot light's transform is not invertible"),
        }
    }
}

impl core::error::Error for SpotConeError {}

/// What a spot cone is made of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotConeSettings {
    /// World directions into the light's frame (the inverse of its
    /// `to_world` transform's linear part); its `+z` is the axis.
    pub world_to_local: Mat3,
    /// Cutoff angle `c` in degrees, in (0, [`MAX_CUTOFF_DEG`]].
    pub cutoff_deg: f64,
    /// Beam width `β` in degrees, in [0, `c`].
    pub beam_width_deg: f64,
}

impl SpotCone {
    /// The cone of `settings`; an error says which angle is out of range or
    /// that the frame is not finite and invertible.
    pub fn new(settings: &SpotConeSettings) -> Result<Self, SpotConeError> {
        let SpotConeSettings {
            world_to_local,
            cutoff_deg,
            beam_width_deg,
        } = *settings;
        if !(cutoff_deg > 0.0 && cutoff_deg <= MAX_CUTOFF_DEG) {
            return Err(SpotConeError::CutoffAngle(cutoff_deg));
        }
        if !(beam_width_deg >= 0.0 && beam_width_deg <= cutoff_deg) {
            return Err(SpotConeError::BeamWidth {
                beam_width_deg,
                cutoff_deg,
            });
        }
        if !(world_to_local.is_finite() && world_to_local.determinant().is_normal()) {
            return Err(SpotConeError::Frame);
        }
        let cutoff_rad = cutoff_deg.to_radians();
        let beam_rad = beam_width_deg.to_radians();
        let transition_rad = cutoff_rad - beam_rad;
        let solid_angle_sr = if transition_rad < SHARP_TRANSITION_RAD {
            core::f64::consts::TAU * (1.0 - cutoff_rad.cos())
        } else {
            core::f64::consts::TAU * (1.0 - (cutoff_rad.sin() - beam_rad.sin()) / transition_rad)
        };
        Ok(Self {
            world_to_local,
            cutoff_rad: cutoff_rad as f32,
            cos_cutoff: cutoff_rad.cos() as f32,
            cos_beam: beam_rad.cos() as f32,
            inv_transition_per_rad: if transition_rad > 0.0 {
                (1.0 / transition_rad) as f32
            } else {
                0.0
            },
            solid_angle_sr: solid_angle_sr as f32,
        })
    }

    /// The profile `f(θ)` in world direction `emitted` (from the light
    /// outwards; any length): in [0, 1], 0 for a zero or non-finite
    /// direction.
    pub fn falloff(&self, emitted: Vec3) -> f32 {
        let Some(local) = (self.world_to_local * emitted).try_normalize() else {
            return 0.0;
        };
        let cos_theta = local.z;
        if cos_theta >= self.cos_beam {
            1.0
        } else if cos_theta > self.cos_cutoff {
            ((self.cutoff_rad - cos_theta.clamp(-1.0, 1.0).acos()) * self.inv_transition_per_rad)
                .clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// `Φ / I`: the power the cone lets through per unit of peak
    /// intensity, in steradians (module docs).
    pub fn solid_angle_sr(&self) -> f32 {
        self.solid_angle_sr
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cone(cutoff_deg: f64, beam_width_deg: f64) -> SpotCone {
        SpotCone::new(&SpotConeSettings {
            world_to_local: Mat3::IDENTITY,
            cutoff_deg,
            beam_width_deg,
        })
        .unwrap_or_else(|e| panic!("{e}"))
    }

    /// A direction at `theta_deg` from `+z`.
    fn at(theta_deg: f64) -> Vec3 {
        let theta = theta_deg.to_radians();
        Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32)
    }

    #[test]
    fn the_profile_is_flat_in_the_beam_linear_in_the_angle_and_zero_past_the_cutoff() {
        let c = cone(20.0, 15.0);
        for theta in [0.0, 5.0, 14.9] {
            assert_eq!(c.falloff(at(theta)), 1.0, "{theta}°");
        }
        // Linear in the angle: 17.5° is half way, 16° a fifth of the way.
        for (theta, expected) in [(17.5, 0.5), (16.0, 0.8), (19.0, 0.2)] {
            let f = c.falloff(at(theta));
            assert!((f - expected).abs() < 2e-4, "{theta}°: {f}");
        }
        // Linear in cos θ (a wrong profile) would give 0.5068 at 17.5°.
        let cos_linear = (17.5f64.to_radians().cos() - 20f64.to_radians().cos())
            / (15f64.to_radians().cos() - 20f64.to_radians().cos());
        assert!((f64::from(c.falloff(at(17.5))) - cos_linear).abs() > 5e-3);
        for theta in [20.0, 21.0, 90.0, 180.0] {
            assert_eq!(c.falloff(at(theta)), 0.0, "{theta}°");
        }
        assert_eq!(c.falloff(Vec3::ZERO), 0.0);
        assert_eq!(c.falloff(Vec3::splat(f32::NAN)), 0.0);
        // Any length: the direction is normalised (to rounding).
        assert!((c.falloff(at(16.0) * 7.0) - c.falloff(at(16.0))).abs() < 1e-5);
    }

    #[test]
    fn a_sharp_cone_has_no_ramp() {
        let c = cone(30.0, 30.0);
        assert_eq!(c.falloff(at(29.9)), 1.0);
        assert_eq!(c.falloff(at(30.1)), 0.0);
    }

    #[test]
    fn the_frame_turns_the_axis() {
        // The light points along +x: its world-to-local map takes +x to +z.
        let to_world = Mat3::from_cols(Vec3::Y, Vec3::Z, Vec3::X);
        let c = SpotCone::new(&SpotConeSettings {
            world_to_local: to_world.inverse(),
            cutoff_deg: 20.0,
            beam_width_deg: 10.0,
        })
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.falloff(Vec3::X), 1.0);
        assert_eq!(c.falloff(Vec3::Z), 0.0);
        assert_eq!(c.falloff(-Vec3::X), 0.0);
    }

    #[test]
    fn the_power_is_the_profile_integrated_over_the_sphere() {
        for (cutoff, beam) in [
            (20.0, 15.0),
            (20.0, 0.0),
            (90.0, 45.0),
            (180.0, 120.0),
            (40.0, 40.0),
        ] {
            let c = cone(cutoff, beam);
            // Midpoint rule over θ, 20 000 steps.
            let steps = 20_000;
            let h = core::f64::consts::PI / f64::from(steps);
            let integral: f64 = (0..steps)
                .map(|k| {
                    let theta = (f64::from(k) + 0.5) * h;
                    f64::from(c.falloff(at(theta.to_degrees()))) * theta.sin() * h
                })
                .sum::<f64>()
                * core::f64::consts::TAU;
            let closed = f64::from(c.solid_angle_sr());
            // The rule's error: small where the profile is continuous; a
            // sharp cone's jump of 1 costs at most one step's width, 2π h.
            assert!(
                (integral - closed).abs() < 1e-4 * closed + core::f64::consts::TAU * h,
                "{cutoff}/{beam}: {integral} vs {closed}"
            );
        }
    }

    #[test]
    fn angles_out_of_range_and_singular_frames_are_refused() {
        let settings = |cutoff_deg, beam_width_deg, world_to_local| SpotConeSettings {
            world_to_local,
            cutoff_deg,
            beam_width_deg,
        };
        for (s, needle) in [
            (settings(0.0, 0.0, Mat3::IDENTITY), "cutoff angle 0°"),
            (settings(-5.0, 0.0, Mat3::IDENTITY), "cutoff angle -5°"),
            (settings(181.0, 0.0, Mat3::IDENTITY), "cutoff angle 181°"),
            (settings(f64::NAN, 0.0, Mat3::IDENTITY), "cutoff angle NaN°"),
            (settings(20.0, 25.0, Mat3::IDENTITY), "beam width 25°"),
            (settings(20.0, -1.0, Mat3::IDENTITY), "beam width -1°"),
            (settings(20.0, 10.0, Mat3::ZERO), "not invertible"),
            (
                settings(20.0, 10.0, Mat3::from_diagonal(Vec3::splat(f32::INFINITY))),
                "not invertible",
            ),
        ] {
            match SpotCone::new(&s) {
                Err(e) => assert!(e.to_string().contains(needle), "{e}"),
                Ok(c) => panic!("{s:?} accepted: {c:?}"),
            }
        }
    }
}
