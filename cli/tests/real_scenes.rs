//! Scene files with the pieces of real scenes: PLY and serialized meshes,
//! analytic shapes, transforms, instances, point, spot and directional lights,
//! environment maps. The example `scenes/ply-meshes.toml` renders alike in
//! the Fourier and the sampled transports; each new key's errors are one
//! line naming the file, the line and the key.

use fspec_cli::scene_file::load_scene_file;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::shading::material::Material;
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::color::Xyz;
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use std::fs;
use std::path::{Path, PathBuf};
use test_support::ScratchDir;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// A fresh, empty directory for one test, removed when the test drops it.
fn test_dir(suite: &str, name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new(&format!("fspec-{suite}"), name)?)
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

const SIZE: (u32, u32) = (32, 24);
const BLOCK: u32 = 8;

fn render_xyz<T: Transport>(
    transport: &T,
    scene: &Scene,
    spp: u32,
    seed: u64,
) -> TestResult<Vec<Xyz>> {
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: SIZE.0,
        height: SIZE.1,
        spp,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    };
    Ok(render(transport, scene, &settings, &mut |_| true)?.xyz)
}

/// Mean ΔE2000 between `BLOCK × BLOCK` block means of two images (Lab with
/// the D65 white of Y = 1).
fn mean_delta_e(a: &[Xyz], b: &[Xyz]) -> TestResult<f64> {
    let white = spectral_core::xyz::white_point(&Builtin::lookup("d65")?)?;
    let (bw, bh) = (SIZE.0 / BLOCK, SIZE.1 / BLOCK);
    let block = |img: &[Xyz], bx: u32, by: u32| -> Xyz {
        let mut sum = [0.0; 3];
        for y in by * BLOCK..(by + 1) * BLOCK {
            for x in bx * BLOCK..(bx + 1) * BLOCK {
                let v = img[(y * SIZE.0 + x) as usize].to_array();
                for (s, v) in sum.iter_mut().zip(v) {
                    *s += v / f64::from(BLOCK * BLOCK);
                }
            }
        }
        Xyz::from_array(sum)
    };
    let mut total = 0.0;
    for by in 0..bh {
        for bx in 0..bw {
            total += delta_e2000(
                block(a, bx, by).to_lab(white),
                block(b, bx, by).to_lab(white),
            );
        }
    }
    Ok(total / f64::from(bw * bh))
}

fn load(path: &Path) -> TestResult<Scene> {
    let loaded = load_scene_file(path)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    Ok(loaded.builder.build()?)
}

/// PLY meshes with smooth normals under an HDR map: the Fourier transport
/// (N = 16) and the sampled one (4 hero wavelengths) agree within the
/// sampled renders' own noise level (ΔE2000 between two seeds); the same
/// scene with the map 10 % brighter does not (the negative control).
#[test]
fn ply_meshes_under_an_environment_map_agree_in_fourier_and_sampled() -> TestResult {
    let path = scenes_dir().join("ply-meshes.toml");
    let scene = load(&path)?;
    assert!(scene.has_vertex_normals() && scene.environment_map().is_some());
    let range = scene.range();
    let fourier = FourierTransport::<16>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    let f = render_xyz(&fourier, &scene, 128, 1)?;
    let s1 = render_xyz(&sampled, &scene, 256, 2)?;
    let s2 = render_xyz(&sampled, &scene, 256, 3)?;
    let noise = mean_delta_e(&s1, &s2)?;
    let between = mean_delta_e(&f, &s1)?;
    println!(
        "ply-meshes: mean ΔE2000 Fourier vs sampled {between:.3}, sampled vs sampled {noise:.3}"
    );
    assert!(
        between < 1.5 * noise,
        "Fourier vs sampled {between}, noise {noise}"
    );
    // Negative control.
    let text = fs::read_to_string(&path)?.replace("scale = 1.0\n", "scale = 1.1\n");
    let dir = test_dir("real-scenes", "brighter")?;
    let brighter_path = dir.join("ply-meshes.toml");
    fs::write(
        &brighter_path,
        text.replace(
            "\"assets/",
            &format!("\"{}/assets/", scenes_dir().display()),
        ),
    )?;
    let brighter = load(&brighter_path)?;
    let fb = render_xyz(&fourier, &brighter, 128, 1)?;
    let wrong = mean_delta_e(&fb, &s1)?;
    println!("brighter map: {wrong:.3}");
    assert!(
        wrong > 1.5 * noise,
        "a 10 % brighter map passes: {wrong} vs noise {noise}"
    );
    Ok(())
}

/// The material named `name` in `scene`.
fn material<'a>(scene: &'a Scene, name: &str) -> TestResult<&'a Material> {
    scene
        .materials()
        .iter()
        .find(|m| m.name == name)
        .ok_or_else(|| format!("no material `{name}`").into())
}

/// The mean luminance `Y` of an image.
fn mean_y(image: &[Xyz]) -> f64 {
    image.iter().map(|x| x.y).sum::<f64>() / image.len() as f64
}

/// A scene file in a fresh directory with the scenes' assets reachable:
/// the directory, which the test keeps until it is done with the file, and
/// the file.
fn scene(name: &str, text: &str) -> TestResult<(ScratchDir, PathBuf)> {
    let dir = test_dir("real-scenes", name)?;
    let assets = scenes_dir().join("assets");
    let text = text.replace("ASSETS", &assets.display().to_string());
    let path = dir.join(format!("{name}.toml"));
    fs::write(&path, text)?;
    Ok((dir, path))
}

const HEAD: &str = r#"
[camera]
position = [0, 0, 5]
target = [0, 0, 0]
fov_deg = 40

[materials.grey]
type = "lambert"
albedo = { constant = 0.5 }

[environment]
spectrum = "d65"
"#;

/// The error of loading a scene `HEAD + body`: one line, exit 2, naming
/// the file's line `line_of` and containing `needle`.
fn error_at(name: &str, body: &str, line_of: &str, needle: &str) -> TestResult {
    error_in(name, &format!("{HEAD}{body}"), line_of, needle)
}

/// The error of loading the scene `text` (as [`error_at`]).
fn error_in(name: &str, text: &str, line_of: &str, needle: &str) -> TestResult {
    let (_dir, path) = scene(name, text)?;
    let line = text
        .lines()
        .position(|l| l.contains(line_of))
        .map(|i| i + 1)
        .ok_or_else(|| format!("{name}: `{line_of}` not in the scene"))?;
    match load_scene_file(&path) {
        Ok(_) => Err(format!("{name}: loaded, expected an error").into()),
        Err(e) => {
            assert_eq!(e.exit_code(), 2, "{name}");
            let message = e.to_string();
            assert!(!message.contains('\n'), "{name}: not one line: {message}");
            assert!(
                message.contains(&format!("{name}.toml:{line}:")) && message.contains(needle),
                "{name}: {message} (expected line {line} and `{needle}`)"
            );
            Ok(())
        }
    }
}

#[test]
fn new_keys_refuse_bad_values_with_one_line() -> TestResult {
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            "two-files",
            "[[meshes]]\nply = \"ASSETS/teapot.ply\"\nobj = \"x.obj\"\nmaterial = \"grey\"\n",
            "[[meshes]]",
            "exactly one of",
        ),
        (
            "missing-ply",
            "[[meshes]]\nply = \"nothere.ply\"\nmaterial = \"grey\"\n",
            "nothere.ply",
            "no such file",
        ),
        (
            "broken-ply",
            "[[meshes]]\nply = \"ASSETS/../cornell/cornell.obj\"\nmaterial = \"grey\"\n",
            "cornell.obj",
            "cornell.obj:",
        ),
        (
            "ply-no-material",
            "[[meshes]]\nply = \"ASSETS/teapot.ply\"\n",
            "[[meshes]]",
            "material",
        ),
        (
            "shape-index-ply",
            "[[meshes]]\nply = \"ASSETS/teapot.ply\"\nshape_index = 1\nmaterial = \"grey\"\n",
            "shape_index",
            "serialized",
        ),
        (
            "serialized-index",
            "[[meshes]]\nserialized = \"ASSETS/teapot.serialized\"\nshape_index = 3\nmaterial = \"grey\"\n",
            "teapot.serialized",
            "shape",
        ),
        (
            "bad-step",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\ntransform = [{ shear = 1 }]\n",
            "transform",
            "unknown key",
        ),
        (
            "two-ops",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\ntransform = [{ scale = 2, translate = [0, 0, 1] }]\n",
            "transform",
            "exactly one",
        ),
        (
            "singular",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\ntransform = [{ scale = [1, 0, 1] }]\n",
            "transform",
            "singular",
        ),
        (
            "zero-axis",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\ntransform = [{ rotate = { axis = [0, 0, 0], angle_deg = 3 } }]\n",
            "transform",
            "axis",
        ),
        (
            "projective",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\ntransform = [{ matrix = [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,0] }]\n",
            "transform",
            "last row",
        ),
        (
            "unknown-shape",
            "[[shapes]]\ntype = \"torus\"\nmaterial = \"grey\"\n",
            "torus",
            "unknown shape",
        ),
        (
            "bad-radius",
            "[[shapes]]\ntype = \"sphere\"\nradius = -1\nmaterial = \"grey\"\n",
            "radius",
            "> 0",
        ),
        (
            "cube-radius",
            "[[shapes]]\ntype = \"cube\"\nradius = 1\nmaterial = \"grey\"\n",
            "radius",
            "only a sphere",
        ),
        (
            "bad-sag",
            "[[shapes]]\ntype = \"sphere\"\nsag = 2\nmaterial = \"grey\"\n",
            "sag",
            "between 0 and 1",
        ),
        (
            "no-instance",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[instances]]\nmesh = \"ghost\"\n",
            "ghost",
            "no mesh or shape named",
        ),
        (
            "twice-named",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\nname = \"a\"\n[[shapes]]\ntype = \"disk\"\nmaterial = \"grey\"\nname = \"a\"  # again\n",
            "# again",
            "exists already",
        ),
        (
            "only-without-name",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\ninstanced_only = true\n",
            "instanced_only",
            "needs `name`",
        ),
        (
            "light-type",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"laser\"\n",
            "laser",
            "unknown light type",
        ),
        (
            "spot-beam",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"spot\"\nposition = [0, 2.5, 0]\ntarget = [0.25, 0, 0]\ncutoff_deg = 30\nbeam_width_deg = 40\nintensity = \"d65\"\n",
            "beam_width_deg",
            "beam width 40°: must be at least 0 and at most the cutoff angle 30°",
        ),
        (
            "spot-cutoff",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"spot\"\nposition = [0, 2.5, 0]\ntarget = [0.25, 0, 0]\ncutoff_deg = 200\nintensity = \"d65\"\n",
            "cutoff_deg",
            "cutoff angle 200°: must be above 0 and at most 180",
        ),
        (
            "spot-both-axes",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"spot\"\nposition = [0, 2.5, 0]\ndirection = [0, -1, 0]\ntarget = [0.25, 0, 0]\nintensity = \"d65\"\n",
            "target = [0.25",
            "not both",
        ),
        (
            "spot-no-axis",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"spot\"\nposition = [0, 2.5, 0]\nintensity = \"d65\"\n",
            "[[lights]]",
            "`target = [x, y, z]`",
        ),
        (
            "spot-zero-axis",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"spot\"\nposition = [0, 2.5, 0]\ntarget = [0, 2.5, 0]\nintensity = \"d65\"\n",
            "target = [0, 2.5",
            "zero length",
        ),
        (
            "light-zero",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nirradiance = \"d65\"\n",
            "direction = ",
            "zero length",
        ),
        (
            "light-nan",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"point\"\nposition = [0, nan, 0]\nintensity = \"d65\"\n",
            "nan",
            "finite",
        ),
        (
            "light-no-spectrum",
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\n",
            "[[lights]]",
            "intensity",
        ),
    ];
    for (name, body, line, needle) in cases {
        error_at(name, body, line, needle)?;
    }
    Ok(())
}

/// A TOML spot light against the point light it widens into and against
/// Mitsuba's default beam width: a spot whose cutoff and beam are 180°
/// renders its point light bit for bit; one without `beam_width_deg`
/// renders as one with ¾ of its cutoff, bit for bit. Negative controls: a
/// 40° cone differs from the point light, a 20° beam from the default.
#[test]
fn spot_lights_widen_into_point_lights_and_take_the_default_beam() -> TestResult {
    let head = HEAD.replace("[environment]\nspectrum = \"d65\"\n", "");
    let wall =
        "[[shapes]]\ntype = \"rectangle\"\nmaterial = \"grey\"\ntransform = [{ scale = 3 }]\n";
    let light = |kind_and_cone: &str| {
        format!(
            "{head}{wall}[[lights]]\n{kind_and_cone}\nposition = [0.5, 0.5, 2]\nintensity = \"d65\"\nscale = 4\n"
        )
    };
    let image = |name: &str, text: &str| -> TestResult<Vec<Xyz>> {
        let (_dir, path) = scene(name, text)?;
        let scene = load(&path)?;
        let range = scene.range();
        let fourier = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
        render_xyz(&fourier, &scene, 4, 7)
    };
    let point = image("point", &light("type = \"point\""))?;
    let wide = image(
        "spot-180",
        &light("type = \"spot\"\ntarget = [0, 0, 0]\ncutoff_deg = 180\nbeam_width_deg = 180"),
    )?;
    assert!(point == wide, "a spot of 180° is not its point light");
    let cone = image(
        "spot-40",
        &light("type = \"spot\"\ntarget = [0, 0, 0]\ncutoff_deg = 40"),
    )?;
    assert!(cone != point, "a spot of 40° renders as a point light");
    let explicit = image(
        "spot-40-30",
        &light("type = \"spot\"\ntarget = [0, 0, 0]\ncutoff_deg = 40\nbeam_width_deg = 30"),
    )?;
    assert!(cone == explicit, "the default beam is not ¾ of the cutoff");
    let narrow = image(
        "spot-40-20",
        &light("type = \"spot\"\ntarget = [0, 0, 0]\ncutoff_deg = 40\nbeam_width_deg = 20"),
    )?;
    assert!(cone != narrow, "the beam width changes nothing");
    Ok(())
}

/// A TOML thin lens: without `focus_distance` it focuses on `target`
/// (bit for bit the image with the target's distance given), and it blurs:
/// its image differs from the pinhole's and from a lens focused elsewhere.
#[test]
fn a_toml_lens_focuses_on_the_target_by_default() -> TestResult {
    let body = "[[shapes]]\ntype = \"sphere\"\nmaterial = \"grey\"\nradius = 0.5\n[[shapes]]\ntype = \"rectangle\"\nmaterial = \"grey\"\ntransform = [{ scale = 3 }, { translate = [0, 0, -2] }]\n";
    let image = |name: &str, lens: &str| -> TestResult<Vec<Xyz>> {
        let head = HEAD.replace("fov_deg = 40\n", &format!("fov_deg = 40\n{lens}"));
        let (_dir, path) = scene(name, &format!("{head}{body}"))?;
        let scene = load(&path)?;
        let fourier =
            FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
        render_xyz(&fourier, &scene, 4, 5)
    };
    let default_focus = image("lens-default", "aperture_radius = 0.3\n")?;
    let given = image("lens-given", "aperture_radius = 0.3\nfocus_distance = 5\n")?;
    assert!(
        default_focus == given,
        "the default focus is not the target's distance"
    );
    let pinhole = image("lens-none", "")?;
    assert!(default_focus != pinhole, "the lens renders as a pinhole");
    let elsewhere = image(
        "lens-elsewhere",
        "aperture_radius = 0.3\nfocus_distance = 3\n",
    )?;
    assert!(
        default_focus != elsewhere,
        "the focus distance changes nothing"
    );
    let closed = image("lens-closed", "aperture_radius = 0\nfocus_distance = 3\n")?;
    assert!(closed == pinhole, "an aperture of 0 is not the pinhole");
    Ok(())
}

#[test]
fn lens_keys_refuse_bad_values_with_one_line() -> TestResult {
    let cube = "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n";
    for (name, lens, line_of, needle) in [
        (
            "lens-negative",
            "aperture_radius = -0.1\n",
            "aperture_radius",
            "must be a number >= 0",
        ),
        (
            "lens-nan",
            "aperture_radius = nan\n",
            "aperture_radius",
            "finite",
        ),
        (
            "lens-huge",
            "aperture_radius = 1e300\n",
            "aperture_radius",
            "too large",
        ),
        (
            "lens-focus-zero",
            "aperture_radius = 0.1\nfocus_distance = 0\n",
            "focus_distance",
            "must be a distance > 0",
        ),
        (
            "lens-focus-negative",
            "aperture_radius = 0.1\nfocus_distance = -2\n",
            "focus_distance",
            "must be a distance > 0",
        ),
    ] {
        let head = HEAD.replace("fov_deg = 40\n", &format!("fov_deg = 40\n{lens}"));
        error_in(name, &format!("{head}{cube}"), line_of, needle)?;
    }
    Ok(())
}

#[test]
fn environment_map_errors_name_the_key() -> TestResult {
    let head = HEAD.replace("[environment]\nspectrum = \"d65\"\n", "");
    let cube = "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n";
    let cases = [
        (
            "env-both",
            "[environment]\nspectrum = \"d65\"\nmap = \"ASSETS/envmap2.exr\"\n",
            "[environment]",
            "exactly one",
        ),
        (
            "env-missing",
            "[environment]\nmap = \"ASSETS/none.hdr\"\n",
            "none.hdr",
            "none.hdr",
        ),
        (
            "env-not-image",
            "[environment]\nmap = \"ASSETS/teapot.ply\"\n",
            "teapot.ply",
            "teapot.ply",
        ),
        (
            "env-scaled",
            "[environment]\nmap = \"ASSETS/envmap2.exr\"\ntransform = [{ scale = 2 }]\n",
            "transform",
            "rotation",
        ),
        (
            "env-const-transform",
            "[environment]\nspectrum = \"d65\"\ntransform = [{ rotate = { axis = [0, 1, 0], angle_deg = 9 } }]\n",
            "transform",
            "constant",
        ),
    ];
    for (name, body, line_of, needle) in cases {
        let text = format!("{head}{cube}{body}");
        let (_dir, path) = scene(name, &text)?;
        let line = text
            .lines()
            .position(|l| l.contains(line_of))
            .map(|i| i + 1)
            .ok_or("line")?;
        let message = match load_scene_file(&path) {
            Ok(_) => return Err(format!("{name} loaded").into()),
            Err(e) => e.to_string(),
        };
        assert!(
            message.contains(&format!("{name}.toml:{line}:"))
                && message.contains(needle)
                && !message.contains('\n'),
            "{name}: {message}"
        );
    }
    Ok(())
}

/// Two instances of a named mesh share one copy of it (a two-level BVH);
/// flattened (`Instancing::Flatten`), the triangle count grows by the
/// mesh's count per instance. Either way a mirrored instance still faces
/// outwards, and the instanced triangles are counted.
#[test]
fn instances_share_a_named_mesh_or_flatten_into_copies() -> TestResult {
    let body = "[[shapes]]\ntype = \"sphere\"\nmaterial = \"grey\"\nname = \"ball\"\ninstanced_only = true\n\
                [[instances]]\nmesh = \"ball\"\ntransform = [{ translate = [-2, 0, 0] }]\n\
                [[instances]]\nmesh = \"ball\"\ntransform = [{ scale = [-1, 1, 1] }, { translate = [2, 0, 0] }]\n";
    let (_dir, path) = scene("instances", &format!("{HEAD}{body}"))?;
    let outwards = |centroid: glam::Vec3, normal: glam::Vec3| {
        let centre = glam::Vec3::new(centroid.x.signum() * 2.0, 0.0, 0.0);
        assert!(
            normal.dot(centroid - centre) > 0.0,
            "inward face at {centroid}"
        );
    };

    let loaded = load_scene_file(&path)?;
    assert_eq!(loaded.instances.copies, 2);
    let scene = loaded.builder.build()?;
    let instances = scene.instances().ok_or("the ball should be instanced")?;
    assert_eq!((instances.len(), instances.meshes().len()), (2, 1));
    assert!(scene.triangles().is_empty());
    assert_eq!(
        loaded.instances.triangles as usize,
        instances.instanced_triangles()
    );
    let mesh = &instances.meshes()[0];
    for instance in 0..2u32 {
        let placement = instances.placement(instance).ok_or("placement")?;
        for (index, triangle) in (0u32..).zip(mesh.triangles()) {
            let centroid = placement
                .transform
                .point((triangle[0] + triangle[1] + triangle[2]) / 3.0);
            outwards(centroid, scene.hit_normal(index, instance).ok_or("normal")?);
        }
    }

    let mut loaded = load_scene_file(&path)?;
    loaded
        .builder
        .set_instancing(simd_tracer::scene::instances::Instancing::Flatten);
    let scene = loaded.builder.build()?;
    assert!(scene.instances().is_none());
    assert_eq!(loaded.instances.triangles as usize, scene.triangle_count());
    for (triangle, normal) in scene.triangles().iter().zip(scene.normals()) {
        outwards((triangle[0] + triangle[1] + triangle[2]) / 3.0, normal);
    }
    Ok(())
}

/// An orthographic camera from TOML and from a Mitsuba file: the
/// conformance scene `camera_orthographic.xml` (to_world scaled by 1.25 on
/// a 64 × 48 film) and its TOML twin (`view_size = 1.875`, the same film
/// plane along the smaller axis) load to the same projection, axes and
/// film plane; the Mitsuba file's rays start at its default near clip
/// (depth 0.01) and end at its far clip (10⁴), the TOML file's are not
/// clipped.
#[test]
fn orthographic_cameras_agree_between_toml_and_mitsuba_files() -> TestResult {
    use simd_tracer::scene::camera::Projection;
    let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
    let xml = load(&suite.join("scenes/camera_orthographic.xml"))?;
    let toml = load(&suite.join("twins/camera_orthographic.toml"))?;
    let (a, b) = (xml.camera(), toml.camera());
    let size = |projection| match projection {
        Projection::Orthographic { view_size } => Ok(view_size),
        other => Err(format!("not orthographic: {other:?}")),
    };
    assert!((size(a.projection())? - 1.875).abs() < 1e-5);
    assert!((size(b.projection())? - 1.875).abs() < 1e-6);
    let (axes_a, axes_b) = (a.axes(), b.axes());
    for (u, v) in [
        (axes_a.forward, axes_b.forward),
        (axes_a.right, axes_b.right),
        (axes_a.up, axes_b.up),
    ] {
        assert!((u - v).length() < 1e-5, "{u} vs {v}");
    }
    assert!((axes_a.position - axes_b.position).length() < 1e-5);
    let clip = a.clip().ok_or("no clip planes")?;
    assert!((clip.near - 0.01).abs() < 1e-7 && (clip.far / 1e4 - 1.0).abs() < 1e-6);
    assert_eq!(b.clip(), None);
    Ok(())
}

/// The conformance scene `camera_clip_shift.xml` (a principal point
/// offset, near and far clip planes, a field of view along the width) and
/// its TOML twin (`shift`, `near_clip`, `far_clip`, the field of view along
/// the smaller axis) load to the same camera.
#[test]
fn shifted_clipped_cameras_agree_between_toml_and_mitsuba_files() -> TestResult {
    use simd_tracer::scene::camera::{ClipRange, Projection};
    let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
    let xml = load(&suite.join("scenes/camera_clip_shift.xml"))?;
    let toml = load(&suite.join("twins/camera_clip_shift.toml"))?;
    let (a, b) = (xml.camera(), toml.camera());
    let fov = |projection| match projection {
        Projection::Perspective { fov_deg } => Ok(fov_deg),
        other => Err(format!("not perspective: {other:?}")),
    };
    assert!((fov(a.projection())? - fov(b.projection())?).abs() < 1e-3);
    assert_eq!(a.shift(), [0.15, -0.1]);
    assert_eq!(b.shift(), a.shift());
    let clip = |camera: &simd_tracer::scene::camera::Camera| {
        camera
            .clip()
            .map(|ClipRange { near, far }| [near, far])
            .ok_or("no clip planes")
    };
    for [near, far] in [clip(a)?, clip(b)?] {
        assert!((near - 3.4).abs() < 1e-5 && (far - 5.5).abs() < 1e-5);
    }
    let (axes_a, axes_b) = (a.axes(), b.axes());
    for (u, v) in [
        (axes_a.position, axes_b.position),
        (axes_a.forward, axes_b.forward),
        (axes_a.up, axes_b.up),
    ] {
        assert!((u - v).length() < 1e-5, "{u} vs {v}");
    }
    Ok(())
}

#[test]
fn camera_keys_refuse_bad_values_with_one_line() -> TestResult {
    let cube = "[[shapes]]\ntype = \"cube\"\nmaterial = \"grey\"\n";
    let ortho = "projection = \"orthographic\"\n";
    for (name, camera, line_of, needle) in [
        (
            "projection-unknown",
            "fov_deg = 40\nprojection = \"fisheye\"\n",
            "projection",
            "use perspective or orthographic",
        ),
        (
            "ortho-fov",
            "fov_deg = 40\nprojection = \"orthographic\"\nview_size = 2\n",
            "fov_deg",
            "does not apply to an orthographic camera",
        ),
        (
            "ortho-lens",
            &format!("{ortho}view_size = 2\naperture_radius = 0.1\n"),
            "aperture_radius",
            "does not apply to an orthographic camera",
        ),
        (
            "ortho-missing",
            ortho,
            "[camera]",
            "the camera needs `view_size`",
        ),
        (
            "ortho-zero",
            &format!("{ortho}view_size = 0\n"),
            "view_size",
            "must be finite and > 0",
        ),
        (
            "ortho-nan",
            &format!("{ortho}view_size = nan\n"),
            "view_size",
            "finite",
        ),
        (
            "perspective-size",
            "fov_deg = 40\nview_size = 2\n",
            "view_size",
            "does not apply to a perspective camera",
        ),
        (
            "shift-short",
            "fov_deg = 40\nshift = [0.1]\n",
            "shift",
            "expected an array of 2 numbers",
        ),
        (
            "shift-absurd",
            "fov_deg = 40\nshift = [20, 0]\n",
            "shift",
            "within ±16 films",
        ),
        (
            "near-negative",
            "fov_deg = 40\nnear_clip = -1\n",
            "near_clip",
            "must be a number >= 0",
        ),
        (
            "far-before-near",
            "fov_deg = 40\nnear_clip = 1\nfar_clip = 0.5\n",
            "far_clip",
            "clip planes need 0 <= near < far",
        ),
        (
            "near-huge",
            "fov_deg = 40\nnear_clip = 1e39\n",
            "near_clip",
            "too large for single precision",
        ),
        (
            "far-zero",
            "fov_deg = 40\nfar_clip = 0\n",
            "far_clip",
            "clip planes need",
        ),
    ] {
        let head = HEAD.replace("fov_deg = 40\n", camera);
        error_in(name, &format!("{head}{cube}"), line_of, needle)?;
    }
    Ok(())
}

/// Cylinders: the conformance scene `shape_cylinder.xml` (Mitsuba's
/// `cylinder` by `p0`, `p1`, `radius`) and its TOML twin (`type =
/// "cylinder"` with the same keys) tessellate into the same triangles.
#[test]
fn cylinders_agree_between_toml_and_mitsuba_files() -> TestResult {
    let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
    let xml = load(&suite.join("scenes/shape_cylinder.xml"))?;
    let toml = load(&suite.join("twins/shape_cylinder.toml"))?;
    let (a, b) = (xml.triangles(), toml.triangles());
    assert_eq!(a.len(), b.len());
    // The floor's two triangles and the two tubes.
    assert!(a.len() > 2 + 2 * 2 * 8, "{} triangles", a.len());
    for (ta, tb) in a.iter().zip(b.iter()) {
        for (p, q) in ta.iter().zip(tb.iter()) {
            assert!((*p - *q).length() < 1e-5, "{p} vs {q}");
        }
    }
    Ok(())
}

#[test]
fn cylinder_keys_refuse_bad_values_with_one_line() -> TestResult {
    for (name, shape, line_of, needle) in [
        (
            "cylinder-same-ends",
            "type = \"cylinder\"\np0 = [0, 1, 0]\np1 = [0, 1, 0]\n",
            "p1",
            "p0 and p1 must differ",
        ),
        (
            "cylinder-radius",
            "type = \"cylinder\"\nradius = 0\n",
            "radius",
            "must be > 0",
        ),
        (
            "sphere-p0",
            "type = \"sphere\"\np0 = [0, 0, 0]\n",
            "p0",
            "a cylinder `p0` and `p1`",
        ),
        (
            "cube-radius",
            "type = \"cube\"\nradius = 2\n",
            "radius",
            "those two `radius`",
        ),
        (
            "cylinder-tiny",
            "type = \"cylinder\"\nradius = 1e-50\n",
            "radius",
            "must be > 0",
        ),
        (
            "cylinder-sag",
            "type = \"cylinder\"\nsag = 2\n",
            "sag",
            "must be between 0 and 1",
        ),
    ] {
        error_at(
            name,
            &format!("[[shapes]]\n{shape}material = \"grey\"\n"),
            line_of,
            needle,
        )?;
    }
    Ok(())
}

/// Cut-outs from TOML: `opacity` wraps a material's BSDF in a mask that
/// keeps the BSDF's sides (the material itself scatters from both faces),
/// and a black card of opacity 0.3 in front of a glowing wall passes 0.7
/// of the wall's light (binomial noise of the pass-or-absorb choice; 0.3,
/// the opacity taken as the transparency, fails). `opacity_texture` reads
/// a grey PNG's values as stored.
#[test]
fn toml_opacity_cuts_a_card_out() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction, Sides};
    let text = |card: &str| {
        format!(
            r#"
[camera]
position = [0, 0, 5]
target = [0, 0, 0]
fov_deg = 8

[materials.wall]
type = "lambert"
albedo = {{ constant = 0 }}
emission = {{ constant = 2 }}

[materials.card]
type = "lambert"
albedo = {{ constant = 0 }}
sides = "front"
{card}

[[shapes]]
type = "rectangle"
material = "wall"
transform = [{{ scale = 3 }}]

[[shapes]]
type = "rectangle"
material = "card"
transform = [{{ translate = [0, 0, 1] }}]
"#
        )
    };
    let (_dir, masked_path) = scene("card-masked", &text("opacity = 0.3"))?;
    let masked = load(&masked_path)?;
    let card = material(&masked, "card")?;
    assert_eq!(card.sides, Sides::Both);
    let Bsdf::Mask(mask) = &card.bsdf else {
        return Err("the card is not masked".into());
    };
    assert_eq!(mask.opacity, Fraction::Constant(0.3));
    assert!(mask.nested_front_only, "the nested lambert keeps `front`");
    let (_dir, open_path) = scene("card-open", &text("opacity = 0"))?;
    let open = load(&open_path)?;
    let fourier = FourierTransport::<8>::new(masked.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let spp = 64;
    let fraction = mean_y(&render_xyz(&fourier, &masked, spp, 1)?)
        / mean_y(&render_xyz(&fourier, &open, spp, 1)?);
    let samples = f64::from(SIZE.0 * SIZE.1 * spp);
    let sigma = (0.7 * 0.3 / samples).sqrt();
    println!("card of opacity 0.3: passes {fraction:.5} ± {sigma:.5}");
    assert!((fraction - 0.7).abs() < 4.0 * sigma, "{fraction}");
    assert!((fraction - 0.3).abs() > 20.0 * sigma, "{fraction}");
    // A grey PNG as the opacity, values as stored: grey.png's top-left
    // texel is 230 (OBJ's convention: v = 1 is the top row).
    let grey =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance/scenes/textures/grey.png");
    let (_dir, path) = scene(
        "card-texture",
        &text(&format!(
            "opacity_texture = {{ file = \"{}\", filter = \"nearest\" }}",
            grey.display()
        )),
    )?;
    let textured = load(&path)?;
    let card = material(&textured, "card")?;
    let Bsdf::Mask(mask) = &card.bsdf else {
        return Err("the card is not masked".into());
    };
    let Fraction::Texture(id) = mask.opacity else {
        return Err("not a texture".into());
    };
    let value = textured.material_tables().textures[id.index()].scalar_at(0.125, 0.875);
    assert!((f64::from(value) - 230.0 / 255.0).abs() < 1e-6, "{value}");
    Ok(())
}

#[test]
fn opacity_keys_refuse_bad_values_with_one_line() -> TestResult {
    let colours = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/conformance/scenes/textures/colours.png")
        .display()
        .to_string();
    for (name, keys, line_of, needle) in [
        (
            "opacity-range",
            "opacity = 1.5\n".to_string(),
            "opacity",
            "must be in [0, 1]",
        ),
        (
            "opacity-type",
            "opacity = \"half\"\n".to_string(),
            "opacity",
            "number",
        ),
        (
            "opacity-both",
            format!("opacity = 0.5\nopacity_texture = \"{colours}\"\n"),
            "opacity_texture",
            "not both",
        ),
        (
            "opacity-colour",
            format!("opacity_texture = \"{colours}\"\n"),
            "opacity_texture",
            "must be a grey image",
        ),
    ] {
        let body = format!(
            "[materials.card]\ntype = \"lambert\"\nalbedo = {{ constant = 0.5 }}\n{keys}\n[[shapes]]\ntype = \"cube\"\nmaterial = \"card\"\n"
        );
        error_at(name, &body, line_of, needle)?;
    }
    Ok(())
}

/// Writes an 8-bit PNG of `size` (width, height) texels of `color`.
fn write_png(path: &Path, size: (u32, u32), color: png::ColorType, data: &[u8]) -> TestResult {
    let file = std::io::BufWriter::new(fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, size.0, size.1);
    encoder.set_color(color);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(data)?;
    writer.finish()?;
    Ok(())
}

/// The mean over the film plane of a pinhole camera of vertical field of
/// view `fov_deg` (the film's smaller side, [`SIZE`]) of `f(cos θ)`, `θ`
/// the angle of a pixel's ray to the view axis (a 400 × 400 midpoint rule):
/// the closed forms of a flat surface that fills the view head-on.
fn film_plane_mean(fov_deg: f64, f: impl Fn(f64) -> f64) -> f64 {
    let half = (fov_deg / 2.0).to_radians().tan();
    let (wide, high) = (f64::from(SIZE.0), f64::from(SIZE.1));
    let steps = 400;
    let mut sum = 0.0;
    for i in 0..steps {
        for j in 0..steps {
            let x = half * wide / high * (2.0 * (i as f64 + 0.5) / steps as f64 - 1.0);
            let y = half * (2.0 * (j as f64 + 0.5) / steps as f64 - 1.0);
            sum += f(1.0 / (1.0 + x * x + y * y).sqrt());
        }
    }
    sum / (steps * steps) as f64
}

/// A scene of a 4 × 4 floor of the material `material` (its lines of
/// `[materials.floor]`) seen from 3 units above with a field of view of
/// `fov_deg`, under a directional light `light_deg` off the zenith
/// (irradiance 3).
fn floor_under_the_sun(material: &str, fov_deg: f64, light_deg: f64) -> String {
    let (sin_l, cos_l) = light_deg.to_radians().sin_cos();
    format!(
        r#"
[camera]
position = [0, 0, 3]
target = [0, 0, 0]
fov_deg = {fov_deg}

[materials.floor]
{material}

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{{ scale = 2 }}]

[[lights]]
type = "directional"
direction = [{}, 0, {}]
irradiance = {{ constant = 3 }}
"#,
        -sin_l, -cos_l
    )
}

/// `normal_texture` on a TOML material: a Lambertian floor under a
/// directional light from 40° towards `+x`, seen from above, with a 1 × 1
/// map whose texel tilts the normal along the rectangle's `u` (`+x`): the
/// image is the unmapped one times `(l · n') G / (l · n)` (Mitsuba's
/// `normalmap`, `G` Estevez et al.'s shadowing term), computed here from
/// the texel's bytes. Noise-free (the light sample is exact), so the bound
/// is `f32` rounding; the same tilt along `−x` (the frame mirrored) is far
/// outside it. The map keeps the material's sides, in the surface's
/// frame. `bump_texture` with `bump_scale`: heights rising along `u` tilt
/// the normal the other way, by their slope over `|∂p/∂u|`.
#[test]
fn toml_normal_and_bump_textures_tilt_the_shading_normal() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, MapFrame};
    let dir = test_dir("real-scenes", "normal-texture")?;
    let tilt_deg = 25.0f64;
    let texel = [
        (255.0 * (tilt_deg.to_radians().sin() + 1.0) / 2.0).round() as u8,
        128,
        (255.0 * (tilt_deg.to_radians().cos() + 1.0) / 2.0).round() as u8,
    ];
    let png = dir.join("tilt.png");
    write_png(&png, (1, 1), png::ColorType::Rgb, &texel)?;
    let light_deg = 40.0f64;
    let (sin_l, cos_l) = light_deg.to_radians().sin_cos();
    let text = |keys: &str| {
        floor_under_the_sun(
            &format!("type = \"lambert\"\nalbedo = {{ constant = 0.5 }}\n{keys}"),
            20.0,
            light_deg,
        )
    };
    let (_d, flat_path) = scene("normal-flat", &text(""))?;
    let (_d, mapped_path) = scene(
        "normal-mapped",
        &text(&format!("normal_texture = \"{}\"", png.display())),
    )?;
    let mapped = load(&mapped_path)?;
    let floor = material(&mapped, "floor")?;
    let Bsdf::NormalMap(map) = &floor.bsdf else {
        return Err("the floor has no normal map".into());
    };
    assert_eq!(map.frame, MapFrame::Surface);
    assert!(map.flip_invalid && map.shadowing && !map.nested_front_only);
    let fourier = FourierTransport::<8>::new(mapped.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let ratio = mean_y(&render_xyz(&fourier, &mapped, 4, 1)?)
        / mean_y(&render_xyz(&fourier, &load(&flat_path)?, 4, 1)?);
    let n = texel.map(|b| 2.0 * f64::from(b) / 255.0 - 1.0);
    let length = n.iter().map(|c| c * c).sum::<f64>().sqrt();
    let [nx, _, nz] = n.map(|c| c / length);
    let alpha_sq = ((1.0 - nz * nz) / (nz * nz) / 8.0).min(1.0);
    let g = 2.0 / (1.0 + (1.0 + alpha_sq * (sin_l / cos_l).powi(2)).sqrt());
    let expected = (nx * sin_l + nz * cos_l) * g / cos_l;
    let mirrored = (-nx * sin_l + nz * cos_l) * g / cos_l;
    println!("normal texture: ratio {ratio:.6}, closed form {expected:.6}");
    assert!(
        (ratio / expected - 1.0).abs() < 1e-3,
        "{ratio} against {expected}"
    );
    assert!(
        (ratio / mirrored - 1.0).abs() > 0.1,
        "{ratio} against {mirrored}"
    );
    // `bump_texture`: heights 0 and 1 (a 2 × 1 grey PNG, clamped) looked up
    // at u' = 0.1 u + 0.5 rise by 0.1 · 2 per unit of u, times bump_scale 8:
    // g = 1.6 over |∂p/∂u| = 4 (the rectangle spans 4 units), so the normal
    // tilts away from the light by atan(0.4).
    let ramp = dir.join("ramp.png");
    write_png(&ramp, (2, 1), png::ColorType::Grayscale, &[0, 255])?;
    let (_d, bumped_path) = scene(
        "bump-mapped",
        &text(&format!(
            "bump_texture = {{ file = \"{}\", wrap = \"clamp\", uv_scale = [0.1, 0.1], uv_offset = [0.5, 0.5] }}\nbump_scale = 8",
            ramp.display()
        )),
    )?;
    let bumped = load(&bumped_path)?;
    let ratio = mean_y(&render_xyz(&fourier, &bumped, 4, 1)?)
        / mean_y(&render_xyz(&fourier, &load(&flat_path)?, 4, 1)?);
    let tilt = 0.4f64.atan();
    let alpha_sq = (tilt.tan().powi(2) / 8.0).min(1.0);
    let g = 2.0 / (1.0 + (1.0 + alpha_sq * (sin_l / cos_l).powi(2)).sqrt());
    let light = light_deg.to_radians();
    let (away, towards) = (
        (light + tilt).cos() * g / cos_l,
        (light - tilt).cos() * g / cos_l,
    );
    println!("bump texture: ratio {ratio:.6}, closed form {away:.6}");
    assert!((ratio / away - 1.0).abs() < 1e-3, "{ratio} against {away}");
    assert!(
        (ratio / towards - 1.0).abs() > 0.1,
        "{ratio} against {towards}"
    );
    // A grey image or a checkerboard is no normal map; the two maps and a
    // scale without heights are refused.
    let grey = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/conformance/scenes/textures/grey.png")
        .display()
        .to_string();
    for (name, keys, key, needle) in [
        (
            "normal-grey",
            format!("normal_texture = \"{grey}\"\n"),
            "normal_texture",
            "a normal map must be an RGB image",
        ),
        (
            "bump-and-normal",
            format!("normal_texture = \"{grey}\"\nbump_texture = \"{grey}\"\n"),
            "bump_texture",
            "not both",
        ),
        (
            "bump-scale-alone",
            "bump_scale = 2\n".to_string(),
            "bump_scale",
            "`bump_scale` needs `bump_texture`",
        ),
        (
            "normal-checkerboard",
            "normal_texture = { checkerboard = [{ constant = 0.5 }, { constant = 1 }] }\n"
                .to_string(),
            "normal_texture",
            "a normal map must be an image file",
        ),
    ] {
        let body = format!(
            "[materials.card]\ntype = \"lambert\"\nalbedo = {{ constant = 0.5 }}\n{keys}\n[[shapes]]\ntype = \"cube\"\nmaterial = \"card\"\n"
        );
        error_at(name, &body, key, needle)?;
    }
    Ok(())
}

/// A TOML conductor's `tint` multiplies its Fresnel term; a tint that is
/// not a spectrum is refused with one line.
#[test]
fn toml_conductor_tints_multiply_the_fresnel_term() -> TestResult {
    use simd_tracer::shading::material::Bsdf;
    let text = |tint: &str| {
        format!(
            "{HEAD}[materials.metal]\ntype = \"conductor\"\nmetal = \"gold\"\n{tint}\n[[shapes]]\ntype = \"cube\"\nmaterial = \"metal\"\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"grey\"\n"
        )
    };
    let fresnel = |name: &str, tint: &str| -> TestResult<Vec<f32>> {
        let (_dir, path) = scene(name, &text(tint))?;
        let built = load(&path)?;
        let id = built
            .materials()
            .iter()
            .find_map(|m| match m.bsdf {
                Bsdf::Conductor { fresnel, .. } => Some(fresnel),
                _ => None,
            })
            .ok_or("no conductor")?;
        let table = &built.material_tables().angular[id.index()];
        Ok([(1.0f32, 450.0f32), (0.5, 550.0), (0.2, 650.0)]
            .iter()
            .map(|&(cos, lambda)| table.eval(cos, lambda, 0.0))
            .collect())
    };
    let plain = fresnel("gold-plain", "")?;
    let tinted = fresnel("gold-tinted", "tint = { constant = 0.4 }")?;
    for (p, t) in plain.iter().zip(&tinted) {
        assert!((t - 0.4 * p).abs() < 1e-6, "{t} vs 0.4 × {p}");
    }
    error_in("tint-bad", &text("tint = 3"), "tint", "a spectrum")?;
    Ok(())
}

/// A TOML `principled` material against its closed form: with `ior = 1`
/// the dielectric Fresnel term is 0 (no specular lobe), with `roughness =
/// 0` there is no retro-reflection, and with `flatness = 1` the diffuse
/// lobe is Hanrahan–Krueger's `1.25 ((1 − w_o)(1 − w_i)(1/(cos θ_o +
/// cos θ_i) − 0.5) + 0.5)` times Lambert's, `w = (1 − cos)⁵`. Under a
/// directional light the floor's image mean over the Lambertian floor's is
/// that factor averaged over the camera's view directions (uniform over
/// the film plane). `flatness = 0` (Burley's diffuse lobe, here within
/// `w_i/2` of Lambert's) is far from it; textures and the index are read
/// into the BSDF as given.
#[test]
fn toml_principled_matches_its_closed_form() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction};
    let light_deg = 40.0f64;
    let fov_deg = 20.0f64;
    let cos_l = light_deg.to_radians().cos();
    let text = |material: &str| {
        floor_under_the_sun(
            &format!("{material}\nalbedo = {{ constant = 0.5 }}"),
            fov_deg,
            light_deg,
        )
    };
    let principled = "type = \"principled\"\nior = 1\nroughness = 0\nmetallic = 0";
    let (_d, flat_path) = scene(
        "principled-flat",
        &text(&format!("{principled}\nflatness = 1")),
    )?;
    let (_d, burley_path) = scene("principled-burley", &text(principled))?;
    let (_d, lambert_path) = scene("principled-lambert", &text("type = \"lambert\""))?;
    let flat = load(&flat_path)?;
    let Bsdf::Principled(p) = &material(&flat, "floor")?.bsdf else {
        return Err("the floor is not principled".into());
    };
    assert_eq!(
        (p.eta, p.flatness, p.roughness),
        (1.0, Fraction::Constant(1.0), Fraction::Constant(0.0))
    );
    let fourier = FourierTransport::<8>::new(flat.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let lambert = mean_y(&render_xyz(&fourier, &load(&lambert_path)?, 4, 1)?);
    let ratio = mean_y(&render_xyz(&fourier, &flat, 4, 1)?) / lambert;
    let burley = mean_y(&render_xyz(&fourier, &load(&burley_path)?, 4, 1)?) / lambert;
    // The closed form over the film plane.
    let w = |cos: f64| (1.0 - cos).clamp(0.0, 1.0).powi(5);
    let expected = film_plane_mean(fov_deg, |cos_o| {
        let fss = (1.0 - w(cos_o)) * (1.0 - w(cos_l));
        1.25 * (fss * (1.0 / (cos_o + cos_l) - 0.5) + 0.5)
    });
    println!(
        "principled flatness 1: ratio {ratio:.5}, closed form {expected:.5}; flatness 0: {burley:.5}"
    );
    assert!(
        (ratio / expected - 1.0).abs() < 5e-4,
        "{ratio} against {expected}"
    );
    assert!((burley - 1.0).abs() < 1e-3, "Burley's lobe {burley}");
    assert!((burley / expected - 1.0).abs() > 0.1);
    // Mistakes are one line at their key.
    let grey = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/conformance/scenes/textures/grey.png")
        .display()
        .to_string();
    let colours = grey.replace("grey.png", "colours.png");
    for (name, keys, key, needle) in [
        (
            "principled-range",
            "albedo = { constant = 0.5 }\nsheen = 1.2\n".to_string(),
            "sheen",
            "sheen 1.2: must be in [0, 1]",
        ),
        (
            "principled-both",
            format!(
                "albedo = {{ constant = 0.5 }}\nroughness = 0.3\nroughness_texture = \"{grey}\"\n"
            ),
            "roughness_texture",
            "give either `roughness` or `roughness_texture`, not both",
        ),
        (
            "principled-ior",
            "albedo = { constant = 0.5 }\nior = -1\n".to_string(),
            "ior",
            "ior -1: must be a number > 0",
        ),
        (
            "principled-textured-glass",
            format!("albedo_texture = \"{colours}\"\nspec_trans = 1\n"),
            "[materials.card]",
            "transmission with a textured base colour",
        ),
    ] {
        let body = format!(
            "[materials.card]\ntype = \"principled\"\n{keys}\n[[shapes]]\ntype = \"cube\"\nmaterial = \"card\"\n"
        );
        error_at(name, &body, key, needle)?;
    }
    Ok(())
}

/// `reflectance_tint` and `transmittance_tint` on a TOML thin-dielectric
/// pane that fills the view in front of a uniform environment: both lobes
/// see the environment, so a pixel is `L (t (1 − R') + r R')` with `R'`
/// the slab's reflectance at the pixel's angle; the image over the
/// untinted pane's (which is `L` everywhere) is that bracket's mean over
/// the film plane. The lobe is sampled, so a sample is `r L` or `t L`: the
/// bound (3·10⁻³) is over ten standard deviations of 64 spp. The tints
/// swapped are far outside it. A dispersive index with tints is a one-line
/// error.
#[test]
fn toml_dielectric_tints_multiply_their_lobes() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, thin_dielectric_reflectance};
    let fov_deg = 20.0f64;
    let (reflectance, transmittance) = (0.8, 0.5);
    let text = |tints: &str| {
        format!(
            r#"
[camera]
position = [0, 0, 3]
target = [0, 0, 0]
fov_deg = {fov_deg}

[environment]
spectrum = {{ constant = 1 }}

[materials.pane]
type = "thin-dielectric"
ior = 1.5
{tints}

[[shapes]]
type = "rectangle"
material = "pane"
transform = [{{ scale = 2 }}]
"#
        )
    };
    let tints = |r: f64, t: f64| {
        format!(
            "reflectance_tint = {{ constant = {r} }}\ntransmittance_tint = {{ constant = {t} }}"
        )
    };
    let (_d, plain_path) = scene("tints-plain", &text(""))?;
    let (_d, tinted_path) = scene("tints", &text(&tints(reflectance, transmittance)))?;
    let (_d, swapped_path) = scene("tints-swapped", &text(&tints(transmittance, reflectance)))?;
    let tinted = load(&tinted_path)?;
    let Bsdf::ThinDielectric {
        tints: Some(ids), ..
    } = &material(&tinted, "pane")?.bsdf
    else {
        return Err("the pane has no tints".into());
    };
    let spectra = tinted.spectra();
    assert_eq!(
        (
            spectra[ids.reflectance.index()].value(550.0),
            spectra[ids.transmittance.index()].value(550.0)
        ),
        (reflectance as f32, transmittance as f32)
    );
    let fourier = FourierTransport::<8>::new(tinted.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let plain = mean_y(&render_xyz(&fourier, &load(&plain_path)?, 64, 1)?);
    let ratio = mean_y(&render_xyz(&fourier, &tinted, 64, 1)?) / plain;
    let swapped = mean_y(&render_xyz(&fourier, &load(&swapped_path)?, 64, 1)?) / plain;
    let expected = film_plane_mean(fov_deg, |cos_o| {
        let r = f64::from(thin_dielectric_reflectance(cos_o as f32, 1.5));
        transmittance * (1.0 - r) + reflectance * r
    });
    println!("tinted pane: ratio {ratio:.5}, closed form {expected:.5}; swapped {swapped:.5}");
    assert!(
        (ratio / expected - 1.0).abs() < 3e-3,
        "{ratio} against {expected}"
    );
    assert!((swapped / expected - 1.0).abs() > 0.1, "swapped {swapped}");
    error_at(
        "tints-dispersive",
        "[materials.card]\ntype = \"dielectric\"\nior = { cauchy = [1.5, 0.004] }\ntransmittance_tint = { constant = 0.5 }\n[[shapes]]\ntype = \"cube\"\nmaterial = \"card\"\n",
        "[materials.card]",
        "specular tints need a constant index of refraction",
    )?;
    Ok(())
}

/// `roughness_texture` on a TOML conductor and dielectric: the surface at
/// each hit is the material with the texture's `α` there, so a one-texel
/// map read without filtering renders bit for bit what `roughness` set to
/// that texel's value renders (same seed); the value read back is the texel's, and a
/// roughness 10 % off renders a different image (the negative control).
/// Both keys at once are a one-line error.
#[test]
fn toml_roughness_texture_is_the_roughness_at_each_hit() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction};
    let dir = test_dir("real-scenes", "roughness-texture")?;
    let png = dir.join("alpha.png");
    write_png(&png, (1, 1), png::ColorType::Grayscale, &[90])?;
    let fourier_render = |scene: &Scene| -> TestResult<Vec<Xyz>> {
        let fourier =
            FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
        render_xyz(&fourier, scene, 4, 7)
    };
    for (name, keys_of_kind) in [
        (
            "conductor",
            "type = \"conductor\"\nn_const = 0.2\nk_const = 3",
        ),
        ("dielectric", "type = \"dielectric\"\nior = 1.5"),
    ] {
        let text = |keys: &str| floor_under_the_sun(&format!("{keys_of_kind}\n{keys}"), 30.0, 35.0);
        let (_d, mapped_path) = scene(
            &format!("roughness-map-{name}"),
            // Nearest: one tap of weight 1, so the texel is read exactly
            // (bilinear weights sum to 1 only within rounding).
            &text(&format!(
                "roughness_texture = {{ file = \"{}\", filter = \"nearest\" }}",
                png.display()
            )),
        )?;
        let mapped = load(&mapped_path)?;
        let Bsdf::RoughnessMap(map) = &material(&mapped, "floor")?.bsdf else {
            return Err(format!("{name}: no roughness map").into());
        };
        let Fraction::Texture(id) = map.alpha_u else {
            return Err(format!("{name}: the roughness is not a texture").into());
        };
        assert_eq!(map.alpha_v, map.alpha_u, "{name}: isotropic");
        let alpha = mapped.textures()[id.index()].scalar_at(0.5, 0.5);
        assert!(alpha > 0.05 && alpha < 0.4, "{name}: α {alpha}");
        let (_d, constant_path) = scene(
            &format!("roughness-constant-{name}"),
            // The f32 texel exactly (as an f64, which the loader reads).
            &text(&format!("roughness = {}", f64::from(alpha))),
        )?;
        let (_d, wrong_path) = scene(
            &format!("roughness-wrong-{name}"),
            &text(&format!("roughness = {}", f64::from(alpha) * 1.1)),
        )?;
        let textured = fourier_render(&mapped)?;
        let constant = fourier_render(&load(&constant_path)?)?;
        let wrong = fourier_render(&load(&wrong_path)?)?;
        let worst = textured
            .iter()
            .zip(&constant)
            .map(|(a, b)| (a.y - b.y).abs() / b.y.abs().max(1e-9))
            .fold(0.0f64, f64::max);
        assert!(
            textured == constant,
            "{name}: the one-texel map differs (α {alpha}, largest relative difference in Y {worst:e})"
        );
        assert!(textured != wrong, "{name}: α × 1.1 renders the same");
        println!("{name}: the one-texel map (α {alpha}) renders bit for bit as `roughness`");
    }
    let body = format!(
        "[materials.card]\ntype = \"conductor\"\nmetal = \"gold\"\nroughness = 0.2\nroughness_texture = \"{}\"\n[[shapes]]\ntype = \"cube\"\nmaterial = \"card\"\n",
        png.display()
    );
    error_at(
        "roughness-both",
        &body,
        "roughness_texture",
        "give either `roughness` or `roughness_texture`, not both",
    )
}

/// A `blendbsdf` of a black diffuse BSDF and a perfect mirror, weight `w`
/// on the mirror, filling the view in front of a uniform environment,
/// reflects `w` of what the mirror alone reflects: the blend is
/// `(1 − w) f_black + w f_mirror`. Each sample takes one component, so a
/// pixel's samples are 0 or the mirror's value: the image mean's relative
/// standard deviation is `√((1 − w)/(w · n))` over `n` samples, 0.5 % here,
/// and the bound is 3 %. Mitsuba 3.9.1 renders this blend darker (about
/// 0.76 w at normal incidence: its `blendbsdf` sample divides the mirror's
/// value by `w + (1 − w) p`, the diffuse density `p` mixed with the delta
/// lobe's nominal pdf of 1; docs/mitsuba-import.md, "Differences"), which
/// this bound excludes. Negative control: the blend at `w = 0.6`.
#[test]
fn a_blend_with_a_mirror_reflects_its_weight() -> TestResult {
    let text = |bsdf: &str| {
        format!(
            r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="20"/>
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{}"/><integer name="height" value="{}"/></film>
    </sensor>
    <shape type="rectangle">{bsdf}</shape>
    <emitter type="constant"><spectrum name="radiance" value="1"/></emitter>
</scene>
"#,
            SIZE.0, SIZE.1
        )
    };
    let blend = |w: f64| {
        format!(
            "<bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"{w}\"/><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf><bsdf type=\"conductor\"/></bsdf>"
        )
    };
    let dir = test_dir("real-scenes", "blend-mirror")?;
    let render_mean = |name: &str, bsdf: &str| -> TestResult<f64> {
        let path = dir.join(format!("{name}.xml"));
        fs::write(&path, text(bsdf))?;
        let scene = load(&path)?;
        let fourier =
            FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
        Ok(mean_y(&render_xyz(&fourier, &scene, 64, 1)?))
    };
    let mirror = render_mean("mirror", "<bsdf type=\"conductor\"/>")?;
    let half = render_mean("half", &blend(0.5))? / mirror;
    let more = render_mean("more", &blend(0.6))? / mirror;
    println!("blend of black and a mirror over the mirror: w 0.5: {half:.4}, w 0.6: {more:.4}");
    assert!((half / 0.5 - 1.0).abs() < 0.03, "{half}");
    assert!(
        (more / 0.5 - 1.0).abs() > 0.1,
        "the negative control: {more}"
    );
    assert!((more / 0.6 - 1.0).abs() < 0.03, "{more}");
    Ok(())
}

/// An emissive TOML `sphere` placed by rotations, translations and a
/// uniform scale is one spherical light at its centre and radius; stretched
/// into an ellipsoid, emitting from both sides (it could enclose the
/// scene) or tessellated more coarsely than the default `sag`, it stays
/// emissive triangles.
#[test]
fn emissive_toml_spheres_are_spherical_lights() -> TestResult {
    let lamp = |transform: &str, extra: &str| {
        format!(
            "{HEAD}[materials.lamp]\ntype = \"lambert\"\nalbedo = {{ constant = 0 }}\n\
             emission = \"d65\"\n{extra}[[shapes]]\ntype = \"sphere\"\nmaterial = \"lamp\"\n\
             center = [0, 1, 0]\nradius = 0.5\ntransform = {transform}\n\
             [[shapes]]\ntype = \"rectangle\"\nmaterial = \"grey\"\n"
        )
    };
    let shape = |transform: &str| lamp(transform, "");
    let similar = "[{ scale = 2 }, { rotate = { axis = [0, 0, 1], angle_deg = 90 } }, \
                   { translate = [3, 0, 0] }]";
    let (_dir, path) = scene("sphere-light", &shape(similar))?;
    let built = load(&path)?;
    let spheres = built.light_sampler().spheres();
    assert_eq!(spheres.len(), 1);
    // (0, 1, 0) × 2 turned 90° about z is (−2, 0, 0); moved to (1, 0, 0).
    assert!((spheres[0].center - glam::Vec3::new(1.0, 0.0, 0.0)).length() < 1e-5);
    assert!((spheres[0].radius - 1.0).abs() < 1e-6);
    assert!(built.lights().is_empty());
    let others = [
        ("ellipsoid-light", shape("[{ scale = [1, 2, 1] }]")),
        ("two-sided-light", lamp(similar, "two_sided = true\n")),
        (
            "coarse-light",
            lamp(similar, "").replace("radius = 0.5\n", "radius = 0.5\nsag = 0.01\n"),
        ),
    ];
    for (name, text) in others {
        let (_dir, path) = scene(name, &text)?;
        let built = load(&path)?;
        assert!(built.light_sampler().spheres().is_empty(), "{name}");
        assert!(!built.lights().is_empty(), "{name}");
    }
    Ok(())
}
