//! The BSDFs evaluated and sampled one lane at a time (the oracle of the
//! packet forms).

use super::MaterialTables;
use super::coated::{CoatLobes, CoatSpec};
use super::frame::{Frame, sample_cosine};
use super::interface::{
    Interface, eval_rough_dielectric, reflect_probability, sample_smooth_interface,
    thin_dielectric_reflectance,
};
use super::lane_spectrum::LaneSpectrum;
use super::{
    Bsdf, BsdfEval, BsdfSample, FLUORESCENT_LOBE_PROBABILITY, ShadingPoint, SpecularTints,
    angular_ref, direction_ior,
};
use crate::ids::AngularId;
use crate::shading::microfacet;
use crate::spectra::angular::Ior;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

impl Bsdf {
    /// Samples `wi` for `wo`; `u_lobe` picks the lobe, `(u, v)` the direction.
    pub fn sample(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        u: f32,
        v: f32,
    ) -> Option<BsdfSample> {
        let frame = self.frame(p);
        let wo_local = frame.to_local(wo);
        if wo_local.z <= 0.0 {
            return None;
        }
        match self {
            Self::Mask(mask) => mask.sample(tables, p, wo, u_lobe, [u, v]),
            Self::Faces(faces) => faces[usize::from(!p.front)].sample(tables, p, wo, u_lobe, u, v),
            Self::Blend(blend) => blend.sample(tables, p, wo, u_lobe, [u, v]),
            Self::NormalMap(map) => map.sample(tables, p, wo, u_lobe, [u, v]),
            Self::RoughnessMap(map) => map.sample(tables, p, wo, u_lobe, [u, v]),
            Self::Principled(principled) => principled.sample(tables, p, wo, u_lobe, [u, v]),
            Self::Lambert { albedo } => {
                let wi = sample_cosine(p.n, u, v);
                let cos = wi.dot(p.n);
                (cos > 0.0).then(|| BsdfSample {
                    wi,
                    pdf: cos * FRAC_1_PI,
                    weight: 1.0,
                    spectrum: LaneSpectrum::of(albedo.at(p.uv)),
                    terminate_secondary: false,
                    fluorophore: None,
                })
            }
            Self::Fluorescent {
                elastic,
                fluorophore,
            } => {
                // Both lobes are cosine-distributed (fluorescent.rs): the
                // lobe scales the weight, the direction is the same.
                let wi = sample_cosine(p.n, u, v);
                let cos = wi.dot(p.n);
                let fluoresce = u_lobe < FLUORESCENT_LOBE_PROBABILITY;
                let elastic_probability = 1.0 - FLUORESCENT_LOBE_PROBABILITY;
                (cos > 0.0).then(|| {
                    if fluoresce {
                        BsdfSample {
                            wi,
                            pdf: 0.0,
                            weight: 1.0 / FLUORESCENT_LOBE_PROBABILITY,
                            spectrum: LaneSpectrum::ONE,
                            terminate_secondary: false,
                            fluorophore: Some(*fluorophore),
                        }
                    } else {
                        BsdfSample {
                            wi,
                            pdf: elastic_probability * cos * FRAC_1_PI,
                            weight: 1.0 / elastic_probability,
                            spectrum: LaneSpectrum::scene(*elastic),
                            terminate_secondary: false,
                            fluorophore: None,
                        }
                    }
                })
            }
            Self::Conductor {
                fresnel,
                microfacet: model,
            } => {
                if model.is_smooth() {
                    let wi = microfacet::reflect(wo, p.n);
                    return Some(BsdfSample {
                        wi,
                        pdf: 0.0,
                        weight: 1.0,
                        spectrum: LaneSpectrum::of(angular_ref(*fresnel, wo_local.z, 0.0)),
                        terminate_secondary: false,
                        fluorophore: None,
                    });
                }
                let m = model.sample_visible_normal(wo_local, u, v);
                let wi_local = microfacet::reflect(wo_local, m);
                if wi_local.z <= 0.0 {
                    return None;
                }
                let cos_om = wo_local.dot(m);
                Some(BsdfSample {
                    wi: frame.to_world(wi_local),
                    pdf: model.visible_normal_pdf(wo_local, m) / (4.0 * cos_om),
                    weight: model.g2(wo_local, wi_local) / model.g1(wo_local),
                    spectrum: LaneSpectrum::of(angular_ref(*fresnel, cos_om, 0.0)),
                    terminate_secondary: false,
                    fluorophore: None,
                })
            }
            Self::Dielectric {
                outside,
                inside,
                ior,
                microfacet: model,
                tints,
            } => {
                let interface = dielectric_seen_from(p, [*outside, *inside], ior, *tints);
                if model.is_smooth() {
                    return sample_smooth_interface(
                        tables, p.n, wo, wo_local.z, u_lobe, &interface,
                    );
                }
                let m = model.sample_visible_normal(wo_local, u, v);
                let cos_om = wo_local.dot(m);
                if cos_om <= 0.0 {
                    return None;
                }
                let p_reflect = reflect_probability(tables, interface.r, None, cos_om, 0.0);
                let (reflected, transmitted) = interface.lobes(tables, cos_om);
                let pdf_m = model.visible_normal_pdf(wo_local, m);
                if u_lobe < p_reflect {
                    let wi_local = microfacet::reflect(wo_local, m);
                    if wi_local.z <= 0.0 {
                        return None;
                    }
                    Some(BsdfSample {
                        wi: frame.to_world(wi_local),
                        pdf: p_reflect * pdf_m / (4.0 * cos_om),
                        weight: model.g2(wo_local, wi_local) / model.g1(wo_local) / p_reflect,
                        spectrum: reflected,
                        terminate_secondary: false,
                        fluorophore: None,
                    })
                } else {
                    let eta = interface.eta;
                    let wi_local = microfacet::refract(wo_local, m, eta)?;
                    if wi_local.z >= 0.0 {
                        return None;
                    }
                    let cos_im = wi_local.dot(m);
                    let denominator = (cos_im + cos_om / eta).powi(2);
                    let p_transmit = 1.0 - p_reflect;
                    Some(BsdfSample {
                        wi: frame.to_world(wi_local),
                        pdf: p_transmit * pdf_m * cos_im.abs() / denominator,
                        weight: model.g2(wo_local, wi_local)
                            / (model.g1(wo_local) * eta * eta * p_transmit),
                        spectrum: transmitted,
                        terminate_secondary: interface.dispersed,
                        fluorophore: None,
                    })
                }
            }
            Self::Coated { .. } => self
                .coat(tables, p)
                .and_then(|coat| coat.sample(frame, wo_local, u_lobe, u, v)),
            Self::ThinDielectric { eta, tints } => {
                // Lobe by `R'`: each weight `R'/R'` or `(1 − R')/(1 − R')`
                // is exactly 1 (`u_lobe < R'` keeps the chosen lobe's
                // probability above 0), times the lobe's tint.
                let reflectance = thin_dielectric_reflectance(wo_local.z, *eta);
                let reflect = u_lobe < reflectance;
                let wi = if reflect {
                    microfacet::reflect(wo, p.n)
                } else {
                    -wo
                };
                let spectrum = tints.map_or(LaneSpectrum::ONE, |t| {
                    LaneSpectrum::scene(if reflect {
                        t.reflectance
                    } else {
                        t.transmittance
                    })
                });
                Some(BsdfSample {
                    wi,
                    pdf: 0.0,
                    weight: 1.0,
                    spectrum,
                    terminate_secondary: false,
                    fluorophore: None,
                })
            }
            Self::ThinFilm {
                front_reflectance,
                front_transmittance,
                back,
                substrate_ior,
                thickness,
            } => {
                let t = thickness
                    .and_then(|id| tables.textures.get(id.index()))
                    .map_or(0.0, |tex| tex.scalar_at(p.uv.x, p.uv.y));
                let (r, tr, eta) = match (p.front, back) {
                    (false, Some((br, bt))) => (*br, Some(*bt), 1.0 / substrate_ior),
                    _ => (*front_reflectance, *front_transmittance, *substrate_ior),
                };
                match tr {
                    Some(_) => {
                        let interface = Interface {
                            r,
                            t: tr,
                            eta,
                            dispersed: false,
                            thickness: t,
                            tints: None,
                        };
                        sample_smooth_interface(tables, p.n, wo, wo_local.z, u_lobe, &interface)
                    }
                    // Opaque base: everything not reflected is absorbed.
                    None => Some(BsdfSample {
                        wi: microfacet::reflect(wo, p.n),
                        pdf: 0.0,
                        weight: 1.0,
                        spectrum: LaneSpectrum::of(angular_ref(r, wo_local.z, t)),
                        terminate_secondary: false,
                        fluorophore: None,
                    }),
                }
            }
        }
    }

    /// Whether [`Bsdf::sample`] with lobe number `u_lobe` would take a
    /// direction that depends on the hero wavelength: the refraction (or the
    /// total internal reflection in its place) of a smooth dispersive
    /// dielectric, and any sample of a rough one (its refractions, and its
    /// light samples' evaluation, follow the hero's index). The reflection
    /// lobe of a smooth dispersive dielectric is chosen with the table's
    /// mean Fresnel `c_0(R)`, which no wavelength enters, and goes the same
    /// way for every wavelength, so a path that takes it needs no
    /// wavelengths: the hybrid transport keeps it Fourier
    /// (`transport/hybrid.rs`). Computed from the same `p`, `wo` and
    /// `u_lobe` as the sample, so the two agree lane for lane.
    pub fn direction_depends_on_wavelength(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
    ) -> bool {
        match self {
            Self::Mask(mask) => return mask.direction_depends_on_wavelength(tables, p, wo, u_lobe),
            Self::Faces(faces) => {
                return faces[usize::from(!p.front)]
                    .direction_depends_on_wavelength(tables, p, wo, u_lobe);
            }
            Self::Blend(blend) => {
                return blend.direction_depends_on_wavelength(tables, p, wo, u_lobe);
            }
            Self::NormalMap(map) => {
                return map.direction_depends_on_wavelength(tables, p, wo, u_lobe);
            }
            Self::RoughnessMap(map) => {
                return map.direction_depends_on_wavelength(tables, p, wo, u_lobe);
            }
            _ => {}
        }
        let Self::Dielectric {
            outside,
            inside,
            ior,
            microfacet: model,
            ..
        } = self
        else {
            return false;
        };
        if !ior.is_dispersive() {
            return false;
        }
        if !model.is_smooth() {
            return true;
        }
        let cos_o = Frame::new(p.n).to_local(wo).z;
        let table = if p.front { *outside } else { *inside };
        // Below the surface the sample is `None`: no direction at all.
        cos_o > 0.0 && u_lobe >= reflect_probability(tables, table, None, cos_o, 0.0)
    }

    /// `f cos θ_i` and the sampling pdf for `wi`.
    pub fn eval(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        wi: Vec3,
    ) -> BsdfEval {
        let frame = self.frame(p);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if wo_local.z <= 0.0 {
            return BsdfEval::ZERO;
        }
        match self {
            Self::Lambert { albedo } => {
                if wi_local.z <= 0.0 {
                    return BsdfEval::ZERO;
                }
                BsdfEval {
                    value: wi_local.z * FRAC_1_PI,
                    spectrum: LaneSpectrum::of(albedo.at(p.uv)),
                    pdf: wi_local.z * FRAC_1_PI,
                }
            }
            // The elastic lobe only: the fluorescent one has no light
            // sample (fluorescent.rs); its pdf is the elastic lobe's share.
            Self::Fluorescent { elastic, .. } => {
                if wi_local.z <= 0.0 {
                    return BsdfEval::ZERO;
                }
                BsdfEval {
                    value: wi_local.z * FRAC_1_PI,
                    spectrum: LaneSpectrum::scene(*elastic),
                    pdf: (1.0 - FLUORESCENT_LOBE_PROBABILITY) * wi_local.z * FRAC_1_PI,
                }
            }
            Self::Conductor {
                fresnel,
                microfacet: model,
            } => {
                if model.is_smooth() || wi_local.z <= 0.0 {
                    return BsdfEval::ZERO;
                }
                let m = (wo_local + wi_local).normalize();
                let cos_om = wo_local.dot(m);
                if cos_om.is_nan() || cos_om <= 0.0 {
                    return BsdfEval::ZERO;
                }
                let d = model.ndf(m);
                BsdfEval {
                    value: d * model.g2(wo_local, wi_local) / (4.0 * wo_local.z),
                    spectrum: LaneSpectrum::of(angular_ref(*fresnel, cos_om, 0.0)),
                    pdf: model.visible_normal_pdf(wo_local, m) / (4.0 * cos_om),
                }
            }
            Self::Dielectric {
                outside,
                inside,
                ior,
                microfacet: model,
                tints,
            } => {
                if model.is_smooth() || wi_local.z == 0.0 {
                    return BsdfEval::ZERO;
                }
                let interface = dielectric_seen_from(p, [*outside, *inside], ior, *tints);
                eval_rough_dielectric(tables, wo_local, wi_local, model, &interface)
            }
            Self::Coated { .. } => self
                .coat(tables, p)
                .map_or(BsdfEval::ZERO, |coat| coat.eval(wo_local, wi_local)),
            Self::ThinFilm { .. } | Self::ThinDielectric { .. } => BsdfEval::ZERO,
            Self::Mask(mask) => mask.eval(tables, p, wo, wi),
            Self::Faces(faces) => faces[usize::from(!p.front)].eval(tables, p, wo, wi),
            Self::Blend(blend) => blend.eval(tables, p, wo, wi),
            Self::NormalMap(map) => map.eval(tables, p, wo, wi),
            Self::RoughnessMap(map) => map.eval(tables, p, wo, wi),
            Self::Principled(principled) => principled.eval(tables, p, wo, wi),
        }
    }
}

/// The interface a dielectric of tables `[outside, inside]` shows from
/// `p`'s side: the outside's table and `η`, or the inside's and `1/η`, `η`
/// the index for directions ([`direction_ior`]: the hero wavelength's when
/// it disperses).
fn dielectric_seen_from(
    p: &ShadingPoint,
    [outside, inside]: [AngularId; 2],
    ior: &Ior,
    tints: Option<SpecularTints>,
) -> Interface {
    let (ior_value, dispersed) = direction_ior(ior, p.hero_nm);
    if p.front {
        Interface::dielectric(outside, ior_value, dispersed, tints)
    } else {
        Interface::dielectric(inside, 1.0 / ior_value, dispersed, tints)
    }
}

impl Bsdf {
    /// The local frame at `p`: along the surface's `∂p/∂u` for an
    /// anisotropic microfacet lobe (Mitsuba's shading frame), any basis
    /// around the normal otherwise.
    fn frame(&self, p: &ShadingPoint) -> Frame {
        match self {
            Self::Conductor { microfacet, .. } | Self::Dielectric { microfacet, .. }
                if microfacet.is_anisotropic() =>
            {
                Frame::along(p.n, p.dp_duv[0])
            }
            _ => Frame::new(p.n),
        }
    }

    /// The lobes of a coated BSDF at `p` (`None` for other BSDFs).
    fn coat<'a>(&'a self, tables: &MaterialTables<'_>, p: &ShadingPoint) -> Option<CoatLobes<'a>> {
        let Self::Coated {
            albedo,
            ior,
            microfacet,
            fdr_inside,
            params,
        } = self
        else {
            return None;
        };
        let spec = CoatSpec {
            albedo,
            eta: *ior,
            microfacet: *microfacet,
            fdr_inside: *fdr_inside,
            params,
            uv: p.uv,
        };
        Some(CoatLobes::new(tables, &spec))
    }
}
