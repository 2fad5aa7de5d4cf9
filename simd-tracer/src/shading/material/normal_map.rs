//! Normal and bump maps: a nested BSDF shaded in a frame whose normal an
//! image tilts (Mitsuba 3.9.1's `normalmap`, src/bsdfs/normalmap.cpp, and
//! `bumpmap`, src/bsdfs/bumpmap.cpp, with src/bsdfs/normalmap_helpers.h),
//! for surface detail (wrinkles, tiles, scratches) without geometry.
//!
//! **The map.** A texel `(r, g, b)` is a unit normal in the shading frame,
//! `ñ = 2 (r, g, b) − 1`: `(0.5, 0.5, 1)` leaves the surface as it is.
//! The frame is Mitsuba's: `z` the shading normal, `s` the texture's `u`
//! direction `∂p/∂u` made orthogonal to it (Gram–Schmidt,
//! `s = normalize(∂p/∂u − z (z · ∂p/∂u))`, [`ShadingPoint::dp_duv`]; any
//! unit vector orthogonal to `z` where `∂p/∂u` vanishes or is parallel to
//! it), `t = n × s` with `n` the surface's front normal. The perturbed
//! normal is `n' = normalize(ñ_x s + ñ_y t + ñ_z z)`.
//!
//! **The bumps.** A bump map gives `ñ` from the slopes of a height field
//! `h(u, v)` (a scalar texture times `scale`; its gradient
//! [`crate::spectra::texture::Texture::scalar_gradient_at`]): the
//! surface's derivatives move along the normal `n` by the heights' slopes,
//! `∂p/∂u' = ∂p/∂u + n (∂h/∂u − n · ∂p/∂u)` and likewise for `v`, the
//! bumped normal is `normalize(∂p/∂u' × ∂p/∂v')` turned to `n`'s side, and
//! `ñ` its coordinates in the frame `(s, t, n)` ([`ShadingPoint::dp_duv`];
//! a unit basis where the derivatives are unknown). Mitsuba turns it to
//! the geometric normal's side, which the shading normal shares but at
//! grazing smooth-shaded silhouettes. From `ñ` on both are the same.
//!
//! **Which side.** Mitsuba builds the frame from the shading normal as the
//! surface has it (its front), also when the viewer is behind it, so that
//! a bump seen from behind is a dent; inside a `twosided` (which turns
//! the frame over before its nested BSDF sees it) the frame's `z` is the
//! normal turned to the viewer instead ([`MapFrame`]). TOML scenes use
//! [`MapFrame::Surface`], the relief of a real surface.
//!
//! **Flipped normals** (`flip_invalid_normals`, default on): where the
//! viewer direction `wo` lies on the other side of `n'` than of `z`
//! (`(wo · z)(wo · ñ) ≤ 0` in the frame), `ñ`'s tangential part changes
//! sign, `ñ = (−ñ_x, −ñ_y, ñ_z)` (Schüssler et al., "Microfacet-based
//! Normal Mapping for Robust Monte Carlo Path Tracing", 2017, as
//! Mitsuba simplifies it).
//!
//! **Evaluation and sampling.** The nested BSDF is evaluated and sampled
//! at `n'` (turned towards `wo`; `wo · n' > 0` says which face it sees);
//! a direction `wi` counts only where it lies on the same side of `z` and
//! of `n'`, `(wi · z)(wi · n') > 0`, and values and sample weights are
//! multiplied by the shadowing term of Estevez et al. (Ray Tracing Gems,
//! 2019, chapter 12; `use_shadowing_function`, default on)
//!
//! `G = 2 / (1 + √(1 + α² tan²θ_i))`, `α² = min(tan²θ_ñ / 8, 1)`,
//!
//! `θ_i` the angle of `wi` to `z`, `θ_ñ` of `ñ` to the frame's `z`; it
//! softens the terminator a tilted normal would cut. The pdf is the
//! nested one: `G` scales the value, not the density, so MIS weights are
//! the nested BSDF's.

use super::frame::basis;
use super::{Bsdf, BsdfEval, BsdfSample, MaterialTables, ShadingPoint};
use crate::ids::TextureId;
use glam::Vec3;

/// Mitsuba's bound on the shadowing term's `α²` (normalmap_helpers.h).
const MAX_SHADOWING_ALPHA_SQ: f32 = 1.0;
/// Mitsuba's factor from `tan²θ_ñ` to `α²`, `1/8` (normalmap_helpers.h,
/// after Estevez et al. 2019).
const SHADOWING_ALPHA_SQ_PER_TAN_SQ: f32 = 0.125;

/// Which normal the map's `z` axis is (module docs, *Which side*).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFrame {
    /// The surface's front normal, on both faces (Mitsuba's `normalmap`
    /// outside a `twosided`, and TOML scenes).
    Surface,
    /// The normal turned towards the viewer (a `normalmap` inside a
    /// `twosided`).
    Viewer,
}

/// Where the tilted normal comes from (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Relief {
    /// The tangent-space normals as `(ñ + 1)/2`, a vector texture
    /// (Mitsuba's `normalmap`).
    Normals(TextureId),
    /// Heights: a scalar texture times `scale` (Mitsuba's `bumpmap`).
    Heights {
        /// The heights, a scalar texture.
        texture: TextureId,
        /// Their multiplier (Mitsuba's `scale`).
        scale: f32,
    },
}

impl Relief {
    /// The texture it reads.
    pub fn texture(self) -> TextureId {
        match self {
            Self::Normals(texture) | Self::Heights { texture, .. } => texture,
        }
    }
}

/// A normal- or bump-mapped BSDF (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct NormalMap {
    /// The tilted normals or the heights.
    pub relief: Relief,
    /// The BSDF shaded in the perturbed frame.
    pub nested: Bsdf,
    /// The frame's `z` axis behind the surface.
    pub frame: MapFrame,
    /// Mitsuba's `flip_invalid_normals`.
    pub flip_invalid: bool,
    /// Mitsuba's `use_shadowing_function`.
    pub shadowing: bool,
    /// The nested BSDF scatters only in front of `n'` (it does not
    /// transmit and is one-sided, [`super::Sides::Front`]): a viewer
    /// behind `n'` sees black, as Mitsuba's one-sided BSDFs give in the
    /// perturbed frame.
    pub nested_front_only: bool,
}

/// The perturbed frame at a shading point.
#[derive(Debug, Clone, Copy)]
struct Perturbed {
    /// The frame's `z` axis (module docs).
    z: Vec3,
    /// The perturbed unit normal `n'` in the world (not turned).
    n: Vec3,
    /// `α²` of the shadowing term (0 without it).
    alpha_sq: f32,
    /// Where the nested BSDF is evaluated: `n'` turned towards `wo`.
    nested: ShadingPoint,
}

impl NormalMap {
    /// The perturbed frame at `p` seen from `wo`; `None` where the map's
    /// normal is degenerate (zero, or `wo` in its tangent plane).
    fn perturb(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
    ) -> Option<Perturbed> {
        let texture = tables.textures.get(self.relief.texture().index())?;
        let surface_normal = if p.front { p.n } else { -p.n };
        let z = match self.frame {
            MapFrame::Surface => surface_normal,
            MapFrame::Viewer => p.n,
        };
        let [dp_du, dp_dv] = p.dp_duv;
        let s = (dp_du - z * z.dot(dp_du))
            .try_normalize()
            .unwrap_or_else(|| basis(z).0);
        let t = surface_normal.cross(s);
        let mut local = match self.relief {
            Relief::Normals(_) => {
                Vec3::from_array(texture.vector_at(p.uv.x, p.uv.y)?) * 2.0 - Vec3::ONE
            }
            Relief::Heights { scale, .. } => {
                let [dh_du, dh_dv] = texture.scalar_gradient_at(p.uv.x, p.uv.y);
                let n = surface_normal;
                let (dp_du, dp_dv) = if dp_du.cross(dp_dv).length_squared() > 0.0 {
                    (dp_du, dp_dv)
                } else {
                    basis(n)
                };
                let bumped_u = dp_du + n * (scale * dh_du - n.dot(dp_du));
                let bumped_v = dp_dv + n * (scale * dh_dv - n.dot(dp_dv));
                let bumped = bumped_u.cross(bumped_v).try_normalize()?;
                let bumped = if bumped.dot(n) < 0.0 { -bumped } else { bumped };
                Vec3::new(bumped.dot(s), bumped.dot(t), bumped.dot(n))
            }
        };
        let wo_local = Vec3::new(wo.dot(s), wo.dot(t), wo.dot(z));
        if self.flip_invalid && wo_local.z * wo_local.dot(local) <= 0.0 {
            local = Vec3::new(-local.x, -local.y, local.z);
        }
        let local = local.try_normalize()?;
        let n = (local.x * s + local.y * t + local.z * z).try_normalize()?;
        let cos_o = wo.dot(n);
        if cos_o == 0.0 || !cos_o.is_finite() || (self.nested_front_only && cos_o < 0.0) {
            return None;
        }
        let alpha_sq = if self.shadowing {
            (SHADOWING_ALPHA_SQ_PER_TAN_SQ * tan_sq(local.z)).min(MAX_SHADOWING_ALPHA_SQ)
        } else {
            0.0
        };
        Some(Perturbed {
            z,
            n,
            alpha_sq,
            nested: ShadingPoint {
                n: if cos_o > 0.0 { n } else { -n },
                front: cos_o > 0.0,
                ..*p
            },
        })
    }

    /// [`Bsdf::sample`] of the normal-mapped BSDF (module docs).
    pub(super) fn sample(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        direction: [f32; 2],
    ) -> Option<BsdfSample> {
        let frame = self.perturb(tables, p, wo)?;
        let [u, v] = direction;
        let mut sample = self
            .nested
            .sample(tables, &frame.nested, wo, u_lobe, u, v)?;
        if !frame.same_sides(sample.wi) {
            return None;
        }
        sample.weight *= frame.shadowing(sample.wi);
        Some(sample)
    }

    /// [`Bsdf::eval`] of the normal-mapped BSDF (module docs).
    pub(super) fn eval(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        wi: Vec3,
    ) -> BsdfEval {
        let Some(frame) = self.perturb(tables, p, wo) else {
            return BsdfEval::ZERO;
        };
        if !frame.same_sides(wi) {
            return BsdfEval::ZERO;
        }
        let mut eval = self.nested.eval(tables, &frame.nested, wo, wi);
        eval.value *= frame.shadowing(wi);
        eval
    }

    /// [`Bsdf::direction_depends_on_wavelength`] of the nested BSDF at the
    /// perturbed frame.
    pub(super) fn direction_depends_on_wavelength(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
    ) -> bool {
        self.perturb(tables, p, wo).is_some_and(|frame| {
            self.nested
                .direction_depends_on_wavelength(tables, &frame.nested, wo, u_lobe)
        })
    }
}

impl Perturbed {
    /// Whether `wi` lies on the same side of the frame's `z` and of `n'`.
    fn same_sides(&self, wi: Vec3) -> bool {
        wi.dot(self.z) * wi.dot(self.n) > 0.0
    }

    /// The shadowing term `G` for `wi` (module docs; 1 without it).
    fn shadowing(&self, wi: Vec3) -> f32 {
        if self.alpha_sq == 0.0 {
            return 1.0;
        }
        let tan_sq_i = tan_sq(wi.dot(self.z));
        2.0 / (1.0 + (1.0 + self.alpha_sq * tan_sq_i).sqrt())
    }
}

/// `tan²θ` of a unit vector whose `z` is `cos_theta`, as Mitsuba's
/// `Frame::tan_theta_2`: `max(0, 1 − cos²)/cos²` (infinite at 0).
fn tan_sq(cos_theta: f32) -> f32 {
    let cos_sq = cos_theta * cos_theta;
    (1.0 - cos_sq).max(0.0) / cos_sq
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::SpectrumId;
    use crate::sampling::rng::Rng;
    use crate::shading::material::Albedo;
    use crate::spectra::texture::Texture;
    use glam::Vec2;
    use spectral_core::SpectralRange;

    fn lambert() -> Bsdf {
        Bsdf::Lambert {
            albedo: Albedo::Spectrum(SpectrumId(0)),
        }
    }

    fn map(frame: MapFrame) -> NormalMap {
        NormalMap {
            relief: Relief::Normals(TextureId(0)),
            nested: lambert(),
            frame,
            flip_invalid: true,
            shadowing: true,
            nested_front_only: false,
        }
    }

    fn textures(texel: [f32; 3]) -> Vec<Texture> {
        vec![Texture::vector(1, 1, vec![texel], SpectralRange::VISIBLE).expect("texture")]
    }

    /// A map of one texel tilting the normal by `deg` towards `+u`: the
    /// tilt in radians, the tilted normal in the frame, the texture.
    fn tilted(deg: f32) -> (f32, Vec3, Vec<Texture>) {
        let tilt = deg.to_radians();
        let local = Vec3::new(tilt.sin(), 0.0, tilt.cos());
        (
            tilt,
            local,
            textures(((local + Vec3::ONE) / 2.0).to_array()),
        )
    }

    fn tables_of(textures: &[Texture]) -> MaterialTables<'_> {
        MaterialTables {
            textures,
            ..crate::shading::material::NO_TABLES
        }
    }

    /// The shadowing term of a map tilted by `tilt` (radians) for a
    /// direction `deg` degrees from `z`.
    fn shadowing(tilt: f32, deg: f32) -> f32 {
        let alpha_sq = (tilt.tan().powi(2) / 8.0).min(1.0);
        2.0 / (1.0 + (1.0 + alpha_sq * deg.to_radians().tan().powi(2)).sqrt())
    }

    /// The point on a surface with front normal `+z` and `u` along `+x`,
    /// seen from the front or from behind.
    fn point(front: bool) -> ShadingPoint {
        ShadingPoint {
            n: if front { Vec3::Z } else { -Vec3::Z },
            front,
            uv: Vec2::new(0.5, 0.5),
            dp_duv: [Vec3::new(2.0, 0.0, 0.3), Vec3::new(0.0, 1.5, 0.0)],
            hero_nm: None,
            lobe: 0.0,
        }
    }

    fn direction(rng: &mut Rng, up: bool) -> Vec3 {
        let (u, v) = (rng.next_f32(), rng.next_f32());
        let z = if up { u } else { -u };
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = core::f32::consts::TAU * v;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// The flat texel `(½, ½, 1)` changes nothing: values, pdfs and
    /// samples are the nested BSDF's bit for bit (`G = 1`, `n' = n`).
    #[test]
    fn a_flat_map_is_the_nested_bsdf() {
        let textures = textures([0.5, 0.5, 1.0]);
        let tables = tables_of(&textures);
        let wrapped = Bsdf::NormalMap(Box::new(map(MapFrame::Surface)));
        let mut rng = Rng::new(1, 2);
        let p = point(true);
        for _ in 0..200 {
            let (wo, wi) = (direction(&mut rng, true), direction(&mut rng, true));
            assert_eq!(
                wrapped.eval(&tables, &p, wo, wi),
                lambert().eval(&tables, &p, wo, wi)
            );
            let (u, v) = (rng.next_f32(), rng.next_f32());
            assert_eq!(
                wrapped.sample(&tables, &p, wo, 0.5, u, v),
                lambert().sample(&tables, &p, wo, 0.5, u, v)
            );
        }
    }

    /// A tilted map: the value is Lambert's at `n'` times `G`, zero where
    /// `wi` is on different sides of `n` and `n'`; a sample's weight is
    /// its value over its pdf. Negative control: the untilted value
    /// differs.
    #[test]
    fn a_tilted_map_shades_at_the_tilted_normal() {
        let (tilt, local, textures) = tilted(35.0);
        let tables = tables_of(&textures);
        let wrapped = Bsdf::NormalMap(Box::new(map(MapFrame::Surface)));
        let p = point(true);
        // The frame: u along +x (the tangent's part orthogonal to z).
        let tilted = local;
        let mut rng = Rng::new(7, 8);
        let (mut compared, mut differed) = (0, 0);
        for _ in 0..400 {
            let (wo, wi) = (direction(&mut rng, true), direction(&mut rng, true));
            if wo.dot(tilted) <= 0.0 {
                continue;
            }
            let eval = wrapped.eval(&tables, &p, wo, wi);
            let cos = wi.dot(tilted);
            let want = if cos > 0.0 {
                let g = shadowing(tilt, wi.z.acos().to_degrees());
                cos / core::f32::consts::PI * g
            } else {
                0.0
            };
            assert!(
                (eval.value - want).abs() < 1e-5,
                "{} against {want}",
                eval.value
            );
            compared += 1;
            let flat = lambert().eval(&tables, &p, wo, wi).value;
            if (flat - want).abs() > 1e-3 {
                differed += 1;
            }
            let (u, v) = (rng.next_f32(), rng.next_f32());
            if let Some(s) = wrapped.sample(&tables, &p, wo, 0.5, u, v) {
                let at = wrapped.eval(&tables, &p, wo, s.wi);
                assert!((s.weight - at.value / at.pdf).abs() < 1e-4 * s.weight.max(1.0));
                assert!((s.pdf - at.pdf).abs() < 1e-5);
            }
        }
        assert!(
            compared > 100 && differed > compared / 2,
            "{compared} {differed}"
        );
    }

    /// Seen from behind, the surface's frame mirrors the relief (a bump is
    /// a dent: `n'` is `−(ñ_x s + ñ_y t + ñ_z n_front)`), while inside a
    /// `twosided` the map follows the normal turned to the viewer
    /// (`ñ_x s + ñ_y t − ñ_z n_front`). The two differ in the tangential
    /// part, so a light on the tilt's side of `−z` lights them unequally.
    #[test]
    fn the_frame_behind_the_surface_depends_on_the_sides() {
        let (tilt, _, textures) = tilted(30.0);
        let tables = tables_of(&textures);
        let behind = point(false);
        let wo = -Vec3::Z;
        // Light from below, tilted towards +x by 40°.
        let wi = Vec3::new(40f32.to_radians().sin(), 0.0, -40f32.to_radians().cos());
        let value = |frame| {
            Bsdf::NormalMap(Box::new(map(frame)))
                .eval(&tables, &behind, wo, wi)
                .value
        };
        let pi = core::f32::consts::PI;
        // Surface frame: n' = (−sin, 0, −cos) turned to the viewer, 70°
        // from the light; viewer frame: (sin, 0, −cos), 10° from it.
        let surface = 70f32.to_radians().cos() / pi * shadowing(tilt, 40.0);
        let viewer = 10f32.to_radians().cos() / pi * shadowing(tilt, 40.0);
        assert!((value(MapFrame::Surface) - surface).abs() < 1e-5);
        assert!((value(MapFrame::Viewer) - viewer).abs() < 1e-5);
    }

    /// Where `wo` is behind the tilted normal the map's tangential part is
    /// flipped (`flip_invalid_normals`), so that the viewer sees the
    /// surface; without the flip the nested BSDF is evaluated from
    /// behind `n'`.
    #[test]
    fn normals_that_face_away_from_the_viewer_are_flipped() {
        let (tilt, local, textures) = tilted(30.0);
        let tables = tables_of(&textures);
        let p = point(true);
        // 70° from the zenith on the far side: 100° from the tilted normal.
        let wo = Vec3::new(-70f32.to_radians().sin(), 0.0, 70f32.to_radians().cos());
        let wi = Vec3::new(-20f32.to_radians().sin(), 0.0, 20f32.to_radians().cos());
        let flipped = Vec3::new(-tilt.sin(), 0.0, tilt.cos());
        let value = wrap_eval(&tables, (true, false), &p, [wo, wi]);
        let g = shadowing(tilt, 20.0);
        let want = wi.dot(flipped) / core::f32::consts::PI * g;
        assert!((value - want).abs() < 1e-5, "{value} against {want}");
        // Without the flip the viewer is behind n': a two-sided Lambert
        // then reflects about −n', where wi is not (zero), and so does a
        // one-sided one, which sees nothing from there; with wi behind both
        // n and n' the two-sided one reflects (about −n') and the one-sided
        // one stays black.
        assert_eq!(wrap_eval(&tables, (false, false), &p, [wo, wi]), 0.0);
        assert_eq!(wrap_eval(&tables, (false, true), &p, [wo, wi]), 0.0);
        let wi = Vec3::new(-0.5, 0.0, -0.2).normalize();
        assert!(wi.z < 0.0 && wi.dot(local) < 0.0);
        assert!(wrap_eval(&tables, (false, false), &p, [wo, wi]) > 0.0);
        assert_eq!(wrap_eval(&tables, (false, true), &p, [wo, wi]), 0.0);
    }

    /// The value of the map of `local` around Lambert with
    /// `(flip_invalid, nested_front_only)`, for `[wo, wi]`.
    fn wrap_eval(
        tables: &MaterialTables<'_>,
        (flip_invalid, nested_front_only): (bool, bool),
        p: &ShadingPoint,
        [wo, wi]: [Vec3; 2],
    ) -> f32 {
        let bsdf = Bsdf::NormalMap(Box::new(NormalMap {
            flip_invalid,
            nested_front_only,
            ..map(MapFrame::Surface)
        }));
        bsdf.eval(tables, p, wo, wi).value
    }
}
