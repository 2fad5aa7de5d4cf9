//! A spherical area light sampled by the cone it subtends.
//!
//! An emissive sphere is tessellated like every shape (`scene::analytic`),
//! and its triangles could be sampled one by one by area, as every other
//! emitter is. Seen from a point `x` outside, that wastes half the samples
//! on the far side (facing away) and weights the near side by
//! `d²/cos θ_y`, which grows without bound towards the silhouette: a small
//! spherical lamp is much noisier than the same lamp sampled the way
//! Mitsuba 3 and pbrt-v4 sample spheres, uniformly in the cone of
//! directions it subtends. This module does the latter.
//!
//! **The cone** (`sampling::cone`): directions are drawn uniformly in the
//! cone the sphere subtends, with the pdf `1/Ω` per steradian. The distance to the sphere along it is
//! the nearer root of `t² − 2 t d cos θ + d² − r² = 0`, evaluated as
//! `(d² − r²) / (d cos θ + √(r² − d² sin² θ))` (the product of the roots
//! over the larger one, no cancellation).
//!
//! **Why the estimate stays right with a tessellated sphere.** The
//! tessellation's vertices lie on the sphere, so its triangles lie inside
//! the ball: every direction that hits the mesh lies in the cone, and the
//! segment from `x` to the sphere's near point never enters the ball, so a
//! shadow ray towards that point is never blocked by the light's own
//! triangles. Next-event estimation thus integrates the emission over the
//! sphere's cone; a BSDF sample that hits one of the light's triangles is
//! weighted by MIS with the pdf `P/Ω(x)` ([`SphereLight::pdf_sr`]), `P` the
//! light's selection probability. The two agree on every direction that
//! hits the mesh; they differ only on the band between the tessellation's
//! silhouette and the sphere's, where light sampling counts emission that
//! BSDF sampling does not see: a relative solid angle of at most twice the
//! tessellation's sag (2·10⁻³ at the default sag), where the analytic
//! sphere (Mitsuba's) is the brighter.
//!
//! From a point inside the ball (or on the light itself) there is no cone:
//! the light is not sampled and its pdf is 0, so BSDF sampling alone (MIS
//! weight 1) sees it, which is unbiased. Hence only spheres that emit from
//! their outer side alone are sphere lights (`SceneBuilder::build`): a
//! two-sided one may enclose the scene (a sky dome), where every light
//! sample that chose it would be lost; its triangles, sampled by area,
//! light the inside. And only spheres tessellated at least as finely as
//! the default sag ([`crate::scene::analytic::DEFAULT_SAG`]): the band
//! above grows with the sag (`MeshPlacement::sphere`).

use crate::ids::SpectrumId;
use crate::sampling::cone::{ConeDirection, SphereCone};
use glam::Vec3;
use std::ops::Range;

/// A spherical emitter: a tessellated sphere's triangles, lit uniformly
/// by one spectrum on their outer side.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereLight {
    /// Centre.
    pub center: Vec3,
    /// Radius of the sphere the tessellation's vertices lie on.
    pub radius: f32,
    /// Emitted radiance.
    pub emission: SpectrumId,
    /// The scene's triangles of the tessellation.
    pub triangles: Range<u32>,
}

/// A direction drawn in a sphere light's cone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeSample {
    /// Unit direction from the shading point.
    pub wi: Vec3,
    /// Distance to the sphere along `wi`.
    pub distance: f32,
    /// Solid-angle pdf `1/Ω` (without the selection probability).
    pub pdf_sr: f32,
}

impl SphereLight {
    /// Checks the invariants: a finite centre, a finite positive radius, a
    /// non-empty range of triangles, an emission.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.center.is_finite() && self.radius > 0.0 && self.radius.is_finite()) {
            return Err(format!(
                "sphere light at {} with radius {}",
                self.center, self.radius
            ));
        }
        if self.triangles.is_empty() {
            return Err("sphere light without triangles".into());
        }
        if self.emission.is_none() {
            return Err("sphere light without emission".into());
        }
        Ok(())
    }

    /// Surface area `4π r²`.
    pub fn area(&self) -> f64 {
        let r = f64::from(self.radius);
        4.0 * core::f64::consts::PI * r * r
    }

    /// Whether triangle `triangle` is one of the light's.
    pub fn holds(&self, triangle: u32) -> bool {
        self.triangles.contains(&triangle)
    }

    /// The cone seen from `origin`; `None` inside the ball, on its surface
    /// or where the numbers are not finite (so that [`Self::pdf_sr`] and
    /// [`Self::sample`] agree on where the light can be sampled).
    fn cone(&self, origin: Vec3) -> Option<SphereCone> {
        SphereCone::new(self.center, self.radius, origin)
    }

    /// Solid-angle pdf `1/Ω` with which [`SphereLight::sample`] draws a
    /// direction towards the light from `origin`; 0 from inside the ball.
    pub fn pdf_sr(&self, origin: Vec3) -> f32 {
        self.cone(origin).map_or(0.0, |cone| cone.pdf_sr)
    }

    /// A direction drawn uniformly in the cone the sphere subtends from
    /// `origin`, with `(u, v)` in `[0, 1)²` (module docs); `None` from
    /// inside the ball.
    pub fn sample(&self, origin: Vec3, [u, v]: [f32; 2]) -> Option<ConeSample> {
        let cone = self.cone(origin)?;
        let ConeDirection {
            direction: wi,
            cos_theta,
            sin_sq,
        } = cone.sample([u, v]);
        let d = cone.distance_to_center;
        let r = self.radius;
        let half_chord = (r * r - d * d * sin_sq).max(0.0).sqrt();
        let distance = cone.roots_product / (d * cos_theta + half_chord);
        (distance > 0.0 && distance.is_finite()).then_some(ConeSample {
            wi,
            distance,
            pdf_sr: cone.pdf_sr,
        })
    }
}

/// The index of the light among `spheres` (in ascending order of their
/// triangles, not overlapping) that triangle `triangle` belongs to, by
/// bisection.
pub fn sphere_holding(spheres: &[SphereLight], triangle: u32) -> Option<usize> {
    let at = spheres.partition_point(|s| s.triangles.end <= triangle);
    spheres
        .get(at)
        .is_some_and(|s| s.holds(triangle))
        .then_some(at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use std::f32::consts::{PI, TAU};

    fn light(center: Vec3, radius: f32) -> SphereLight {
        SphereLight {
            center,
            radius,
            emission: SpectrumId(0),
            triangles: 0..1,
        }
    }

    /// The near intersection of a ray with the sphere, by the textbook
    /// quadratic in `f64` (the oracle of the sample's distance).
    fn ray_sphere(origin: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Option<f64> {
        let o = (origin - center).as_dvec3();
        let d = dir.as_dvec3().normalize();
        let b = o.dot(d);
        let c = o.length_squared() - f64::from(radius).powi(2);
        let disc = b * b - c;
        (disc >= 0.0).then(|| -b - disc.sqrt())
    }

    #[test]
    fn samples_hit_the_sphere_at_their_distance() {
        let mut rng = Rng::new(7, 1);
        for (center, radius) in [
            (Vec3::new(0.0, 3.0, 0.0), 1.0),
            (Vec3::new(40.0, -2.0, 5.0), 0.05),
            (Vec3::new(0.3, 0.2, 1.02), 1.0),
        ] {
            let light = light(center, radius);
            let origin = Vec3::new(0.1, -0.2, 0.0);
            for _ in 0..2000 {
                let s = light
                    .sample(origin, [rng.next_f32(), rng.next_f32()])
                    .expect("outside the ball");
                assert!((s.wi.length() - 1.0).abs() < 1e-5);
                // Away from the silhouette, where the distance is well
                // conditioned, it is the oracle's; everywhere the point is
                // on the sphere, on the side facing the origin.
                let t = ray_sphere(origin, s.wi, center, radius).unwrap_or(f64::NAN);
                let depth = s.wi.dot(center - origin) - s.distance;
                if t.is_finite() && depth > 0.1 * radius {
                    let err = (f64::from(s.distance) - t).abs();
                    assert!(err <= 1e-5 * t, "{err} at {t}");
                }
                let hit = origin + s.wi * s.distance;
                let off = ((hit - center).length() - radius).abs();
                assert!(off < 1e-3 * radius + 1e-5 * s.distance, "{off}");
                assert!((hit - center).dot(s.wi) <= 1e-3 * radius, "far side");
            }
        }
    }

    #[test]
    fn the_pdf_is_the_inverse_solid_angle_of_the_cone() {
        // Ω = 2π (1 − √(1 − r²/d²)) in f64, and `pdf_sr` integrates to 1:
        // the fraction of uniform directions on the unit sphere that hit the
        // ball, times 4π, is Ω.
        let center = Vec3::new(0.0, 0.0, 2.5);
        let radius = 1.0;
        let light = light(center, radius);
        let d = 2.5f64;
        let omega = 2.0 * std::f64::consts::PI * (1.0 - (1.0 - 1.0 / (d * d)).sqrt());
        let pdf = f64::from(light.pdf_sr(Vec3::ZERO));
        assert!((pdf * omega - 1.0).abs() < 1e-5, "{}", pdf * omega);
        let mut rng = Rng::new(3, 1);
        let n = 400_000;
        let mut hits = 0u32;
        for _ in 0..n {
            let z = 1.0 - 2.0 * rng.next_f32();
            let phi = TAU * rng.next_f32();
            let s = (1.0 - z * z).max(0.0).sqrt();
            let dir = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            hits += u32::from(ray_sphere(Vec3::ZERO, dir, center, radius).is_some_and(|t| t > 0.0));
        }
        let p = f64::from(hits) / f64::from(n);
        let measured = 4.0 * std::f64::consts::PI * p;
        let sigma = 4.0 * std::f64::consts::PI * (p * (1.0 - p) / f64::from(n)).sqrt();
        assert!(
            (measured - omega).abs() < 4.0 * sigma,
            "{measured} vs {omega}"
        );
        // A tiny, distant sphere: the stable form keeps the pdf finite and
        // right where `1 − cos θ_max` would round to 0.
        let tiny = self::light(Vec3::new(0.0, 0.0, 1000.0), 1e-2);
        let expected = 1.0 / (std::f64::consts::PI * (1e-2f64 / 1000.0).powi(2));
        let relative = f64::from(tiny.pdf_sr(Vec3::ZERO)) / expected - 1.0;
        assert!(relative.abs() < 1e-4, "{relative}");
    }

    #[test]
    fn the_cone_estimates_the_irradiance_of_a_sphere() {
        // A uniform sphere of radiance 1 at distance d above a surface
        // facing its centre gives the irradiance E = π sin² θ_max (a
        // classic form factor). The cone estimate Σ cos θ / pdf converges to
        // it; its negative control, the same sum with the pdf of a cone
        // one tenth wider, does not.
        let d = 3.0f32;
        let radius = 1.2f32;
        let light = light(Vec3::new(0.0, 0.0, d), radius);
        let exact = f64::from(PI) * f64::from(radius * radius / (d * d));
        let mut rng = Rng::new(11, 1);
        let n = 200_000;
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let s = light
                .sample(Vec3::ZERO, [rng.next_f32(), rng.next_f32()])
                .expect("outside");
            let f = f64::from(s.wi.z.max(0.0) / s.pdf_sr);
            sum += f;
            sum_sq += f * f;
        }
        let mean = sum / f64::from(n);
        let sigma = ((sum_sq / f64::from(n) - mean * mean) / f64::from(n)).sqrt();
        assert!(
            (mean - exact).abs() < 4.0 * sigma + 1e-6,
            "{mean} vs {exact}"
        );
        let wider = self::light(Vec3::new(0.0, 0.0, d), radius * 1.1);
        let wrong = mean * f64::from(light.pdf_sr(Vec3::ZERO) / wider.pdf_sr(Vec3::ZERO));
        assert!((wrong - exact).abs() > 10.0 * sigma, "{wrong} vs {exact}");
    }

    #[test]
    fn inside_the_ball_there_is_no_cone() {
        let light = light(Vec3::ZERO, 1.0);
        assert_eq!(light.pdf_sr(Vec3::new(0.5, 0.0, 0.0)), 0.0);
        assert!(
            light
                .sample(Vec3::new(0.0, 0.99, 0.0), [0.5, 0.5])
                .is_none()
        );
        assert_eq!(light.pdf_sr(Vec3::new(f32::NAN, 0.0, 0.0)), 0.0);
        assert!(light.validate().is_ok());
        assert!(self::light(Vec3::ZERO, 0.0).validate().is_err());
        let mut empty = self::light(Vec3::ZERO, 1.0);
        empty.triangles = 3..3;
        assert!(empty.validate().is_err());
    }
}
