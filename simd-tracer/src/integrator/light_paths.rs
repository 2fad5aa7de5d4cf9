//! Light paths for the caustics of dispersive glass: paths traced from the
//! lamps, through the glass, to a surface that a connection to the camera
//! sees.
//!
//! **Why.** A caustic — a lamp's light focused by glass onto a wall — is
//! reached by camera paths only by chance: a shadow ray cannot pass the
//! glass, so a path from the wall must *sample* its way through the prism
//! onto the lamp, and a small lamp behind glass is almost never hit. The
//! hybrid transport's caustic was therefore its noisiest region (and every
//! sampled transport's: `docs/results.md`, "Hybrid transport"). Traced from
//! the lamp, the same light lands on the wall with the lamp's density, and
//! a connection to the pinhole finds its pixel (pbrt-v4's and Mitsuba's
//! light tracers, `LightPathIntegrator` and `ptracer`).
//!
//! **Which paths** (`caustics.rs`, the camera side): a path is the light
//! paths' when the events from its lamp up to its first non-delta vertex
//! are all delta, at least one on a material that disperses (a refraction
//! through dispersive glass or a reflection off it), and the vertex the
//! camera sees scattered through a non-delta lobe. Camera paths leave
//! exactly those out, so the two estimators count disjoint parts of path
//! space and their sum needs no weights. The walk below follows that
//! definition: it connects to the camera at every non-delta vertex once
//! its first stretch of delta events met dispersive glass, and ends as
//! soon as a non-delta event comes without that (no path with that
//! beginning is its).
//!
//! **The estimate.** A path starts on an emissive triangle of the light
//! set, at a point or spot light, or on a sphere light (`light_start.rs`),
//! chosen with the light sampler's probability `P` renormalized over those
//! lights, on a triangle at a uniform point (pdf `1/A`; a sphere's `A` is
//! `4πρ²`), in a direction drawn by the
//! lamp's own density (a triangle's cosine, a point's sphere) or aimed at
//! the dispersive glass (`light_aim.rs`: a mixture of both, density `p_ω`
//! per steradian), carrying [`LIGHT_PATH_WAVELENGTHS`] wavelengths `λ_i`
//! drawn as the hybrid draws a split's (hero rotations, each with the
//! marginal density `p`): each starts with the weight
//! `β_i = L_e(λ_i) |cos θ| A / (P p_ω)` (at a point light of intensity
//! `I` and spot profile `f`: `I(λ_i) f(θ) / (P p_ω)`; camera paths never
//! reach a point light, so its light through the glass is the light
//! paths' alone). Up to the first
//! surface whose direction depends on wavelength the path is shared (the
//! hero's sample, each wavelength's factor); there each wavelength takes
//! its own direction and goes on alone, carrying `1/C` of the estimate
//! (`(1/C) Σ_i`, the sampled estimator over the `C` wavelengths). Each
//! bounce multiplies `β` by the BSDF sample's `f cos θ/p` at `λ`, with two
//! corrections for the adjoint BSDF (Veach's thesis, §5.2–5.3; pbrt-v4's
//! `TransportMode::Importance`): a refraction's radiance factor `1/η²` is
//! undone (`η²` for a plain dielectric), and interpolated normals weigh in
//! as `|ω_l·n_s| |ω_o·n_g| / (|ω_l·n_g| |ω_o·n_s|)`. A connection from
//! vertex `y` (light from `ω_l`, towards the camera `ω_c` at distance `d`,
//! film point `x`) adds to the film, per unit film area,
//!
//! ```text
//! C(x) = β f(ω_c, ω_l) |ω_l·n_s| |ω_c·n_g| / |ω_l·n_g| / d² · dA_px/dω
//! ```
//!
//! (`Camera::project`: `dA_px/dω = 1/(k² cos³θ)`; through a thin lens the
//! connection goes to a point of the aperture drawn uniformly, as camera
//! rays draw theirs, with the same density at that point,
//! `Camera::project_through_lens`), where the camera's
//! BSDF evaluation with the viewer at `ω_c` is the adjoint's value for
//! light from `ω_l` (generalized reciprocity: no `η` enters a connection).
//! With `M` light paths a pass, `C/(C M)` at `λ` becomes XYZ as a sampled
//! estimate does (`x̄(λ)/p(λ)/∫ȳ`); a pixel receives it weighted by its
//! filter (`render::light_film`). Russian roulette and the depth limit are
//! the camera paths': a connection from the `i`-th vertex is a path of
//! `i + 1` segments.
//!
//! **Limits.** A perspective camera only (an orthographic camera sees a
//! point along one ray, which a connection cannot find; the renderer then
//! leaves the caustics to the camera paths). Not in scenes
//! with fluorescence (a fluorescent bounce shifts a light path's
//! wavelength by a re-emission the camera side integrates). With
//! `--dispersion-paths all` the children a refraction spawns start with the
//! partition's state their own sample of that refraction gives
//! (`ChildPath::caustic_state`), so they leave out the light paths' share
//! as their parents do. The `η²` correction knows plain dielectrics; a refraction
//! through another transmitting BSDF (a principled or masked one) keeps
//! the radiance factor, which cancels over a path that leaves the medium
//! it entered, so only light connected from inside such a medium is off.

use super::light_aim::{Aimed, AimedBeam, LightAim};
use super::light_start::{LightStarts, Place, departure};
use super::packet_shading::offset;
use super::{IntegratorSettings, RR_MAX_SURVIVAL, RayCounts, SHADOW_EPSILON};
use crate::packet::{PacketHit, Ray};
use crate::sampling::disk::concentric_disk;
use crate::sampling::rng::{Purpose, Rng};
use crate::scene::camera::Projection;
use crate::scene::{Scene, WideStacks};
use crate::shading::material::{Bsdf, LaneSpectrum, ShadingPoint, direction_ior};
use crate::simd::{LANES, LaneMask};
use crate::transport::LightPathSpectra;
use core::ops::Range;
use glam::{Vec2, Vec3};
use spectral_core::sampling::SampledWavelengths;
use wide::f32x8;

/// Where a light path met the film: the film point, px, and the XYZ it
/// adds there per px² of film and per pass (the path's `C` over the pass's
/// number of light paths, module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilmHit {
    /// Column, px.
    pub x: f32,
    /// Row, px.
    pub y: f32,
    /// XYZ per px² and pass.
    pub xyz: [f32; 3],
}

/// What the light paths of a render need (module docs).
#[derive(Debug, Clone)]
pub struct LightPaths<'a> {
    scene: &'a Scene,
    spectra: LightPathSpectra,
    settings: IntegratorSettings,
    seed: u64,
    width: u32,
    height: u32,
    /// Where the paths start.
    starts: LightStarts,
    /// Where the paths' first segments go.
    aim: LightAim,
}

/// The light paths' inputs besides the scene ([`LightPaths::new`]).
#[derive(Debug, Clone)]
pub struct LightPathSettings {
    /// The transport's light-path spectra (`None`: no light paths).
    pub spectra: Option<LightPathSpectra>,
    /// Depth and roulette, the camera paths'.
    pub integrator: IntegratorSettings,
    /// The render's seed.
    pub seed: u64,
    /// The film's size, px.
    pub width: u32,
    /// The film's height, px.
    pub height: u32,
}

/// Wavelengths a light path carries until dispersion sends each its own
/// way (the hybrid's default `C`: the stretch from the lamp to the glass
/// is shared, and past it each wavelength's walk carries a quarter of the
/// estimate, so the caustic's colour is the mean of four wavelengths'
/// instead of one's).
pub const LIGHT_PATH_WAVELENGTHS: usize = 4;

/// A BSDF sample of a light path at one wavelength ([`LightPaths::scatter`]).
struct Scatter {
    to: Vec3,
    /// `f cos θ/p` of the adjoint at the wavelength.
    factor: f32,
    delta: bool,
}

/// Where a chunk of light paths leaves its film hits and ray counts, and
/// the scratch of its rays' walks.
struct Tally<'h> {
    hits: &'h mut Vec<FilmHit>,
    counts: &'h mut RayCounts,
    stacks: WideStacks,
}

/// What a connection to the camera draws besides its vertex: the
/// wavelength, the lobe number and the point of the lens's unit disk.
#[derive(Clone, Copy)]
struct Connection<'w> {
    wavelength: &'w SampledWavelengths<1>,
    u_lobe: f32,
    lens_point: (f32, f32),
}

/// One wavelength's light path past the stretch its wavelengths share.
struct Walk {
    ray: Ray,
    /// Segments up to the end of `ray`.
    depth: u32,
    beta: f32,
    /// `beta` at the lamp (Russian roulette's reference).
    start: f32,
    /// Still in the first stretch of delta events (module docs).
    first_stretch: bool,
    /// That stretch held a delta event on a material that disperses.
    dispersed: bool,
    wavelength: SampledWavelengths<1>,
    /// The walk's share of the path's estimate, `1/C`.
    share: f32,
}

/// The geometry of a light path's vertex.
struct Vertex {
    position: Vec3,
    /// Geometric normal (the triangle's front).
    normal: Vec3,
    /// Interpolated normal (the triangle's front), where smooth.
    smooth: Option<Vec3>,
    uv: Vec2,
    dp_duv: [Vec3; 2],
    front_only: bool,
}

impl Vertex {
    /// The shading point seen from `view` (module `path`'s convention:
    /// the geometric normal turned to `view`, the interpolated one where it
    /// faces `view` too).
    fn seen_from(&self, view: Vec3, lambda_nm: f32, lobe: f32) -> ShadingPoint {
        let front = self.normal.dot(view) >= 0.0;
        let side = if front { self.normal } else { -self.normal };
        let n = self
            .smooth
            .map(|s| if front { s } else { -s })
            .filter(|s| s.dot(view) > 0.0)
            .unwrap_or(side);
        ShadingPoint {
            n,
            front,
            uv: self.uv,
            dp_duv: self.dp_duv,
            hero_nm: Some(lambda_nm),
            lobe,
        }
    }

    /// Whether a viewer along `view` sees the surface scatter (a
    /// one-sided BSDF is black from behind its shading normal).
    fn scatters_towards(&self, view: Vec3) -> bool {
        !self.front_only || self.smooth.unwrap_or(self.normal).dot(view) > 0.0
    }

    /// Where a ray leaving towards `direction` starts.
    fn departure(&self, direction: Vec3) -> Vec3 {
        let side = if self.normal.dot(direction) >= 0.0 {
            self.normal
        } else {
            -self.normal
        };
        offset(self.position, side)
    }
}

/// The relative index `η` a refraction crosses at a plain dielectric,
/// seen from the side of `p` (`1` for other BSDFs, module docs).
fn refraction_eta(bsdf: &Bsdf, p: &ShadingPoint) -> f32 {
    match bsdf {
        Bsdf::Dielectric { ior, .. } => {
            let (eta, _) = direction_ior(ior, p.hero_nm);
            if p.front { eta } else { 1.0 / eta }
        }
        Bsdf::Faces(faces) => refraction_eta(&faces[usize::from(!p.front)], p),
        _ => 1.0,
    }
}

/// `|ω_l·n_s| |ω_o·n_g| / (|ω_l·n_g| |ω_o·n_s|)`: the adjoint's factor
/// for interpolated normals (module docs), 1 on flat triangles.
fn shading_normal_factor(vertex: &Vertex, shading: Vec3, from: Vec3, to: Vec3) -> f32 {
    if vertex.smooth.is_none() {
        return 1.0;
    }
    let n = vertex.normal;
    let denominator = from.dot(n).abs() * to.dot(shading).abs();
    if denominator > 0.0 {
        from.dot(shading).abs() * to.dot(n).abs() / denominator
    } else {
        0.0
    }
}

impl<'a> LightPaths<'a> {
    /// The light paths of a render, or `None` where it traces none: the
    /// transport asks for none, nothing disperses, the scene has neither an
    /// emissive triangle nor a point light or has fluorescence, or the
    /// camera is orthographic (module docs).
    pub fn new(scene: &'a Scene, settings: LightPathSettings) -> Option<Self> {
        let spectra = settings.spectra?;
        let camera = scene.camera();
        let perspective = matches!(camera.projection(), Projection::Perspective { .. });
        let disperses = scene.materials().iter().any(|m| m.bsdf.disperses());
        let usable = perspective && disperses && scene.fluorophores().is_empty();
        let starts = LightStarts::new(scene).filter(|_| usable)?;
        let aim = LightAim::new(scene);
        debug_assert!(aim.validate().is_ok(), "{:?}", aim.validate());
        Some(Self {
            scene,
            spectra,
            settings: settings.integrator,
            seed: settings.seed,
            width: settings.width,
            height: settings.height,
            starts,
            aim,
        })
    }

    /// Light paths a pass traces: one per pixel of the film (of the whole
    /// film, so that a crop traces the same paths).
    pub fn per_pass(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// Traces light paths `paths` of pass `pass`, appending their film
    /// hits to `hits` in path order and counting their rays.
    pub fn trace(
        &self,
        pass: u32,
        paths: Range<u64>,
        hits: &mut Vec<FilmHit>,
        counts: &mut RayCounts,
    ) {
        let mut tally = Tally {
            hits,
            counts,
            stacks: WideStacks::default(),
        };
        for index in paths {
            let mut rng = Rng::for_sample(self.seed, index, u64::from(pass), Purpose::LightPaths);
            self.trace_path(&mut rng, &mut tally);
        }
    }

    /// The vertex a ray hit.
    fn vertex(
        &self,
        ray: &Ray,
        t: f32,
        triangle: u32,
        instance: u32,
        (u, v): (f32, f32),
    ) -> Option<Vertex> {
        let scene = self.scene;
        let surface = scene.hit_surface(triangle, instance)?;
        let uv = scene
            .hit_uvs(triangle, instance)
            .map_or(Vec2::ZERO, |[a, b, c]| a * (1.0 - u - v) + b * u + c * v);
        let smooth = if scene.has_vertex_normals() {
            let hit = PacketHit {
                t: f32x8::splat(t),
                u: f32x8::splat(u),
                v: f32x8::splat(v),
                triangle: [triangle; LANES],
                instance: [instance; LANES],
                hit: LaneMask(1),
            };
            scene.hit_smooth_normals(&hit, LaneMask(1))[0]
        } else {
            None
        };
        let dp_duv = if scene.needs_tangent() {
            scene.hit_tangents(triangle, instance)
        } else {
            [Vec3::ZERO; 2]
        };
        Some(Vertex {
            position: ray.origin + ray.direction * t,
            normal: surface.normal,
            smooth,
            uv,
            dp_duv,
            front_only: surface.front_only,
        })
    }

    /// One light path (module docs): the stretch its wavelengths share,
    /// from the lamp to the first surface whose direction depends on
    /// wavelength, where each goes on alone ([`Self::walk`]).
    fn trace_path(&self, rng: &mut Rng, tally: &mut Tally<'_>) {
        let scene = self.scene;
        let wavelengths = self.spectra.draw::<LIGHT_PATH_WAVELENGTHS>(rng.next_f32());
        let (u_light, u, v) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
        let Some(light) = self.starts.choose(scene, u_light, u, v) else {
            return;
        };
        let u_aim = [
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
        ];
        let (origin, direction, density) = match light.place {
            Place::At { origin, emitting } => {
                let Some(Aimed { direction, pdf_sr }) = self.aim.sample(origin, &emitting, u_aim)
                else {
                    return;
                };
                let Some(origin) = self.starts.enter(origin, direction) else {
                    return;
                };
                (departure(origin, &emitting, direction), direction, pdf_sr)
            }
            Place::Beam(beam) => {
                let Some(AimedBeam {
                    origin,
                    pdf_per_area,
                }) = self.aim.sample_beam(&beam, u_aim)
                else {
                    return;
                };
                (origin, beam.travel, pdf_per_area)
            }
        };
        let emission = LaneSpectrum::scene(light.emission);
        let lambdas = *wavelengths.lambda_nm();
        let start = lambdas.map(|lambda_nm| {
            let le = self.spectra.factor(scene, &emission, lambda_nm);
            light.beta(le, direction, density)
        });
        // Outside a spot's cone (or where the lamp emits nothing at these
        // wavelengths) the path would carry nothing.
        if !start.iter().any(|&b| b > 0.0) {
            return;
        }
        let mut beta = start;
        let mut ray = Ray {
            origin,
            direction,
            t_max: f32::INFINITY,
        };
        let tables = scene.material_tables();
        for depth in 1u32.. {
            tally.counts.closest += 1;
            let Some((vertex, bsdf)) = self.hit(&ray, &mut tally.stacks) else {
                return;
            };
            let from = -ray.direction.normalize();
            if depth.saturating_add(2) > self.settings.max_depth || !vertex.scatters_towards(from) {
                return;
            }
            let uniforms = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let hero = vertex.seen_from(from, lambdas[0], uniforms[0]);
            let depends = bsdf.direction_depends_on_wavelength(&tables, &hero, from, uniforms[0]);
            let hero_scatter = if depends {
                None
            } else {
                self.scatter(&vertex, bsdf, from, lambdas[0], uniforms)
            };
            // A delta event on a material that disperses counts as
            // dispersive on the camera side (`caustics.rs`) even where its
            // direction does not depend on wavelength (a reflection off
            // the glass, a mask's pass through): the walks start there too,
            // each wavelength with its own sample of the event.
            let meets_glass = hero_scatter
                .as_ref()
                .is_some_and(|s| s.delta && bsdf.disperses());
            if depends || meets_glass {
                let share = 1.0 / LIGHT_PATH_WAVELENGTHS as f32;
                for (i, (&lambda_nm, &pdf_per_nm)) in
                    lambdas.iter().zip(wavelengths.pdf_per_nm()).enumerate()
                {
                    let Some(scattered) = self.scatter(&vertex, bsdf, from, lambda_nm, uniforms)
                    else {
                        continue;
                    };
                    // A non-delta event before any dispersion: not a light
                    // path's (module docs). A total internal reflection at
                    // this wavelength goes on undispersed.
                    if !(scattered.delta && beta[i] > 0.0 && pdf_per_nm > 0.0) {
                        continue;
                    }
                    let walk = Walk {
                        ray: Ray {
                            origin: vertex.departure(scattered.to),
                            direction: scattered.to,
                            t_max: f32::INFINITY,
                        },
                        depth: depth.saturating_add(1),
                        beta: beta[i] * scattered.factor,
                        start: start[i],
                        first_stretch: true,
                        dispersed: bsdf.disperses(),
                        wavelength: SampledWavelengths::from_parts([lambda_nm], [pdf_per_nm]),
                        share,
                    };
                    self.walk(rng, walk, tally);
                }
                return;
            }
            // The same direction at every wavelength: the hero's sample,
            // each wavelength's factor. A non-delta event before any
            // dispersion ends the path.
            let Some(scattered) = hero_scatter else {
                return;
            };
            if !scattered.delta {
                return;
            }
            beta[0] *= scattered.factor;
            for (b, &lambda_nm) in beta.iter_mut().zip(&lambdas).skip(1) {
                *b *= self
                    .scatter(&vertex, bsdf, from, lambda_nm, uniforms)
                    .map_or(0.0, |s| s.factor);
            }
            if depth >= self.settings.rr_depth {
                let survival = (beta[0] / start[0]).min(RR_MAX_SURVIVAL);
                if survival <= 0.0 || rng.next_f32() >= survival {
                    return;
                }
                beta = beta.map(|b| b / survival);
            }
            ray = Ray {
                origin: vertex.departure(scattered.to),
                direction: scattered.to,
                t_max: f32::INFINITY,
            };
        }
    }

    /// The vertex and BSDF a ray hits.
    fn hit(&self, ray: &Ray, stacks: &mut WideStacks) -> Option<(Vertex, &'a Bsdf)> {
        let scene = self.scene;
        let hit = scene.intersect_one(ray, stacks)?;
        let material = scene
            .hit_material(hit.triangle, hit.instance)
            .and_then(|m| scene.materials().get(m.index()))?;
        let vertex = self.vertex(ray, hit.t, hit.triangle, hit.instance, (hit.u, hit.v))?;
        Some((vertex, &material.bsdf))
    }

    /// The BSDF sample at `vertex` for light from `from` at `lambda_nm`
    /// with the uniforms `[lobe, u, v]`, and its factor for the adjoint
    /// (module docs).
    fn scatter(
        &self,
        vertex: &Vertex,
        bsdf: &Bsdf,
        from: Vec3,
        lambda_nm: f32,
        [u_lobe, u, v]: [f32; 3],
    ) -> Option<Scatter> {
        let scene = self.scene;
        let p = vertex.seen_from(from, lambda_nm, u_lobe);
        let sample = bsdf.sample(&scene.material_tables(), &p, from, u_lobe, u, v)?;
        let side = if vertex.normal.dot(from) >= 0.0 {
            vertex.normal
        } else {
            -vertex.normal
        };
        let to = sample.wi;
        if vertex.smooth.is_some() && to.dot(side) * to.dot(p.n) <= 0.0 {
            return None;
        }
        let refracted = to.dot(side) < 0.0;
        let mut factor = sample.weight * self.spectra.factor(scene, &sample.spectrum, lambda_nm);
        if refracted {
            let eta = refraction_eta(bsdf, &p);
            factor *= eta * eta;
        }
        factor *= shading_normal_factor(vertex, p.n, from, to);
        (factor > 0.0 && factor.is_finite()).then_some(Scatter {
            to,
            factor,
            delta: sample.pdf == 0.0,
        })
    }

    /// One wavelength's walk past the shared stretch: a connection to the
    /// camera from every vertex once dispersive glass came first
    /// (module docs).
    fn walk(&self, rng: &mut Rng, mut walk: Walk, tally: &mut Tally<'_>) {
        let scale = walk.share / self.per_pass() as f32;
        let lambda_nm = walk.wavelength.lambda_nm()[0];
        loop {
            tally.counts.closest += 1;
            let Some((vertex, bsdf)) = self.hit(&walk.ray, &mut tally.stacks) else {
                return;
            };
            let from = -walk.ray.direction.normalize();
            let uniforms = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            if walk.dispersed && walk.depth.saturating_add(1) <= self.settings.max_depth {
                // A thin lens: the connection's point on the aperture,
                // uniform as the camera rays' (pinholes draw nothing).
                let lens_point = match self.scene.camera().lens() {
                    Some(_) => concentric_disk(rng.next_f32(), rng.next_f32()),
                    None => (0.0, 0.0),
                };
                let connection = Connection {
                    wavelength: &walk.wavelength,
                    u_lobe: uniforms[0],
                    lens_point,
                };
                if let Some(hit) = self.connect(&vertex, bsdf, from, connection, walk.beta, tally) {
                    tally.hits.push(FilmHit {
                        xyz: hit.xyz.map(|c| c * scale),
                        ..hit
                    });
                }
            }
            if walk.depth.saturating_add(2) > self.settings.max_depth
                || !vertex.scatters_towards(from)
            {
                return;
            }
            let Some(scattered) = self.scatter(&vertex, bsdf, from, lambda_nm, uniforms) else {
                return;
            };
            walk.beta *= scattered.factor;
            if walk.first_stretch {
                if scattered.delta {
                    walk.dispersed |= bsdf.disperses();
                } else if walk.dispersed {
                    walk.first_stretch = false;
                } else {
                    return;
                }
            }
            if walk.depth >= self.settings.rr_depth {
                let survival = (walk.beta / walk.start).min(RR_MAX_SURVIVAL);
                if survival <= 0.0 || rng.next_f32() >= survival {
                    return;
                }
                walk.beta /= survival;
            }
            walk.depth = walk.depth.saturating_add(1);
            walk.ray = Ray {
                origin: vertex.departure(scattered.to),
                direction: scattered.to,
                t_max: f32::INFINITY,
            };
        }
    }

    /// The connection of `vertex`, lit from `from` by `beta` at the
    /// wavelength (with the bounce's lobe number), to the camera: its film
    /// hit, unscaled by the pass's number of paths (module docs).
    fn connect(
        &self,
        vertex: &Vertex,
        bsdf: &Bsdf,
        from: Vec3,
        connection: Connection<'_>,
        beta: f32,
        tally: &mut Tally<'_>,
    ) -> Option<FilmHit> {
        let Connection {
            wavelength,
            u_lobe,
            lens_point,
        } = connection;
        let scene = self.scene;
        let camera = scene.camera();
        let (film, eye) =
            camera.project_through_lens(vertex.position, lens_point, self.width, self.height)?;
        let to_camera = eye - vertex.position;
        let distance_sq = to_camera.length_squared();
        let view = to_camera / distance_sq.sqrt();
        if !vertex.scatters_towards(view) {
            return None;
        }
        let lambda_nm = wavelength.lambda_nm()[0];
        let p = vertex.seen_from(view, lambda_nm, u_lobe);
        let side = if vertex.normal.dot(view) >= 0.0 {
            vertex.normal
        } else {
            -vertex.normal
        };
        if vertex.smooth.is_some() && from.dot(side) * from.dot(p.n) <= 0.0 {
            return None;
        }
        let eval = bsdf.eval(&scene.material_tables(), &p, view, from);
        let cos_from = from.dot(vertex.normal).abs();
        if !(eval.value > 0.0 && cos_from > 0.0) {
            return None;
        }
        let value = beta
            * eval.value
            * self.spectra.factor(scene, &eval.spectrum, lambda_nm)
            * view.dot(vertex.normal).abs()
            / cos_from
            / distance_sq
            * film.density_per_sr;
        if !(value.is_finite() && value > 0.0) {
            return None;
        }
        // The shadow ray ends short of the pinhole (the lens point), or at
        // the near clip plane, in front of which the camera sees nothing.
        let origin = vertex.departure(view);
        let to_pinhole = eye - origin;
        let depth = to_pinhole.dot(camera.axes().forward);
        let near = camera.clip().map_or(0.0, |clip| clip.near);
        let t_max = (1.0 - SHADOW_EPSILON).min(1.0 - near / depth);
        tally.counts.shadow += 1;
        let ray = Ray {
            origin,
            direction: to_pinhole,
            t_max,
        };
        let blocked = scene.occluded_one(&ray, &mut tally.stacks);
        (!blocked).then(|| FilmHit {
            x: film.x,
            y: film.y,
            xyz: self.spectra.xyz(value, wavelength),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Buffer;
    use crate::scene::builtin::{SceneOptions, builtin_scene};
    use crate::transport::{HybridSettings, HybridTransport, Transport};
    use spectral_core::SpectralRange;
    use spectral_core::observer::Observer;
    use spectral_core::sampling::WavelengthStrategy;
    use spectral_core::xyz::XyzRoute;
    use std::sync::Arc;

    type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

    /// The film hits and the luminance they bring, pass by pass, of
    /// `passes` passes of `paths`.
    fn luminance_per_pass(paths: &LightPaths<'_>, passes: u32) -> (usize, Vec<f64>) {
        let mut count = 0;
        let per_pass = (0..passes)
            .map(|pass| {
                let mut hits = Vec::new();
                paths.trace(
                    pass,
                    0..paths.per_pass(),
                    &mut hits,
                    &mut RayCounts::default(),
                );
                count += hits.len();
                hits.iter().map(|h| f64::from(h.xyz[1])).sum::<f64>()
            })
            .collect();
        (count, per_pass)
    }

    fn mean_and_error(values: &[f64]) -> (f64, f64) {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    }

    /// On `prism`, whose lamp shines through a slit at the glass, light
    /// paths aimed at the glass (`light_aim.rs`) reach the film several
    /// times as often as paths leaving by the lamp's cosine, and bring the
    /// film the same light (their mean luminance a pass within 4σ of each
    /// other). Negative control: the cosine's light 20 % darker is not.
    #[test]
    fn aimed_light_paths_bring_the_cosines_light_more_often() -> TestResult {
        let range = SpectralRange::VISIBLE;
        let scene = builtin_scene("prism", range, &SceneOptions::default())?.build()?;
        let hybrid = HybridTransport::<12, 4>::new(&HybridSettings {
            range,
            buffer: Buffer::Xyz,
            route: XyzRoute::Zeroth,
            strategy: WavelengthStrategy::Hero,
            observer: &Arc::new(Observer::default()),
            density: None,
            children: false,
            light_paths: true,
        })?;
        let settings = LightPathSettings {
            spectra: hybrid.light_path_spectra(),
            integrator: IntegratorSettings::default(),
            seed: 3,
            width: 24,
            height: 24,
        };
        let aimed = LightPaths::new(&scene, settings.clone()).ok_or("no light paths")?;
        assert_eq!(aimed.aim.targets().len(), 1, "the prism's glass");
        let cosine = LightPaths {
            aim: LightAim::default(),
            ..LightPaths::new(&scene, settings).ok_or("no light paths")?
        };
        let passes = 450;
        let (aimed_hits, aimed_y) = luminance_per_pass(&aimed, passes);
        let (cosine_hits, cosine_y) = luminance_per_pass(&cosine, passes);
        let (a, a_error) = mean_and_error(&aimed_y);
        let (c, c_error) = mean_and_error(&cosine_y);
        let sigma = a_error.hypot(c_error);
        eprintln!(
            "hits {aimed_hits} against {cosine_hits}; Y {a} ± {a_error} against {c} ± {c_error}"
        );
        assert!(
            aimed_hits >= 3 * cosine_hits,
            "{aimed_hits} against {cosine_hits}"
        );
        assert!((a - c).abs() < 4.0 * sigma, "{a} against {c} ± {sigma}");
        assert!(
            (a - 0.8 * c).abs() > 4.0 * sigma,
            "negative control: {a} against 0.8 × {c}"
        );
        Ok(())
    }
}
