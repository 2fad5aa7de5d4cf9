//! Where a light path's first segment goes: a mixture of the lamp's cosine
//! distribution and the cones of the dispersive glass seen from the lamp.
//!
//! **Why.** A light path counts only if the events from its lamp to its
//! first non-delta vertex are delta and one of them is on dispersive
//! glass (`light_paths.rs`): its *first* segment must reach glass. A lamp
//! that emits by its cosine sends most paths
//! elsewhere, and in a slit projector (`prism`'s lamp at the end of a
//! black tube) nearly all of them into the tube's wall, where they end
//! after costing a ray. Photon mappers aim photons at specular objects for
//! the same reason (Jensen's projection maps); here the glass is bounded
//! by spheres and the first direction drawn in their cones.
//!
//! **The density.** With `K` targets (balls bounding the triangles of each
//! dispersive material, and each instance whose mesh holds such
//! triangles), a share `a` of the paths ([`COSINE_SHARE`]) leaves by the
//! lamp's own density `p_own` — a triangle's cosine (`|cos θ|/π` over the
//! emitting side, halved for a two-sided lamp), a point light's uniform
//! sphere (`1/4π`) — the rest aim at one target chosen uniformly,
//! uniformly in its cone (`sampling::cone`):
//!
//! ```text
//! p(ω) = a p_own(ω) + (1 − a)/K Σ_k [ω ∈ cone_k] / Ω_k
//! ```
//!
//! where `K` counts the targets the lamp point can aim at: a ball that
//! holds the point is left out (its cone would be the whole sphere, worse
//! than the cosine), and so is a ball wholly behind a one-sided lamp.
//!
//! a one-sample mixture whose weights are folded into the density (Veach's
//! thesis, §9.2.2), so the path starts with `β = L_e |cos θ| A / (P p(ω))`
//! (a point light: `β = I f(θ) / (P p(ω))`, `f` a spot's profile).
//! The own share keeps `p ≥ a p_own` everywhere the lamp emits: paths
//! that reach glass outside every cone (by a mirror first, or glass the
//! targets leave out) are still drawn, with weights at most `1/a` of a
//! cosine light tracer's, so the estimate stays unbiased for every path.
//! Without targets to aim at `a = 1`: the plain cosine. The mixture, `K`
//! included, depends only on the lamp point, so each point's density is
//! exact.
//!
//! **Beams.** Parallel light (a directional light) has one direction and
//! starts anywhere on a disk across it ([`Beam`]: the radius of the sphere
//! around the scene, a diameter before its centre). The same mixture is
//! drawn over the disk's points per unit area: a share `a` uniform over
//! the disk, the rest uniform over the disk a target's ball casts on it,
//! `p(x) = a/(π R²) + (1 − a)/K Σ_k [x ∈ disk_k] / (π r_k²)`.
//!
//! **Targets.** One ball per dispersive material over its triangles, one
//! per instance that shows dispersive triangles; beyond
//! [`MAX_TARGETS`] they merge into one ball around all of them (the
//! density's cost per path grows with `K`).

use crate::sampling::cone::SphereCone;
use crate::sampling::disk::concentric_disk;
use crate::scene::Scene;
use crate::shading::material::sample_cosine;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The share of light paths that leave by the lamp's cosine where there
/// are targets (module docs): a quarter, so that three in four aim at the
/// glass while no direction's weight exceeds four times the cosine light
/// tracer's.
pub const COSINE_SHARE: f32 = 0.25;

/// Most targets kept apart (module docs).
pub const MAX_TARGETS: usize = 64;

/// A ball bounding glass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AimTarget {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

/// How a light path's lamp emits: the own density of the mixture (module
/// docs) and the side(s) it can aim at.
#[derive(Debug, Clone, Copy)]
pub enum Emitting {
    /// A lamp's triangle: by the cosine about its unit front `normal`, on
    /// both sides where `two_sided`.
    Surface {
        /// The triangle's unit front normal.
        normal: Vec3,
        /// Whether it emits on both sides.
        two_sided: bool,
    },
    /// A point light: uniformly over the sphere (a spot's cone weighs the
    /// path's start, not the density).
    Point,
}

impl Emitting {
    /// `p_own(ω)` (module docs), 0 off the emitting side(s).
    fn own_pdf_sr(&self, direction: Vec3) -> f32 {
        match *self {
            Self::Surface { normal, two_sided } => {
                let cos = direction.dot(normal);
                if two_sided {
                    0.5 * cos.abs() / PI
                } else {
                    cos.max(0.0) / PI
                }
            }
            Self::Point => 1.0 / (4.0 * PI),
        }
    }

    /// A direction of the own density from two uniforms, choosing a side
    /// of a two-sided triangle by `u_side`.
    fn sample_own(&self, u_side: f32, u: f32, v: f32) -> Vec3 {
        match *self {
            Self::Surface { normal, two_sided } => {
                let normal = if two_sided && u_side < 0.5 {
                    -normal
                } else {
                    normal
                };
                sample_cosine(normal, u, v)
            }
            Self::Point => uniform_sphere(u, v),
        }
    }

    /// Whether a cone of `cone.sin_sq_max` about `cone.axis` reaches the
    /// emitting side(s).
    fn reaches(&self, cone: &SphereCone) -> bool {
        match *self {
            Self::Surface { normal, two_sided } => {
                two_sided || cone.axis.dot(normal) > -cone.sin_sq_max.sqrt()
            }
            Self::Point => true,
        }
    }
}

/// A uniform direction on the unit sphere from two uniforms (`z = 1 − 2u`,
/// `φ = 2πv`: Archimedes' hat-box theorem makes `z` uniform).
pub(super) fn uniform_sphere(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (2.0 * PI * v).sin_cos();
    Vec3::new(r * cos, r * sin, z)
}

/// A first direction and its density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aimed {
    /// Unit direction.
    pub direction: Vec3,
    /// `p(ω)` per steradian (module docs).
    pub pdf_sr: f32,
}

/// The light paths' first-direction density (module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LightAim {
    targets: Vec<AimTarget>,
}

/// An axis-aligned box, grown point by point.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    min: Vec3,
    max: Vec3,
}

impl Bounds {
    const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    fn grow(&mut self, point: Vec3) {
        self.min = self.min.min(point);
        self.max = self.max.max(point);
    }

    fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    fn corners(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..8u32).map(|k| {
            Vec3::new(
                if k & 1 == 0 { self.min.x } else { self.max.x },
                if k & 2 == 0 { self.min.y } else { self.max.y },
                if k & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// The ball through the box's corners, if the box holds a point.
    fn ball(&self) -> Option<AimTarget> {
        let radius = 0.5 * (self.max - self.min).length();
        (self.min.cmple(self.max).all() && radius > 0.0 && radius.is_finite()).then(|| AimTarget {
            center: 0.5 * (self.min + self.max),
            radius,
        })
    }
}

impl LightAim {
    /// The targets of `scene`: its dispersive glass (module docs).
    pub fn new(scene: &Scene) -> Self {
        let disperses: Vec<bool> = scene
            .materials()
            .iter()
            .map(|m| m.bsdf.disperses())
            .collect();
        let dispersive = |m: Option<crate::ids::MaterialId>| {
            m.is_some_and(|m| disperses.get(m.index()).copied().unwrap_or(false))
        };
        let mut by_material = vec![Bounds::EMPTY; disperses.len()];
        for (index, triangle) in scene.triangles().iter().enumerate() {
            let material = scene.material_of(index);
            if let Some(m) = material.filter(|&m| dispersive(Some(m))) {
                triangle
                    .iter()
                    .for_each(|&p| by_material[m.index()].grow(p));
            }
        }
        let mut boxes: Vec<Bounds> = by_material
            .into_iter()
            .filter(|b| b.ball().is_some())
            .collect();
        if let Some(instances) = scene.instances() {
            // Per mesh: the box of the triangles whose own material
            // disperses, and the box of all of them (for an instance that
            // shows every triangle in one material).
            let meshes: Vec<[Bounds; 2]> = instances
                .meshes()
                .iter()
                .map(|mesh| {
                    let mut own = Bounds::EMPTY;
                    let mut all = Bounds::EMPTY;
                    for (triangle, &material) in mesh.triangles().iter().zip(mesh.materials()) {
                        for &p in triangle {
                            all.grow(p);
                            if dispersive(Some(material)) {
                                own.grow(p);
                            }
                        }
                    }
                    [own, all]
                })
                .collect();
            for (instance, mesh) in instances.instance_meshes().enumerate() {
                let (Some(placement), Some([own, all])) = (
                    u32::try_from(instance)
                        .ok()
                        .and_then(|i| instances.placement(i)),
                    meshes.get(mesh as usize),
                ) else {
                    continue;
                };
                let local = match placement.material {
                    Some(m) if dispersive(Some(m)) => *all,
                    Some(_) => continue,
                    None => *own,
                };
                if local.ball().is_none() {
                    continue;
                }
                let affine = placement.transform.affine();
                let mut world = Bounds::EMPTY;
                local
                    .corners()
                    .for_each(|c| world.grow(affine.transform_point3(c)));
                boxes.push(world);
            }
        }
        Self::from_boxes(&boxes)
    }

    /// Targets around `boxes` (`[min, max]` corners), merged into one
    /// beyond [`MAX_TARGETS`]; empty boxes are left out.
    pub fn from_corners(boxes: &[[Vec3; 2]]) -> Self {
        let boxes: Vec<Bounds> = boxes
            .iter()
            .map(|&[min, max]| Bounds { min, max })
            .collect();
        Self::from_boxes(&boxes)
    }

    fn from_boxes(boxes: &[Bounds]) -> Self {
        let targets = if boxes.len() > MAX_TARGETS {
            let all = boxes.iter().fold(Bounds::EMPTY, |a, &b| a.union(b));
            all.ball().into_iter().collect()
        } else {
            boxes.iter().filter_map(Bounds::ball).collect()
        };
        Self { targets }
    }

    /// The targets.
    pub fn targets(&self) -> &[AimTarget] {
        &self.targets
    }

    /// Checks the invariants: at most [`MAX_TARGETS`] targets, each with a
    /// finite centre and a finite positive radius.
    pub fn validate(&self) -> Result<(), String> {
        if self.targets.len() > MAX_TARGETS {
            return Err(format!(
                "{} light-path targets, more than {MAX_TARGETS}",
                self.targets.len()
            ));
        }
        match self
            .targets
            .iter()
            .find(|t| !(t.center.is_finite() && t.radius > 0.0 && t.radius.is_finite()))
        {
            Some(t) => Err(format!(
                "light-path target at {} with radius {}",
                t.center, t.radius
            )),
            None => Ok(()),
        }
    }

    /// The cones of the targets a lamp at `origin` can aim at: not one
    /// whose ball holds `origin`, nor, for a one-sided lamp, one wholly
    /// behind it (`cos(axis, n) ≤ −sin θ_max`).
    fn cones<'s>(
        &'s self,
        origin: Vec3,
        emitting: &'s Emitting,
    ) -> impl Iterator<Item = SphereCone> + 's {
        self.targets.iter().filter_map(move |t| {
            SphereCone::new(t.center, t.radius, origin).filter(|cone| emitting.reaches(cone))
        })
    }

    /// A first direction from `origin` on a lamp `emitting`, from four
    /// uniforms in `[0, 1)` (the strategy, the side or target, the
    /// direction's two); `None` where it leaves off the emitting side(s).
    pub fn sample(&self, origin: Vec3, emitting: &Emitting, u: [f32; 4]) -> Option<Aimed> {
        let count = self.cones(origin, emitting).count();
        let share = cosine_share(count);
        let (direction, chosen) = if u[0] < share {
            (emitting.sample_own(u[1], u[2], u[3]), None)
        } else {
            let k = ((u[1] * count as f32) as usize).min(count.saturating_sub(1));
            let cone = self.cones(origin, emitting).nth(k)?;
            (cone.sample([u[2], u[3]]).direction, Some(k))
        };
        let pdf_sr = self.density(origin, emitting, direction, chosen);
        (emitting.own_pdf_sr(direction) > 0.0 && pdf_sr > 0.0 && pdf_sr.is_finite())
            .then_some(Aimed { direction, pdf_sr })
    }

    /// `p(ω)` of [`Self::sample`] for the unit `direction` from `origin`
    /// (module docs).
    pub fn pdf_sr(&self, origin: Vec3, emitting: &Emitting, direction: Vec3) -> f32 {
        self.density(origin, emitting, direction, None)
    }

    /// `p(ω)`, counting the `chosen`-th cone as holding `direction` (its
    /// own sample: no rounding at its rim can leave it out).
    fn density(
        &self,
        origin: Vec3,
        emitting: &Emitting,
        direction: Vec3,
        chosen: Option<usize>,
    ) -> f32 {
        let (count, cones) = self.cones(origin, emitting).enumerate().fold(
            (0usize, 0.0f32),
            |(count, sum), (k, cone)| {
                let holds = chosen == Some(k) || cone.contains(direction);
                (count + 1, if holds { sum + cone.pdf_sr } else { sum })
            },
        );
        let share = cosine_share(count);
        let cosine = share * emitting.own_pdf_sr(direction);
        if count == 0 {
            return cosine;
        }
        cosine + (1.0 - share) * cones / count as f32
    }
}

/// Parallel light across the scene (a directional light): its paths enter
/// through a disk across the beam, of the radius of the sphere around the
/// scene, a scene's diameter before its centre (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Unit direction the light travels.
    pub travel: Vec3,
    /// Centre of the sphere around the scene.
    pub center: Vec3,
    /// Its radius.
    pub radius: f32,
}

/// Where a path of parallel light starts and its density per unit area of
/// the beam's cross-section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AimedBeam {
    /// The ray's origin.
    pub origin: Vec3,
    /// `p(x)` per unit area (module docs).
    pub pdf_per_area: f32,
}

impl LightAim {
    /// A start of parallel light `beam` from four uniforms in `[0, 1)` (the
    /// strategy, the target, the point's two): a quarter uniform over the
    /// beam's disk, the rest uniform over the disk each target's ball
    /// casts on the cross-section (module docs).
    pub fn sample_beam(&self, beam: &Beam, u: [f32; 4]) -> Option<AimedBeam> {
        let frame = beam.travel.any_orthonormal_pair();
        let count = self.targets.len();
        let (x, y) = concentric_disk(u[2], u[3]);
        let (p, chosen) = if u[0] < cosine_share(count) {
            (beam.radius * Vec2::new(x, y), Chosen::Own)
        } else {
            let k = ((u[1] * count as f32) as usize).min(count.saturating_sub(1));
            let (centre, radius) = self.discs(beam, frame).nth(k)?;
            (centre + radius * Vec2::new(x, y), Chosen::Target(k))
        };
        let pdf_per_area = self.beam_density(beam, frame, p, chosen);
        let (t, b) = frame;
        let origin = beam.center - 2.0 * beam.radius * beam.travel + t * p.x + b * p.y;
        (pdf_per_area > 0.0 && pdf_per_area.is_finite()).then_some(AimedBeam {
            origin,
            pdf_per_area,
        })
    }

    /// `p(x)` of [`Self::sample_beam`] at the start `origin` (module docs).
    pub fn beam_pdf_per_area(&self, beam: &Beam, origin: Vec3) -> f32 {
        let frame = beam.travel.any_orthonormal_pair();
        let d = origin - beam.center;
        let p = Vec2::new(d.dot(frame.0), d.dot(frame.1));
        self.beam_density(beam, frame, p, Chosen::Neither)
    }

    /// The disks the targets' balls cast on the cross-section of `beam`:
    /// centre in the `frame` and radius.
    fn discs<'s>(
        &'s self,
        beam: &Beam,
        (t, b): (Vec3, Vec3),
    ) -> impl Iterator<Item = (Vec2, f32)> + 's {
        let center = beam.center;
        self.targets.iter().map(move |target| {
            let d = target.center - center;
            (Vec2::new(d.dot(t), d.dot(b)), target.radius)
        })
    }

    /// The beam's `p(x)` at the cross-section's point `p`, counting the
    /// strategy that drew it as holding it (no rounding at a rim can leave
    /// it out).
    fn beam_density(&self, beam: &Beam, frame: (Vec3, Vec3), p: Vec2, chosen: Chosen) -> f32 {
        let count = self.targets.len();
        let share = cosine_share(count);
        let disk_area = |radius: f32| PI * radius * radius;
        let on_disk = chosen == Chosen::Own || p.length() <= beam.radius;
        let own = if on_disk {
            share / disk_area(beam.radius)
        } else {
            0.0
        };
        if count == 0 {
            return own;
        }
        let discs = self
            .discs(beam, frame)
            .enumerate()
            .filter(|&(k, (centre, radius))| {
                chosen == Chosen::Target(k) || p.distance(centre) <= radius
            })
            .map(|(_, (_, radius))| 1.0 / disk_area(radius))
            .sum::<f32>();
        own + (1.0 - share) * discs / count as f32
    }
}

/// Which strategy drew a beam's start.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Chosen {
    /// The uniform disk across the beam.
    Own,
    /// The disk of target `k`.
    Target(usize),
    /// None (a density asked for a given point).
    Neither,
}

/// The cosine's share `a` with `count` cones to aim at (module docs).
fn cosine_share(count: usize) -> f32 {
    if count == 0 { 1.0 } else { COSINE_SHARE }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;

    fn uniforms(rng: &mut Rng) -> [f32; 4] {
        [
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
        ]
    }

    fn lamp(two_sided: bool) -> Emitting {
        Emitting::Surface {
            normal: Vec3::Y,
            two_sided,
        }
    }

    /// The mean of `f(ω)/p(ω)` over `n` samples, and its standard error.
    fn estimate(
        aim: &LightAim,
        emitting: &Emitting,
        n: u32,
        f: impl Fn(Vec3) -> f64,
    ) -> (f64, f64) {
        let mut rng = Rng::new(5, 1);
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        // The density of a sample, evaluated again for its direction alone,
        // is the sampler's but where rounding puts a sample of a cone on
        // its rim outside it: a few in a million.
        let mut rim = 0u32;
        for _ in 0..n {
            let u = uniforms(&mut rng);
            if let Some(a) = aim.sample(Vec3::ZERO, emitting, u) {
                let pdf = aim.pdf_sr(Vec3::ZERO, emitting, a.direction);
                rim += u32::from((pdf - a.pdf_sr).abs() > 1e-4 * a.pdf_sr);
                let w = f(a.direction) / f64::from(a.pdf_sr);
                sum += w;
                sum_sq += w * w;
            }
        }
        assert!(rim <= n / 100_000, "{rim} densities differ");
        let mean = sum / f64::from(n);
        (
            mean,
            ((sum_sq / f64::from(n) - mean * mean) / f64::from(n)).sqrt(),
        )
    }

    /// Two targets above a lamp facing `+y`, one of them around the lamp.
    fn aim() -> LightAim {
        LightAim::from_corners(&[
            [Vec3::new(0.5, 1.5, -0.2), Vec3::new(0.9, 2.0, 0.3)],
            [Vec3::splat(-0.1), Vec3::splat(0.1)],
        ])
    }

    #[test]
    fn the_mixture_integrates_what_the_cosine_does() {
        // ∫ cos θ dω over the emitting side is π; with f = |cos θ| the
        // estimate converges to it for one- and two-sided lamps (2π), and
        // so does the integral of cos θ over a cap around a target (an
        // indicator the cones favour). A density with the wrong cone share
        // (the cosine's share doubled in the weight) misses.
        let aim = aim();
        assert!(aim.validate().is_ok());
        assert_eq!(aim.targets().len(), 2);
        for (two_sided, exact) in [(false, PI), (true, 2.0 * PI)] {
            let emitting = lamp(two_sided);
            let (mean, sigma) = estimate(&aim, &emitting, 200_000, |w| f64::from(w.y.abs()));
            let exact = f64::from(exact);
            assert!(
                (mean - exact).abs() < 4.0 * sigma,
                "{mean} vs {exact} ± {sigma}"
            );
        }
        // The cap: directions within 10° of (0.7, 1.75, 0.05); its cosine
        // integral by dense quadrature in f64.
        let axis = Vec3::new(0.7, 1.75, 0.05).normalize();
        let cap_cos = 10f32.to_radians().cos();
        let in_cap = |w: Vec3| w.dot(axis) >= cap_cos;
        let emitting = lamp(false);
        let (mean, sigma) = estimate(&aim, &emitting, 200_000, |w| {
            if in_cap(w) {
                f64::from(w.y.max(0.0))
            } else {
                0.0
            }
        });
        let steps = 2000;
        let mut exact = 0.0f64;
        for i in 0..steps {
            for j in 0..steps {
                let z = 1.0 - 2.0 * (f64::from(i) + 0.5) / f64::from(steps);
                let phi = 2.0 * std::f64::consts::PI * (f64::from(j) + 0.5) / f64::from(steps);
                let r = (1.0 - z * z).sqrt();
                let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                if in_cap(w) {
                    exact += f64::from(w.y.max(0.0));
                }
            }
        }
        exact *= 4.0 * std::f64::consts::PI / f64::from(steps * steps);
        assert!(
            (mean - exact).abs() < 4.0 * sigma + 1e-4 * exact,
            "{mean} vs {exact}"
        );
        // The cap is sampled far more densely than by the cosine alone:
        // its relative error is well below the cosine's at equal samples.
        let cosine = LightAim::default();
        let (plain, plain_sigma) = estimate(&cosine, &emitting, 200_000, |w| {
            if in_cap(w) {
                f64::from(w.y.max(0.0))
            } else {
                0.0
            }
        });
        assert!((plain - exact).abs() < 4.0 * plain_sigma);
        assert!(sigma < 0.5 * plain_sigma, "{sigma} against {plain_sigma}");
        // Negative control: weights as if every sample were the cosine's
        // (the mixture's density ignored) are far off.
        let mut rng = Rng::new(5, 1);
        let n = 200_000;
        let mut wrong = 0.0f64;
        for _ in 0..n {
            let u = uniforms(&mut rng);
            if let Some(a) = aim.sample(Vec3::ZERO, &emitting, u) {
                if in_cap(a.direction) {
                    wrong += f64::from(PI);
                }
            }
        }
        wrong /= f64::from(n);
        assert!((wrong - exact).abs() > 10.0 * sigma, "{wrong} vs {exact}");
    }

    /// A beam's starts cover its cross-section: `∫ [x on the disk] dA = π R²`
    /// and `∫ [x in a target's disk] dA = π r²` within 4σ (with the aim's
    /// two targets, one wholly inside the disk); the density a start reports
    /// is the density at its origin. Negative control: weighing the starts
    /// by the disk's uniform density alone misses `π R²` by more than 10σ.
    #[test]
    fn beams_cover_the_cross_section_and_aim_at_the_targets() {
        use std::f64::consts::PI;
        let aim = aim();
        let beam = Beam {
            travel: Vec3::new(0.3, -1.0, 0.2).normalize(),
            center: Vec3::new(0.2, 1.0, 0.0),
            radius: 3.0,
        };
        let frame = beam.travel.any_orthonormal_pair();
        let plane = |origin: Vec3| {
            let d = origin - beam.center;
            Vec2::new(d.dot(frame.0), d.dot(frame.1))
        };
        let discs: Vec<(Vec2, f32)> = aim.discs(&beam, frame).collect();
        let mut rng = Rng::new(9, 3);
        let n = 200_000u32;
        let (mut own, mut target, mut uniform) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
        let add = |sums: &mut [f64; 2], w: f64| {
            sums[0] += w;
            sums[1] += w * w;
        };
        for _ in 0..n {
            let start = aim.sample_beam(&beam, uniforms(&mut rng)).expect("a start");
            let density = aim.beam_pdf_per_area(&beam, start.origin);
            assert!((density - start.pdf_per_area).abs() <= 1e-3 * start.pdf_per_area);
            let p = plane(start.origin);
            let w = 1.0 / f64::from(start.pdf_per_area);
            let on_disk = p.length() <= beam.radius;
            add(&mut own, if on_disk { w } else { 0.0 });
            let (centre, radius) = discs[0];
            add(
                &mut target,
                if p.distance(centre) <= radius { w } else { 0.0 },
            );
            let uniform_density = f64::from(COSINE_SHARE) / (PI * f64::from(beam.radius).powi(2));
            add(
                &mut uniform,
                if on_disk { 1.0 / uniform_density } else { 0.0 },
            );
        }
        let stat = |[sum, sum_sq]: [f64; 2]| {
            let mean = sum / f64::from(n);
            (
                mean,
                ((sum_sq / f64::from(n) - mean * mean) / f64::from(n)).sqrt(),
            )
        };
        let disk = PI * f64::from(beam.radius).powi(2);
        let (mean, sigma) = stat(own);
        assert!(
            (mean - disk).abs() < 4.0 * sigma,
            "{mean} vs {disk} ± {sigma}"
        );
        let exact = PI * f64::from(discs[0].1).powi(2);
        let (mean, sigma) = stat(target);
        assert!(
            (mean - exact).abs() < 4.0 * sigma,
            "{mean} vs {exact} ± {sigma}"
        );
        let (wrong, _) = stat(uniform);
        assert!((wrong - disk).abs() > 10.0 * sigma, "{wrong} vs {disk}");
    }

    /// A point light's mixture covers the whole sphere: `∫ 1 dω = 4π` and
    /// `∫ max(cos θ, 0) dω = π` about any axis, within 4σ, with the targets
    /// (the one around the light left out) and without. Negative control:
    /// a one-sided lamp's mixture at the same point, which draws no
    /// direction below its side, misses `4π` by more than 10σ.
    #[test]
    fn point_lights_aim_over_the_whole_sphere() {
        use std::f64::consts::PI;
        // Without targets every weight is `4π` in `f32`: a rounding floor.
        let rounding = 1e-6 * 4.0 * PI;
        for aim in [aim(), LightAim::default()] {
            for (f, exact) in [
                (
                    Box::new(|_: Vec3| 1.0) as Box<dyn Fn(Vec3) -> f64>,
                    4.0 * PI,
                ),
                (Box::new(|w: Vec3| f64::from(w.x.max(0.0))), PI),
                (Box::new(|w: Vec3| f64::from((-w.y).max(0.0))), PI),
            ] {
                let (mean, sigma) = estimate(&aim, &Emitting::Point, 200_000, &f);
                assert!(
                    (mean - exact).abs() < 4.0 * sigma + rounding,
                    "{mean} vs {exact} ± {sigma}"
                );
            }
        }
        let (mean, sigma) = estimate(&aim(), &lamp(false), 200_000, |_| 1.0);
        let exact = 4.0 * PI;
        assert!(
            (mean - exact).abs() > 10.0 * sigma + rounding,
            "{mean} vs {exact}"
        );
    }

    #[test]
    fn lamps_aim_only_at_targets_they_can_reach() {
        // A target wholly behind a one-sided lamp is left out: the plain
        // cosine, nothing leaves backwards, the density behind is 0. A
        // two-sided lamp aims at it: the cone's share plus the cosine's.
        let aim =
            LightAim::from_corners(&[[Vec3::new(-0.2, -2.0, -0.2), Vec3::new(0.2, -1.5, 0.2)]]);
        let emitting = lamp(false);
        let mut rng = Rng::new(9, 1);
        for _ in 0..10_000 {
            let u = uniforms(&mut rng);
            if let Some(a) = aim.sample(Vec3::ZERO, &emitting, u) {
                assert!(a.direction.y > 0.0);
                let cosine = a.direction.y / PI;
                assert!((a.pdf_sr - cosine).abs() <= 1e-6 * cosine, "{a:?}");
            }
        }
        assert_eq!(aim.pdf_sr(Vec3::ZERO, &emitting, -Vec3::Y), 0.0);
        let cone = SphereCone::new(aim.targets()[0].center, aim.targets()[0].radius, Vec3::ZERO)
            .map_or(0.0, |c| c.pdf_sr);
        let two_sided = aim.pdf_sr(Vec3::ZERO, &lamp(true), -Vec3::Y);
        let expected = (1.0 - COSINE_SHARE) * cone + COSINE_SHARE * 0.5 / PI;
        assert!(
            (two_sided - expected).abs() <= 1e-6 * expected,
            "{two_sided} vs {expected}"
        );
        // A lamp inside a target's ball: that target is left out too (its
        // cone would be the whole sphere); with it alone, the cosine.
        let around = LightAim::from_corners(&[[Vec3::splat(-1.0), Vec3::splat(1.0)]]);
        let up = Vec3::new(0.3, 0.8, 0.1).normalize();
        let density = around.pdf_sr(Vec3::ZERO, &emitting, up);
        assert!((density - up.y / PI).abs() <= 1e-6, "{density}");
        // A target half behind the lamp is kept.
        let beside =
            LightAim::from_corners(&[[Vec3::new(2.0, -0.5, -0.5), Vec3::new(3.0, 0.5, 0.5)]]);
        assert!(beside.pdf_sr(Vec3::ZERO, &emitting, Vec3::X) > 0.0);
    }

    /// A glass triangle of the scene's own, two glass cubes `[−1, 1]³`
    /// placed as instances, and what is no target: a grey triangle and a
    /// third cube shown in grey. The targets are the triangle's ball and
    /// each glass instance's, around its world box.
    #[test]
    fn targets_bound_the_dispersive_triangles_and_instances()
    -> Result<(), Box<dyn std::error::Error>> {
        use crate::scene::SceneBuilder;
        use crate::scene::analytic::cube_mesh;
        use crate::scene::builtin::prism::add_sf11_glass;
        use crate::scene::instances::InstancePlacement;
        use crate::scene::transform::Transform;
        use crate::shading::material::Material;
        use crate::spectra::SpectrumSource;
        let mut b = SceneBuilder::new(spectral_core::SpectralRange::VISIBLE);
        let glass = add_sf11_glass(&mut b)?;
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
        let grey = b.add_material(Material::lambert("grey", grey));
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], glass);
        b.add_triangle(
            [
                Vec3::splat(5.0),
                Vec3::new(6.0, 5.0, 5.0),
                Vec3::new(5.0, 6.0, 5.0),
            ],
            grey,
        );
        let cube = b.add_instanced_mesh(vec![(cube_mesh(), glass)])?;
        let centres = [
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(-10.0, 2.0, 0.0),
            Vec3::new(0.0, 0.0, -20.0),
        ];
        for (k, &centre) in centres.iter().enumerate() {
            b.add_instance(
                cube,
                InstancePlacement {
                    transform: Transform::scale(Vec3::splat(2.0))?
                        .then(&Transform::translate(centre)?)?,
                    material: (k == 2).then_some(grey),
                    flip_normals: false,
                    face_normals: false,
                },
            )?;
        }
        b.set_camera(crate::scene::camera::Camera::look_at(
            Vec3::Z * 30.0,
            Vec3::ZERO,
            Vec3::Y,
            40.0,
        )?);
        let scene = b.build()?;
        assert!(scene.instances().is_some_and(|i| i.len() == 3));
        let aim = LightAim::new(&scene);
        aim.validate()?;
        let expected = [
            AimTarget {
                center: Vec3::new(0.5, 0.5, 0.0),
                radius: 0.5 * 2.0f32.sqrt(),
            },
            AimTarget {
                center: centres[0],
                radius: 2.0 * 3.0f32.sqrt(),
            },
            AimTarget {
                center: centres[1],
                radius: 2.0 * 3.0f32.sqrt(),
            },
        ];
        assert_eq!(aim.targets().len(), expected.len(), "{:?}", aim.targets());
        for (target, expected) in aim.targets().iter().zip(&expected) {
            assert!(
                (target.center - expected.center).length() < 1e-4,
                "{target:?}"
            );
            assert!((target.radius - expected.radius).abs() < 1e-4, "{target:?}");
        }
        Ok(())
    }

    #[test]
    fn targets_merge_beyond_the_limit_and_validate() {
        let boxes: Vec<[Vec3; 2]> = (0..=MAX_TARGETS)
            .map(|k| {
                let c = Vec3::new(k as f32, 0.0, 0.0);
                [c, c + Vec3::ONE]
            })
            .collect();
        let merged = LightAim::from_corners(&boxes);
        assert_eq!(merged.targets().len(), 1);
        let ball = merged.targets()[0];
        for [min, max] in &boxes {
            assert!((*min - ball.center).length() <= ball.radius * (1.0 + 1e-6));
            assert!((*max - ball.center).length() <= ball.radius * (1.0 + 1e-6));
        }
        assert!(merged.validate().is_ok());
        let kept = LightAim::from_corners(&boxes[..MAX_TARGETS]);
        assert_eq!(kept.targets().len(), MAX_TARGETS);
        // Empty and non-finite boxes are left out; a broken target fails
        // validation.
        let empty = LightAim::from_corners(&[[Vec3::ONE, Vec3::ZERO], [Vec3::ZERO, Vec3::NAN]]);
        assert!(empty.targets().is_empty());
        let broken = LightAim {
            targets: vec![AimTarget {
                center: Vec3::ZERO,
                radius: -1.0,
            }],
        };
        assert!(broken.validate().is_err());
    }
}
