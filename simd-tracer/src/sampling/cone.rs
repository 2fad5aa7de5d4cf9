//! The cone of directions a ball subtends from a point outside it, and
//! directions drawn uniformly in it: what sphere lights sample
//! (`shading::sphere_light`) and where light paths aim at glass
//! (`integrator::light_aim`).
//!
//! With `d = |c − x|` the distance from the point `x` to the centre `c`
//! and `r` the radius, the ball subtends the half-angle `θ_max` with
//! `sin² θ_max = r²/d²`. Its solid angle is `Ω = 2π (1 − cos θ_max)`,
//! evaluated as `2π sin² θ_max / (1 + cos θ_max)` (no cancellation for a
//! small, distant ball). A direction is drawn uniformly in the cone:
//! `1 − cos θ = u (1 − cos θ_max)`, `φ = 2π v`, about the axis `(c − x)/d`;
//! its pdf is `1/Ω` per steradian. Whether a direction lies in the cone is
//! decided by `sin² θ ≤ sin² θ_max` on the side of the axis (a cross
//! product, not `1 − cos θ`, which cancels for a small cone).

use glam::Vec3;
use std::f32::consts::TAU;

/// The cone of a ball seen from a point outside it (module docs).
#[derive(Debug, Clone, Copy)]
pub struct SphereCone {
    /// Unit direction to the centre.
    pub axis: Vec3,
    /// `d`.
    pub distance_to_center: f32,
    /// `d² − r²`, the product of the two distances to the sphere along
    /// any ray from the origin that meets it.
    pub roots_product: f32,
    /// `sin² θ_max = r²/d²`.
    pub sin_sq_max: f32,
    /// `1 − cos θ_max`.
    pub one_minus_cos_max: f32,
    /// `1/Ω`.
    pub pdf_sr: f32,
}

/// A direction drawn in a [`SphereCone`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeDirection {
    /// Unit direction.
    pub direction: Vec3,
    /// `cos θ` from the axis.
    pub cos_theta: f32,
    /// `sin² θ` from the axis.
    pub sin_sq: f32,
}

impl SphereCone {
    /// The cone of the ball (`center`, `radius`) seen from `origin`;
    /// `None` inside the ball, on its surface or where the numbers are not
    /// finite.
    pub fn new(center: Vec3, radius: f32, origin: Vec3) -> Option<Self> {
        let to_center = center - origin;
        let distance_sq = to_center.length_squared();
        let radius_sq = radius * radius;
        if !(distance_sq > radius_sq && distance_sq.is_finite()) {
            return None;
        }
        let distance_to_center = distance_sq.sqrt();
        let sin_sq_max = radius_sq / distance_sq;
        let cos_max = (1.0 - sin_sq_max).max(0.0).sqrt();
        let one_minus_cos_max = sin_sq_max / (1.0 + cos_max);
        let pdf_sr = 1.0 / (TAU * one_minus_cos_max);
        let roots_product = distance_sq - radius_sq;
        (one_minus_cos_max > 0.0 && pdf_sr.is_finite() && roots_product > 0.0).then(|| Self {
            axis: to_center / distance_to_center,
            distance_to_center,
            roots_product,
            sin_sq_max,
            one_minus_cos_max,
            pdf_sr,
        })
    }

    /// A direction drawn uniformly in the cone from `(u, v)` in `[0, 1)²`.
    pub fn sample(&self, [u, v]: [f32; 2]) -> ConeDirection {
        let one_minus_cos = u * self.one_minus_cos_max;
        let cos_theta = 1.0 - one_minus_cos;
        let sin_sq = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0);
        let sin_theta = sin_sq.sqrt();
        let (sin_phi, cos_phi) = (TAU * v).sin_cos();
        let (t1, t2) = self.axis.any_orthonormal_pair();
        let direction =
            (self.axis * cos_theta + (t1 * cos_phi + t2 * sin_phi) * sin_theta).normalize();
        ConeDirection {
            direction,
            cos_theta,
            sin_sq,
        }
    }

    /// Whether the unit `direction` lies in the cone.
    pub fn contains(&self, direction: Vec3) -> bool {
        direction.dot(self.axis) > 0.0
            && direction.cross(self.axis).length_squared() <= self.sin_sq_max
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;

    /// Every drawn direction lies in the cone, and uniform directions fall
    /// in it with probability `Ω/4π` (within 4σ); a cone whose `sin² θ_max`
    /// is 10 % too small misses that fraction (negative control).
    #[test]
    fn drawn_directions_lie_in_the_cone_that_covers_its_solid_angle() {
        let mut rng = Rng::new(21, 1);
        for (center, radius) in [
            (Vec3::new(0.0, 0.0, 3.0), 1.0),
            (Vec3::new(-2.0, 5.0, 1.0), 0.01),
        ] {
            let cone = SphereCone::new(center, radius, Vec3::ZERO).expect("outside");
            // Rounding may put a direction drawn at the rim just outside.
            let mut outside = 0u32;
            for _ in 0..20_000 {
                let drawn = cone.sample([rng.next_f32(), rng.next_f32()]);
                assert!((drawn.direction.length() - 1.0).abs() < 1e-5);
                let axis_cos = drawn.direction.dot(cone.axis);
                assert!((axis_cos - drawn.cos_theta).abs() < 1e-5);
                outside += u32::from(!cone.contains(drawn.direction));
            }
            assert!(outside <= 2, "{outside} of 20 000 outside");
        }
        let cone = SphereCone::new(Vec3::new(0.3, -0.2, 2.0), 1.1, Vec3::ZERO).expect("outside");
        let narrower = SphereCone {
            sin_sq_max: 0.9 * cone.sin_sq_max,
            ..cone
        };
        let n = 400_000u32;
        let (mut inside, mut inside_narrower) = (0u32, 0u32);
        for _ in 0..n {
            let z = 1.0 - 2.0 * rng.next_f32();
            let phi = TAU * rng.next_f32();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let direction = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            inside += u32::from(cone.contains(direction));
            inside_narrower += u32::from(narrower.contains(direction));
        }
        let expected = 1.0 / (2.0 * f64::from(cone.pdf_sr)) / (2.0 * std::f64::consts::PI);
        let sigma = (expected * (1.0 - expected) / f64::from(n)).sqrt();
        let fraction = f64::from(inside) / f64::from(n);
        assert!(
            (fraction - expected).abs() < 4.0 * sigma,
            "{fraction} vs {expected}"
        );
        let narrow = f64::from(inside_narrower) / f64::from(n);
        assert!(
            (narrow - expected).abs() > 10.0 * sigma,
            "{narrow} vs {expected}"
        );
    }
}
