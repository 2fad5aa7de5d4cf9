"""fspec.render against the `fspec` command line's EXR output and its
error messages."""

import math
import signal
import subprocess
import sys
import time

import numpy as np
import OpenEXR
import pytest

import fspec
from conftest import run_cli

SMALL = {"spp": 4, "width": 24, "height": 20, "seed": 5}


def cli_flags(settings):
    return [f"--{key.replace('_', '-')}={value}" for key, value in settings.items()]


def read_exr(path, channels):
    """The named channels of an EXR as an (H, W, len(channels)) float32 array."""
    with OpenEXR.File(str(path), separate_channels=True) as exr:
        planes = exr.channels()
        return np.stack([planes[name].pixels.astype(np.float32) for name in channels], axis=-1)


def cli_render(fspec_cli, tmp_path, scene, settings, extra=()):
    out = tmp_path / "cli.exr"
    done = run_cli(fspec_cli, "render", scene, *cli_flags(settings), *extra, "--quiet", f"--out={out}")
    assert done.returncode == 0, done.stderr
    return out


def test_render_returns_a_float32_image_of_the_requested_size():
    image = fspec.render("cornell", **SMALL)
    assert image.dtype == np.float32 and image.shape == (20, 24, 3)
    assert np.isfinite(image).all() and image.mean() > 0.01


@pytest.mark.parametrize(
    "scene, settings",
    [
        ("cornell", {}),
        ("cornell", {"transport": "sampled", "wavelengths": 8}),
        ("cornell", {"transport": "cv", "wavelengths": 4, "coeffs": 8}),
        ("materials", {"coeffs": 16, "to_color": "mese"}),
    ],
)
def test_render_equals_the_cli_exr(fspec_cli, tmp_path, scene, settings):
    settings = {**SMALL, **settings}
    image = fspec.render(scene, **settings)
    reference = read_exr(cli_render(fspec_cli, tmp_path, scene, settings), "RGB")
    # One program, one seed: the same pixels (float32 of the same doubles).
    # The tolerance only allows for a last-bit difference.
    np.testing.assert_allclose(image, reference, rtol=1e-6, atol=1e-7)


def test_render_against_the_cli_negative_control(fspec_cli, tmp_path):
    image = fspec.render("cornell", **{**SMALL, "seed": 6})
    reference = read_exr(cli_render(fspec_cli, tmp_path, "cornell", SMALL), "RGB")
    assert np.max(np.abs(image - reference)) > 1e-3


def test_xyz_image_equals_the_cli_xyz_channels(fspec_cli, tmp_path):
    xyz = fspec.render("cornell", color="xyz", **SMALL)
    reference = read_exr(cli_render(fspec_cli, tmp_path, "cornell", SMALL, ["--exr-xyz"]), "XYZ")
    np.testing.assert_allclose(xyz, reference, rtol=1e-6, atol=1e-7)
    rgb = fspec.render("cornell", **SMALL)
    np.testing.assert_allclose(fspec.xyz_to_linear_srgb(xyz), rgb, rtol=1e-5, atol=1e-6)


def test_coefficient_planes_convert_to_the_image():
    rendered = fspec.render("cornell", coefficients=True, coeffs=8, color="xyz", **SMALL)
    assert rendered.coefficients.shape == (20, 24, 8) and rendered.coefficients.dtype == np.float32
    assert rendered.range_nm == fspec.VISIBLE_RANGE_NM and rendered.passes == SMALL["spp"]
    # The film converts its mean coefficients by the zeroth route; the planes
    # are those coefficients in float32.
    xyz = fspec.to_xyz(rendered.coefficients.astype(np.float64), range_nm=rendered.range_nm)
    np.testing.assert_allclose(xyz, rendered.image, rtol=1e-5, atol=1e-6)


def test_coefficient_planes_equal_the_cli_coefficient_exr(fspec_cli, tmp_path):
    rendered = fspec.render("cornell", coefficients=True, coeffs=8, **SMALL)
    out = tmp_path / "coeffs.exr"
    cli_render(fspec_cli, tmp_path, "cornell", {**SMALL, "coeffs": 8}, [f"--coefficients-exr={out}"])
    with OpenEXR.File(str(out), separate_channels=True) as exr:
        names = sorted(exr.channels(), key=lambda name: int(name[1:]))
    reference = read_exr(out, names)
    np.testing.assert_allclose(rendered.coefficients, reference, rtol=1e-6, atol=1e-7)


def test_scene_files_of_every_format(repo, fspec_cli, tmp_path):
    for scene, settings in [
        (repo / "scenes" / "cornell.toml", SMALL),
        (repo / "scenes" / "cornell" / "cornell.obj", SMALL),
        (repo / "scenes" / "mitsuba" / "simple.xml", {"seed": 2}),
    ]:
        defines = {"spp": 2, "res": 16} if scene.suffix == ".xml" else None
        image = fspec.render(scene, defines=defines, **settings)
        extra = ["-Dspp=2", "-Dres=16"] if defines else []
        reference = read_exr(cli_render(fspec_cli, tmp_path, str(scene), settings, extra), "RGB")
        assert image.shape == reference.shape
        np.testing.assert_allclose(image, reference, rtol=1e-6, atol=1e-7, err_msg=str(scene))


def test_crop_renders_the_window_of_the_full_frame():
    full = fspec.render("cornell", **SMALL)
    window = fspec.render("cornell", crop=(8, 4, 10, 6), **SMALL)
    np.testing.assert_array_equal(window, full[4:10, 8:18])


@pytest.mark.parametrize(
    "arguments, exception",
    [
        ({"scene": "no-such-scene"}, ValueError),
        ({"scene": "missing/scene.toml"}, FileNotFoundError),
        ({"scene": "cornell", "coeffs": 5}, ValueError),
        ({"scene": "cornell", "width": 0}, ValueError),
        ({"scene": "cornell", "max_depth": -3}, ValueError),
        ({"scene": "cornell", "transport": "cv", "wavelengths": 4, "coeffs": 32}, ValueError),
    ],
)
def test_bad_renders_raise_the_cli_message(fspec_cli, tmp_path, arguments, exception):
    settings = {**SMALL, **arguments}
    scene = settings.pop("scene")
    with pytest.raises(exception) as raised:
        fspec.render(scene, **settings)
    done = run_cli(fspec_cli, "render", scene, *cli_flags(settings), "--quiet", f"--out={tmp_path / 'x.exr'}")
    assert done.returncode == 2
    assert done.stderr.strip() == f"fspec: error: {raised.value}"
    assert "\n" not in str(raised.value)


def test_malformed_scene_file_raises_the_cli_message(fspec_cli, tmp_path):
    scene = tmp_path / "broken.toml"
    scene.write_text("[camera]\nfov_deg = \"wide\"\n")
    with pytest.raises(ValueError) as raised:
        fspec.render(scene, **SMALL)
    done = run_cli(fspec_cli, "render", str(scene), *cli_flags(SMALL), "--quiet", f"--out={tmp_path / 'x.exr'}")
    assert done.stderr.strip() == f"fspec: error: {raised.value}"
    assert "broken.toml" in str(raised.value)


@pytest.mark.parametrize(
    "arguments, message",
    [
        ({"transport": "bogus"}, "invalid value 'bogus' for '--transport <TRANSPORT>'"),
        ({"transport": "sampled", "coefficients": True}, 'coefficients=True needs transport="fourier"'),
        ({"color": "hsv"}, 'color "hsv"'),
        ({"crop": (1, 2)}, "crop (1, 2): expected (x, y, width, height)"),
        ({"crop": (20, 0, 10, 10)}, "--crop"),
    ],
)
def test_bad_options_raise_value_error(arguments, message):
    with pytest.raises(ValueError) as raised:
        fspec.render("cornell", **{**SMALL, **arguments})
    assert message in str(raised.value)
    assert "\n" not in str(raised.value)


def test_warnings_become_python_warnings():
    with pytest.warns(RuntimeWarning, match="--illuminant only applies to the colorchecker scene"):
        fspec.render("cornell", illuminant="d65", **SMALL)


def test_builtin_scenes_are_listed_and_render():
    scenes = fspec.builtin_scenes()
    assert "cornell" in scenes
    for name in scenes:
        image = fspec.render(name, spp=1, width=8, height=8)
        assert image.shape == (8, 8, 3) and np.isfinite(image).all(), name
        assert not math.isclose(float(image.max()), 0.0), name


def test_ctrl_c_stops_a_render_with_keyboard_interrupt():
    # A render of about a minute; SIGINT once it has started must end it
    # after the batch in progress (at most about half a second of passes).
    script = (
        "import fspec\n"
        "print('started', flush=True)\n"
        "try:\n"
        "    fspec.render('cornell', spp=100000, width=64, height=64)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True)\n"
    )
    # The child starts with SIGINT at its default, whatever this process
    # inherited (a shell's background job ignores it, and Python then keeps
    # it ignored), so that it gets Python's KeyboardInterrupt handler.
    process = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    assert process.stdout.readline().strip() == "started"
    time.sleep(1.0)
    signalled = time.monotonic()
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=60)
    assert "interrupted" in out
    # Generous for a loaded machine, far below the render's own length.
    assert time.monotonic() - signalled < 20.0
