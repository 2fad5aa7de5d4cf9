//! Scene files: the TOML format of `fspec render`, and bare OBJ files as
//! scenes.
//!
//! [`load_scene_file`] parses and validates a scene file, loads every file it
//! refers to (CSV spectra, OBJ/MTL meshes, textures) and returns a
//! [`SceneBuilder`] ready for `build()`, the file's render defaults and its
//! warnings. [`load_obj_scene`] makes a scene of a bare OBJ. The spectral
//! range is 360–830 nm ([`SpectralRange::VISIBLE`]). `docs/scene-format.md`
//! has the same reference with an example per section.
//!
//! # Flow and layout
//!
//! 1. `source`: the file is read within limits and kept as a `Source` (name
//!    and text); every message points at a `Spot` of it (key path and byte
//!    span), so errors read `file:line: key: message`.
//! 2. `toml_reader`: the text is parsed into a spanned TOML document and
//!    walked as `Table`s and `Item`s that know their key paths and read
//!    typed values. It knows nothing of scenes.
//! 3. `toml_scene`: the TOML front end reads the sections in a fixed order
//!    (settings, spectra, materials, environment, meshes, quads), checks
//!    keys and types, and passes plain values on.
//! 4. `construction`: the format-independent part — named spectra and
//!    materials, BSDFs, textures, OBJ meshes and quads, reference checking
//!    and the warnings — around the `SceneBuilder`.
//!
//! The seams follow what another front end needs: a Mitsuba XML importer
//! brings its own parser and reports at `Spot`s of its own source, and
//! builds the scene through `construction` without TOML types, so both
//! formats share one scene construction and one error format. The bare-OBJ
//! scene uses the mesh loading of `construction` alone.
//!
//! # Format
//!
//! ```toml
//! [render]                  # optional defaults; command-line flags override them
//! width = 512               # pixels, 1 … 65536
//! height = 512              # pixels, 1 … 65536
//! spp = 64                  # samples per pixel, >= 1
//! max_depth = 8             # longest path in segments, >= 1
//! seed = 0                  # 0 … 2^63 − 1
//!
//! [camera]                  # required: a pinhole camera
//! position = [0, 0, 3.9]
//! target = [0, 0, 0]
//! up = [0, 1, 0]            # optional, default [0, 1, 0]
//! fov_deg = 39.3077         # required; along the smaller image axis, 0 < fov < 180
//!
//! [spectra.lamp]            # named spectra: exactly one source key each
//! builtin = "fl11"          # a built-in (`fspec spectrum --list`, or blackbody-<K>)
//! # csv = "lamp.csv"        # a two-column CSV file, relative to the scene file
//! # values = [[400, 0.1], [700, 0.9]]   # inline [wavelength_nm, value] pairs
//! # blackbody_k = 3000      # Planck, normalised to 1 at its peak
//! # rgb = [0.8, 0.2, 0.1]   # sRGB reflectance in [0, 1], upsampled (Jakob–Hanika)
//! # rgb_emission = [18.4, 14.0, 6.8]   # linear-sRGB radiance (RGB illuminant, × D65)
//! # fourier = [0.5, 0.1, -0.02]        # coefficients c_0, c_1, … (1 to 32)
//! # constant = 0.5
//! scale = 10.0              # optional multiplier (>= 0) of any source
//!
//! [materials.floor]         # named materials; `type` is required
//! type = "lambert"          # lambert | conductor | dielectric | thin-dielectric | coated | thin-film | neural
//! albedo = "colorchecker-19"
//! emission = "lamp"         # optional, any type
//! emission_scale = 1.0      # optional, >= 0 (needs `emission`)
//! two_sided = false         # optional: emit from both faces
//! sides = "both"            # optional: "front" = black from behind (non-transmitting BSDFs)
//!
//! [[meshes]]                # zero or more OBJ files
//! obj = "cornell/cornell.obj"            # relative to the scene file
//! materials = { light = "lamp_quad" }    # optional: MTL name -> scene material
//! # material = "floor"      # optional instead: one scene material for every face
//!
//! [[quads]]                 # zero or more quads (two triangles)
//! vertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]   # counter-clockwise seen from the front
//! material = "floor"
//!
//! [environment]             # optional constant radiance from every direction
//! spectrum = "d65"
//! scale = 0.5               # optional, >= 0
//! ```
//!
//! Numbers may be written as integers or floats; NaN and infinities are
//! refused everywhere. Unknown keys are errors.
//!
//! ## Spectrum references
//!
//! Wherever a spectrum is expected (`albedo`, `emission`, `n`, `k`,
//! `spectrum`), give a string — a name from `[spectra]`, else a built-in name
//! (case-insensitive) — or an inline table with one source key as in
//! `[spectra]` (and optionally `scale`), e.g. `albedo = { rgb = [0.8, 0.8, 0.8] }`.
//! A `[spectra]` name shadows the built-in of the same name (with a
//! warning). `scale`, `emission_scale` and the environment's `scale` multiply
//! the spectrum: built-in tables, CSV and inline values are scaled
//! sample by sample, `rgb` reflectances are sampled every 1 nm over the range
//! and scaled, the other sources scale their parameters (blackbody scale,
//! RGB radiance, Fourier coefficients, constant).
//!
//! ## Materials
//!
//! | type | keys (besides `type`, `emission`, `emission_scale`, `two_sided`, `sides`) | BSDF |
//! | --- | --- | --- |
//! | `lambert` | `albedo` or `albedo_texture` | Lambertian |
//! | `conductor` | `metal` (`gold`, `silver`, `copper`, `aluminium`), or `n` and `k` (spectra), or `n_const` and `k_const` (numbers); `roughness` | GGX conductor, Fresnel from the complex index (outside medium n = 1) |
//! | `dielectric` | `ior`; `roughness` | smooth or GGX dielectric interface (inside relative to outside) |
//! | `thin-dielectric` | `ior` (a number > 0, the slab relative to the outside) | thin slab: reflects `R' = 2R/(1 + R)`, passes the rest straight through (Mitsuba's `thindielectric`) |
//! | `coated` | `albedo` or `albedo_texture`; `ior` (a number); `roughness` | dielectric coat over a Lambertian base |
//! | `thin-film` | `layers`, `substrate`, `base`; `thickness_texture` with `thickness_range_nm` | smooth thin-film stack |
//! | `neural` | `network`; `roughness`; for two-input networks `thickness_nm`, or `thickness_texture` with `thickness_range_nm` | GGX reflector whose Fresnel reflectance is a trained sine network (paper §4) |
//! | `fluorescent` | `albedo`; `fluorophore` (a built-in name or an inline table); `absorptance`, `quantum_yield` | fluorescent layer over a Lambertian base |
//!
//! * `roughness`: GGX `α`, a number `>= 0`, default 0 (smooth; below 10⁻³
//!   the surface is a mirror).
//! * `ior`: a number `>= 1`, `"bk7"` (Schott N-BK7, Sellmeier),
//!   `{ cauchy = [a, b_um2] }` (`n = a + b/λ²`, λ in µm) or
//!   `{ sellmeier_b = [B1, B2, B3], sellmeier_c = [C1, C2, C3] }` (C in µm²);
//!   it must stay `>= 1` over the whole range. A coat takes a number only.
//! * `albedo` values above 1 are accepted with a warning (they add energy);
//!   `albedo_texture` is a PNG or OpenEXR file relative to the scene file:
//!   RGB/grey (PNG sRGB-decoded, EXR linear) or an EXR with channels
//!   `F0 … F{N−1}` (Fourier coefficients per texel) — see
//!   [`crate::texture_file`]. Meshes supply the texture coordinates (`vt`);
//!   quads map their vertices to (0, 0), (1, 0), (1, 1), (0, 1).
//! * `albedo_texture` and `thickness_texture` may also be a table:
//!   `{ file = "a.png", wrap = "mirror", filter = "nearest", uv_scale = [4, 4],
//!   uv_offset = [0.5, 0], uv_rotation_deg = 30 }` or
//!   `{ checkerboard = [<spectrum ref>, <spectrum ref>], uv_scale = [8, 8] }`
//!   (exactly one of `file` and `checkerboard`; `wrap` is `repeat`, the
//!   default, `mirror` or `clamp`, `filter` `bilinear`, the default, or
//!   `nearest`, both for images only; the coordinates are scaled, then
//!   rotated counter-clockwise, then offset:
//!   `uv' = R(θ) · (S · uv) + offset`). The checkerboard is Mitsuba 3's:
//!   the first spectrum where the halves of `u'` and `v'` agree. Semantics
//!   in `simd_tracer::spectra::texture`.
//! * `thin-film`: `layers = [{ ior = 2.0, k = 0.0, thickness_nm = 400 }, …]`
//!   (1 to 16 layers, the first on the incident side; `ior` as above, `k >= 0`
//!   default 0, `thickness_nm >= 0`), `substrate = { ior = 1.5, k = 0.0 }`
//!   (required), `base = "opaque"` (reflection only, the default) or
//!   `"transparent"` (reflection and refraction into the substrate, whose `k`
//!   must then be 0). With `thickness_texture = "t.png"` and
//!   `thickness_range_nm = [100, 800]` (both or neither) layer 0's thickness
//!   comes from a grey texture, 0 … 1 mapping linearly into the range (layer
//!   0's `thickness_nm` may then be left out).
//! * `neural`: `network = "film.nn"` is a file written by `fspec train`
//!   (`spectral_core::neural` byte format; 1 or 2 inputs, 10 or 16 hidden,
//!   10, 12 or 16 coefficients, spectral range 360–830 nm). Its
//!   coefficients are the Fresnel reflectance at `cos θ`: a mirror, or a
//!   GGX reflector with `roughness`; the rest of the light is absorbed (a
//!   film on a black base). A two-input network (`--param thickness:…`)
//!   takes `thickness_nm = 400`, or a grey `thickness_texture` with
//!   `thickness_range_nm` (smooth only).
//!
//! ## Meshes
//!
//! OBJ faces are triangulated; `vt` coordinates are kept. Faces take the
//! scene material `material` if it is given; otherwise their MTL material,
//! mapped through `materials` when the name is listed there, else converted
//! by `simd_tracer::scene::obj::mtl_material` (the one MTL conversion, shared with
//! bare OBJs and the built-in scenes): `Kd` a linear-sRGB reflectance
//! (default 0.5 grey) and `Ke`, when positive, a linear-sRGB radiance
//! upsampled as an illuminant (× D65). Faces without an MTL material are
//! 0.5 grey. `material` and `materials` exclude each other. A `materials`
//! name that the MTL does not define is a warning.
//!
//! # Errors and warnings
//!
//! Every error is one line, [`CliError`] with exit code 2. Errors that come
//! from the TOML name the file, the line and the key:
//! `scenes/x.toml:12: materials.gold.roughness: must be a number >= 0`; a
//! missing key names the line of its table (line 1 for the top level);
//! errors of referenced files follow the key with that file's own message
//! (`…: meshes[0].obj: scenes/box.obj: face parse error (OBJ/MTL syntax)`).
//!
//! Warnings (in [`LoadedScene::warnings`], same prefix): `[spectra]` names
//! that shadow built-ins, spectra and materials defined but never used,
//! albedos above 1, degenerate triangles (zero area or non-finite; skipped,
//! with their count per mesh), unknown MTL names in `materials`, and a scene
//! without any light.

mod construction;
mod mitsuba;
mod source;
mod toml_reader;
mod toml_scene;

use crate::error::CliError;
pub use construction::InstanceCount;
use construction::{FaceMaterials, Mesher, Placement, load_obj_geometry};
use glam::Vec3;
pub use mitsuba::{MitsubaOptions, fuzz_scene_xml, load_mitsuba_scene};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{SceneBuilder, SceneError};
use simd_tracer::spectra::SpectrumSource;
use source::{Source, read_text};
use spectral_core::SpectralRange;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use toml_scene::load_toml_scene;

/// Largest scene file accepted, bytes (16 MiB).
pub const MAX_SCENE_FILE_BYTES: u64 = 16 * 1024 * 1024;
/// Field of view of the camera of [`load_obj_scene`], degrees.
pub const OBJ_SCENE_FOV_DEG: f32 = 40.0;
/// Largest image edge accepted in `[render]`, pixels.
pub const MAX_IMAGE_EDGE: i64 = 65536;

/// A loaded scene, not yet built.
#[derive(Debug)]
pub struct LoadedScene {
    /// Everything the file describes; call `.build()`.
    pub builder: SceneBuilder,
    /// The file's `[render]` defaults.
    pub render: RenderDefaults,
    /// Warnings, one line each (`file:line: key: message`).
    pub warnings: Vec<String>,
    /// Instances placed (kept as instances or flattened at build).
    pub instances: InstanceCount,
}

/// Render settings a scene file may preset (command-line flags override).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RenderDefaults {
    /// What the channels measure (`observer` or `sensor` in `[render]`).
    pub observer: Option<crate::sensor_file::ObserverChoice>,
    /// Image width, pixels.
    pub width: Option<u32>,
    /// Image height, pixels.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Longest path in segments.
    pub max_depth: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Camera rays do not see emitters.
    pub hide_emitters: Option<bool>,
    /// How samples reach pixels (TOML scenes only: Mitsuba's files keep
    /// the default).
    pub film: Option<simd_tracer::film::FilmMode>,
    /// Independent or Sobol numbers (TOML scenes only).
    pub sampler: Option<simd_tracer::sampling::sampler::SamplerKind>,
    /// Depth from which Russian roulette may end paths.
    pub rr_depth: Option<u32>,
    /// Pixel reconstruction filter.
    pub filter: Option<FilterChoice>,
    /// The part of the film rendered (Mitsuba's crop window).
    pub crop: Option<CropWindow>,
    /// What a path carries, one of [`TRANSPORT_NAMES`] (TOML scenes only).
    pub transport: Option<String>,
    /// How sampled wavelengths are drawn, one of [`SAMPLING_NAMES`] (TOML
    /// scenes only).
    pub sampling: Option<String>,
    /// Fourier coefficients, a number or `auto` (TOML scenes only).
    pub coeffs: Option<crate::coefficient_choice::CoeffsChoice>,
}

/// The transports a TOML scene's `[render] transport` may name: those of
/// `fspec render --transport`.
pub const TRANSPORT_NAMES: [&str; 4] = ["fourier", "sampled", "cv", "hybrid"];

/// The wavelength samplings a TOML scene's `[render] sampling` may name:
/// those of `fspec render --sampling`.
pub const SAMPLING_NAMES: [&str; 5] = ["uniform", "stratified", "hero", "visible", "lights"];

/// A pixel reconstruction filter named by a scene file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FilterChoice {
    /// One pixel wide.
    Box,
    /// A tent of this radius, px.
    Tent {
        /// Radius, px.
        radius_px: f32,
    },
    /// A truncated Gaussian of this standard deviation, px.
    Gaussian {
        /// Standard deviation, px.
        stddev_px: f32,
    },
    /// A Mitchell–Netravali cubic of parameters `B` and `C`.
    Cubic {
        /// `B`.
        b: f32,
        /// `C`.
        c: f32,
    },
    /// A Lanczos sinc of this many lobes.
    Lanczos {
        /// Lobes (the radius, px).
        lobes: u32,
    },
}

/// The filters a TOML scene's `[render] filter` and `fspec render
/// --filter` may name, each with Mitsuba's default parameters.
pub const FILTER_NAMES: [&str; 6] = [
    "box",
    "tent",
    "gaussian",
    "mitchell",
    "catmull-rom",
    "lanczos",
];

impl FilterChoice {
    /// The filter of one of [`FILTER_NAMES`] with Mitsuba's defaults (tent
    /// radius 1 px, Gaussian σ 0.5 px, Mitchell `B = C = 1/3`, Catmull–Rom
    /// `B = 0`, `C = 1/2`, Lanczos 3 lobes); `None` for another name.
    pub fn named(name: &str) -> Option<Self> {
        use simd_tracer::film::filter::{
            CATMULL_ROM_B_C, GAUSSIAN_SIGMA_PX, LANCZOS_LOBES, MITCHELL_B_C, TENT_RADIUS_PX,
        };
        let cubic = |[b, c]: [f32; 2]| Self::Cubic { b, c };
        match name {
            "box" => Some(Self::Box),
            "tent" => Some(Self::Tent {
                radius_px: TENT_RADIUS_PX,
            }),
            "gaussian" => Some(Self::Gaussian {
                stddev_px: GAUSSIAN_SIGMA_PX,
            }),
            "mitchell" => Some(cubic(MITCHELL_B_C)),
            "catmull-rom" => Some(cubic(CATMULL_ROM_B_C)),
            "lanczos" => Some(Self::Lanczos {
                lobes: LANCZOS_LOBES,
            }),
            _ => None,
        }
    }
}

/// A rectangle of the film, pixels from its top-left corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CropWindow {
    /// First column.
    pub x: u32,
    /// First row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

/// Parses and validates a scene file (module docs; a `.xml` file is read
/// as a Mitsuba 3 scene with default [`MitsubaOptions`]); every reference
/// is checked; textures and OBJ files are loaded. The builder is returned
/// un-built (call `.build()`); the range is 360–830 nm.
pub fn load_scene_file(path: &Path) -> Result<LoadedScene, CliError> {
    let xml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    if xml {
        return load_mitsuba_scene(path, &MitsubaOptions::default());
    }
    let text = read_text(path, MAX_SCENE_FILE_BYTES)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_scene_text(&path.display().to_string(), &text, Some(dir))
}

/// [`load_scene_file`] on the text of a file named `file` (for messages),
/// with file references relative to `dir`, or refused when `dir` is `None`.
fn load_scene_text(file: &str, text: &str, dir: Option<PathBuf>) -> Result<LoadedScene, CliError> {
    let src = Source {
        file: file.to_string(),
        text,
    };
    load_toml_scene(src, dir)
}

/// Fuzz entry point: arbitrary bytes as a scene file, with every file
/// reference (`csv`, `obj`, textures) refused so that nothing is read from
/// disk. Checks that nothing panics, that every error and warning is one
/// line (module docs), and that a scene the loader accepts either builds
/// into a scene with a valid BVH and finite normals or gives `Err`.
pub fn fuzz_scene_toml(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let loaded = match load_scene_text("fuzz.toml", text, None) {
        Ok(loaded) => loaded,
        Err(e) => {
            let message = e.to_string();
            assert!(!message.contains('\n'), "multi-line error: {message:?}");
            return;
        }
    };
    for warning in &loaded.warnings {
        assert!(!warning.contains('\n'), "multi-line warning: {warning:?}");
    }
    match loaded.builder.build() {
        Ok(scene) => {
            assert!(
                scene.bvh().validate(&scene.triangles()).is_ok(),
                "{:?}",
                scene.bvh().validate(&scene.triangles())
            );
            assert!(scene.normals().all(|n| n.is_finite()));
        }
        // A tree that fails its own validation is a bug, not bad input.
        Err(SceneError::Bvh(message)) => panic!("BVH validation failed: {message}"),
        Err(_) => {}
    }
}

/// A bare OBJ as a scene (module docs of `simd_tracer::scene::obj` for the MTL
/// mapping): a camera with a 40° field of view on the +z side of the mesh's
/// bounding box, looking at its centre from the distance at which the box's
/// bounding sphere fits the view, and — if no face emits — a constant white
/// environment (D65 with Y = 1).
pub fn load_obj_scene(path: &Path) -> Result<LoadedScene, CliError> {
    let range = SpectralRange::VISIBLE;
    let mut builder = SceneBuilder::new(range);
    let mut mesher = Mesher::default();
    let info = load_obj_geometry(
        &mut builder,
        &mut mesher,
        path,
        &FaceMaterials::Mapped(HashMap::new()),
        &Placement::default(),
    )
    .map_err(CliError::input)?;
    let shown = path.display();
    let mut warnings = Vec::new();
    if info.degenerate > 0 {
        warnings.push(format!(
            "{shown}: {} degenerate triangle(s) (zero area or non-finite) are skipped",
            info.degenerate
        ));
    }
    let Some((lo, hi)) = mesher.bounds.filter(|_| mesher.triangles > 0) else {
        return Err(CliError::input(format!(
            "{shown}: the OBJ has no usable triangle"
        )));
    };
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-6);
    let half_fov = 0.5 * OBJ_SCENE_FOV_DEG.to_radians();
    let distance = radius / half_fov.sin();
    let camera = Camera::look_at(
        centre + Vec3::new(0.0, 0.0, distance),
        centre,
        Vec3::Y,
        OBJ_SCENE_FOV_DEG,
    )
    .map_err(|e| CliError::input(format!("{shown}: cannot frame the mesh: {e}")))?;
    builder.set_camera(camera);
    if mesher.emissive_triangles == 0 {
        let white = builder
            .add_spectrum("white environment", SpectrumSource::RgbIlluminant([1.0; 3]))
            .map_err(|e| CliError::input(format!("{shown}: {e}")))?;
        builder.set_environment(Some(white));
    }
    Ok(LoadedScene {
        builder,
        render: RenderDefaults::default(),
        warnings,
        instances: InstanceCount::default(),
    })
}

impl From<CropWindow> for simd_tracer::render::PixelWindow {
    fn from(c: CropWindow) -> Self {
        Self {
            x: c.x,
            y: c.y,
            width: c.width,
            height: c.height,
        }
    }
}
