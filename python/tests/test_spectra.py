"""spectral-core from Python, against analytic values, independent numpy
oracles and colour-science."""

import colour
import numpy as np
import pytest

import fspec

VISIBLE = fspec.VISIBLE_RANGE_NM
WIDTH_NM = VISIBLE[1] - VISIBLE[0]


def phase(lambda_nm, range_nm=VISIBLE):
    """The phase map of the coefficient convention (module docs of fspec)."""
    low, high = range_nm
    return np.pi * (np.asarray(lambda_nm) - low) / (high - low) - np.pi


def series(coeffs, lambda_nm, range_nm=VISIBLE):
    """The truncated series c_0 + 2 sum c_j cos(j phi), written out in numpy."""
    coeffs = np.asarray(coeffs)
    j = np.arange(coeffs.shape[-1])
    weights = np.where(j == 0, 1.0, 2.0)
    cosines = np.cos(np.multiply.outer(phase(lambda_nm, range_nm), j))
    return np.einsum("...j,kj->...k", coeffs * weights, cosines)


def quadrature_coefficients(function, n, range_nm=VISIBLE, step_nm=0.01):
    """c_j = (1/W) int s(l) cos(j phi(l)) dl by the trapezoid rule on a fine grid."""
    low, high = range_nm
    lam = np.linspace(low, high, int(round((high - low) / step_nm)) + 1)
    values = function(lam)
    cosines = np.cos(np.multiply.outer(np.arange(n), phase(lam, range_nm)))
    return np.trapezoid(cosines * values, lam, axis=-1) / (high - low)


# --- projection -----------------------------------------------------------------


def test_projection_of_a_constant_is_its_mean_and_nothing_else():
    for value in (0.0, 0.25, 3.5):
        coeffs = fspec.project([400.0, 700.0], [value, value], n=16)
        expected = np.zeros(16)
        expected[0] = value
        np.testing.assert_allclose(coeffs, expected, atol=1e-12)


def test_projection_of_a_ramp_matches_its_fourier_series():
    # s(l) = l over the range: c_0 = l0 + W/2, c_j = W (1 - (-1)^j) / (pi^2 j^2).
    lam = np.array(VISIBLE)
    coeffs = fspec.project(lam, lam, n=32)
    j = np.arange(1, 32)
    expected = np.concatenate(([VISIBLE[0] + WIDTH_NM / 2], WIDTH_NM * (1 - (-1.0) ** j) / (np.pi**2 * j**2)))
    np.testing.assert_allclose(coeffs, expected, rtol=1e-10, atol=1e-10)


def test_projection_is_vectorised_over_any_batch_shape():
    lam = np.linspace(380.0, 780.0, 41)
    rng = np.random.default_rng(1)
    values = rng.uniform(0.0, 1.0, size=(2, 3, lam.size))
    batch = fspec.project(lam, values, n=8)
    assert batch.shape == (2, 3, 8)
    for index in np.ndindex(2, 3):
        np.testing.assert_array_equal(batch[index], fspec.project(lam, values[index], n=8))
    # One row of wavelengths per spectrum gives the same result.
    per_row = fspec.project(np.broadcast_to(lam, values.shape), values, n=8)
    np.testing.assert_array_equal(per_row, batch)


def test_projection_of_a_polyline_matches_dense_quadrature():
    lam = np.array([360.0, 450.0, 500.0, 610.0, 700.0, 830.0])
    values = np.array([0.1, 0.8, 0.3, 0.9, 0.05, 0.4])
    coeffs = fspec.project(lam, values, n=24)
    oracle = quadrature_coefficients(lambda x: np.interp(x, lam, values), 24)
    # Trapezoid error on a 0.01 nm grid of a polyline with kinks: 9e-10 measured.
    np.testing.assert_allclose(coeffs, oracle, atol=1e-8)


# --- blackbody --------------------------------------------------------------------


# CODATA 2018 (exact SI values): colour-science defaults to the rounded
# second radiation constant c2 = 1.4388e-2 m K of ITS-90, which moves a
# 1500 K spectrum by 1e-4; the core uses h c / k.
PLANCK_J_S = 6.62607015e-34
SPEED_OF_LIGHT_M_PER_S = 299792458.0
BOLTZMANN_J_PER_K = 1.380649e-23
C2_M_K = PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S / BOLTZMANN_J_PER_K
WIEN_M_K = 2.897771955e-3


def planck_peak_normalised(lambda_nm, temperature_k):
    """colour-science's Planck's law, divided by its value at Wien's peak."""
    planck = lambda lam_m: colour.colorimetry.planck_law(lam_m, temperature_k, c2=C2_M_K)  # noqa: E731
    return planck(np.asarray(lambda_nm) * 1e-9) / planck(WIEN_M_K / temperature_k)


@pytest.mark.parametrize("temperature_k", [1500.0, 2856.0, 6500.0, 10000.0])
def test_blackbody_matches_planck_from_colour_science(temperature_k):
    coeffs = fspec.blackbody(temperature_k, n=16)
    oracle = quadrature_coefficients(lambda lam: planck_peak_normalised(lam, temperature_k), 16)
    # The core integrates Gauss-Legendre panels of 1 nm, the oracle the
    # trapezoid rule on 0.01 nm: they agree to 7e-11 (measured).
    np.testing.assert_allclose(coeffs, oracle, atol=1e-9)


def test_blackbody_negative_control_another_temperature_fails():
    coeffs = fspec.blackbody(6500.0, n=16)
    oracle = quadrature_coefficients(lambda lam: planck_peak_normalised(lam, 6600.0), 16)
    assert np.max(np.abs(coeffs - oracle)) > 1e-3


def test_blackbody_is_vectorised():
    temperatures = np.array([[2000.0, 3000.0], [5000.0, 9000.0]])
    batch = fspec.blackbody(temperatures, n=8)
    assert batch.shape == (2, 2, 8)
    np.testing.assert_array_equal(batch[1, 0], fspec.blackbody(5000.0, n=8))


# --- product and evaluation ---------------------------------------------------------


def truncated_product_oracle(a, b):
    """The truncated product from its definition: the two-sided sequences
    a_|k| (|k| < n) convolved, the result's coefficients 0..n-1 kept."""
    n = a.shape[-1]
    two_sided = lambda c: np.concatenate((c[:0:-1], c))  # noqa: E731
    full = np.convolve(two_sided(a), two_sided(b))
    centre = 2 * (n - 1)
    return full[centre : centre + n]


def test_product_matches_the_convolution_of_the_two_series():
    rng = np.random.default_rng(7)
    for n in (1, 2, 5, 12, 32):
        a, b = rng.normal(size=n), rng.normal(size=n)
        np.testing.assert_allclose(fspec.product(a, b), truncated_product_oracle(a, b), rtol=1e-12, atol=1e-12)


def test_product_is_the_projection_of_the_product_of_the_series():
    # An oracle independent of the convolution: multiply the two series on a
    # dense grid and project by quadrature.
    rng = np.random.default_rng(11)
    a, b = rng.normal(size=8), rng.normal(size=8)
    oracle = quadrature_coefficients(lambda lam: series(a, lam) * series(b, lam), 8, step_nm=0.005)
    # The trapezoid rule is exact for trigonometric polynomials of low enough
    # degree on a uniform grid over the period: 1.6e-15 measured.
    np.testing.assert_allclose(fspec.product(a, b), oracle, atol=1e-12)


def test_product_with_the_constant_one_is_the_identity_and_broadcasts():
    rng = np.random.default_rng(3)
    spectra = rng.normal(size=(4, 5, 12))
    one = np.zeros(12)
    one[0] = 1.0
    np.testing.assert_allclose(fspec.product(spectra, one), spectra, rtol=1e-15, atol=1e-15)
    assert fspec.product(spectra[:, :1], spectra[:1]).shape == (4, 5, 12)


def test_evaluate_is_the_written_out_series():
    rng = np.random.default_rng(5)
    coeffs = rng.normal(size=(3, 10))
    lam = np.linspace(360.0, 830.0, 97).reshape(1, 97)
    values = fspec.evaluate(coeffs, lam)
    assert values.shape == (3, 1, 97)
    np.testing.assert_allclose(values[:, 0, :], series(coeffs, lam[0]), rtol=1e-12, atol=1e-12)


def test_evaluate_reconstructs_a_smooth_spectrum():
    lam = np.linspace(360.0, 830.0, 471)
    smooth = 0.5 + 0.3 * np.sin(lam / 60.0)
    reconstructed = fspec.evaluate(fspec.project(lam, smooth, n=32), lam[20:-20])
    # The even extension has a kink at the range's ends, so the coefficients
    # fall as 1/j^2 and 32 of them leave a few 1e-3 near the ends (measured
    # 2.6e-3 at 381 nm); a wrong series would be off by tenths.
    np.testing.assert_allclose(reconstructed, smooth[20:-20], atol=5e-3)


# --- XYZ and sRGB --------------------------------------------------------------------


def test_xyz_of_the_constant_one_has_unit_luminance_on_every_linear_route():
    one = np.zeros(12)
    one[0] = 1.0
    for route in ("zeroth", "series", "lut", "mese"):
        assert fspec.to_xyz(one, route=route)[1] == pytest.approx(1.0, abs=1e-6)


def test_xyz_of_d65_matches_the_published_white_point():
    # CIE 15:2018, Table T.3: D65 with the 1931 observer, x = 0.31272, y = 0.32903.
    lam, power = fspec.builtin_table("d65")
    x, y = colour.XYZ_to_xy(fspec.tabulated_xyz(lam, power))
    assert (x, y) == pytest.approx((0.31272, 0.32903), abs=5e-5)
    # Through 32 coefficients and the zeroth route: the truncation moves the
    # chromaticity by 1.9e-5 (measured).
    x, y = colour.XYZ_to_xy(fspec.to_xyz(fspec.builtin("d65", n=32)))
    assert (x, y) == pytest.approx((0.31272, 0.32903), abs=1e-4)


def test_xyz_of_d65_matches_colour_science():
    d65 = colour.SDS_ILLUMINANTS["D65"]
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    expected = colour.sd_to_XYZ(d65, cmfs, method="Integration")
    expected = expected / expected[1]
    lam, power = fspec.builtin_table("d65")
    ours = fspec.tabulated_xyz(lam, power)
    # Exact polyline integral against colour-science's 1 nm sum: 1.3e-5.
    np.testing.assert_allclose(ours / ours[1], expected, atol=5e-5)


def test_routes_agree_for_colorchecker_patches_under_d65():
    d65 = fspec.builtin("d65", n=32)
    patches = np.stack([fspec.builtin(f"colorchecker-{i}", n=32) for i in range(1, 25)])
    lit = fspec.product(patches, d65)
    zeroth = fspec.to_xyz(lit, route="zeroth")
    # Routes 1-2 integrate the series by the 1 nm trapezoid rule (the LUT
    # with float32 cosines), route 3 exactly: measured relative difference
    # at most 8.1e-5.
    for route in ("series", "lut"):
        np.testing.assert_allclose(fspec.to_xyz(lit, route=route), zeroth, rtol=2e-4)


def test_colorchecker_under_d65_matches_colour_science():
    d65 = colour.SDS_ILLUMINANTS["D65"]
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    shape = colour.SpectralShape(360, 830, 1)
    d65_1nm = d65.copy().align(shape)
    lam = np.arange(360.0, 831.0)
    d65_power = d65_1nm.values
    d65_coeffs = fspec.project(lam, d65_power, n=32)
    normalisation = fspec.to_xyz(d65_coeffs)[1]
    for i in range(1, 25):
        patch_lam, reflectance = fspec.builtin_table(f"colorchecker-{i}")
        patch = colour.SpectralDistribution(dict(zip(patch_lam, reflectance)))
        patch = patch.copy().align(shape, extrapolator_kwargs={"method": "Constant", "left": None, "right": None})
        # colour-science scales XYZ so that the illuminant has Y = 100.
        expected = colour.sd_to_XYZ(patch, cmfs, d65_1nm, method="Integration") / 100.0
        ours = fspec.to_xyz(fspec.product(fspec.project(patch_lam, reflectance, n=32), d65_coeffs)) / normalisation
        # 32 coefficients of reflectance and light, truncated product, against
        # colour-science's 1 nm sums: measured at most 3.3e-4 (Y of white = 1).
        np.testing.assert_allclose(ours, expected, atol=1e-3, err_msg=f"patch {i}")


def test_srgb_matrices_and_transfer_function_match_colour_science():
    rng = np.random.default_rng(9)
    xyz = rng.uniform(0.0, 1.0, size=(50, 3))
    # The matrix derived from the sRGB primaries and the D65 chromaticity
    # (colour-science's own sRGB colourspace uses the standard's matrix
    # rounded to 4 decimals, 3e-4 away).
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    rgb_to_xyz = colour.normalised_primary_matrix(srgb.primaries, srgb.whitepoint)
    expected = xyz @ np.linalg.inv(rgb_to_xyz).T
    np.testing.assert_allclose(fspec.xyz_to_linear_srgb(xyz), expected, atol=1e-6)
    np.testing.assert_allclose(fspec.linear_srgb_to_xyz(fspec.xyz_to_linear_srgb(xyz)), xyz, atol=1e-6)
    linear = rng.uniform(0.0, 1.0, size=(7, 4))
    encoded = fspec.srgb_encode(linear)
    assert encoded.shape == (7, 4)
    np.testing.assert_allclose(encoded, colour.cctf_encoding(linear, "sRGB"), atol=1e-12)
    np.testing.assert_allclose(fspec.srgb_decode(encoded), linear, atol=1e-12)


def test_upsampled_illuminant_reproduces_its_rgb():
    rgb = np.array([[1.0, 1.0, 1.0], [0.8, 0.3, 0.1], [0.1, 0.5, 0.2], [0.2, 0.3, 0.9]])
    spectra = fspec.upsample_rgb(rgb, n=32, kind="illuminant")
    back = fspec.xyz_to_linear_srgb(fspec.to_xyz(spectra))
    # The sigmoid fit reproduces in-gamut sRGB to about 1e-3, and 32
    # coefficients add their truncation: measured at most 1.4e-3.
    np.testing.assert_allclose(back, rgb, atol=5e-3)
    # Negative control: another colour is far from it.
    assert np.max(np.abs(back[1] - rgb[2])) > 0.1


def test_upsampled_reflectance_stays_in_the_unit_interval():
    rgb = np.random.default_rng(2).uniform(0.0, 1.0, size=(20, 3))
    values = fspec.bounded_mese(fspec.upsample_rgb(rgb, n=16), np.linspace(360.0, 830.0, 95))
    assert values.min() >= 0.0 and values.max() <= 1.0


# --- MESE ---------------------------------------------------------------------------


def test_mese_is_non_negative_where_the_series_rings():
    # A narrow line at 550 nm: its truncated series dips below zero.
    lam = np.array([360.0, 545.0, 550.0, 555.0, 830.0])
    coeffs = fspec.project(lam, [0.0, 0.0, 1.0, 0.0, 0.0], n=16)
    grid = np.linspace(360.0, 830.0, 941)
    assert fspec.evaluate(coeffs, grid).min() < -1e-3
    assert fspec.mese(coeffs, grid).min() >= 0.0


@pytest.mark.parametrize("bounded", [False, True])
def test_mese_reproduces_its_moments(bounded):
    # MESE is the maximum-entropy density *with the given coefficients*:
    # projecting its samples back gives them again.
    if bounded:
        coeffs = fspec.builtin("colorchecker-3", n=8)
        reconstruct = fspec.bounded_mese
    else:
        coeffs = fspec.builtin("d65", n=8) / 100.0
        reconstruct = fspec.mese
    grid = np.linspace(360.0, 830.0, 47001)
    moments = fspec.project(grid, reconstruct(coeffs, grid), n=8)
    # Measured 3e-10: the polyline through 0.01 nm samples of a smooth density.
    np.testing.assert_allclose(moments, coeffs, atol=1e-8)
    # Negative control: the moments of a neighbouring patch differ.
    other = fspec.builtin("colorchecker-4", n=8) if bounded else fspec.builtin("a", n=8) / 100.0
    assert np.max(np.abs(moments - other)) > 1e-3


def test_mese_route_agrees_with_the_linear_routes_for_a_smooth_spectrum():
    coeffs = fspec.builtin("d65", n=16)
    # MESE is not the truncated series, but close to it for D65: 1e-3 measured.
    np.testing.assert_allclose(fspec.to_xyz(coeffs, route="mese"), fspec.to_xyz(coeffs), rtol=3e-3)


# --- built-ins ------------------------------------------------------------------------


def test_builtin_names_and_tables():
    names = fspec.builtin_names()
    assert "d65" in names and "colorchecker-24" in names and "cie-y" in names
    lam, values = fspec.builtin_table("cie-y")
    assert lam[0] == fspec.CIE_RANGE_NM[0] and lam[-1] == fspec.CIE_RANGE_NM[1]
    assert values[np.searchsorted(lam, 555.0)] == pytest.approx(1.0, abs=1e-4)
    # A built-in projects as its table does.
    lam, power = fspec.builtin_table("a")
    np.testing.assert_allclose(fspec.builtin("a", n=12), fspec.project(lam, power, n=12), rtol=1e-12)
    np.testing.assert_allclose(fspec.builtin("blackbody-3000", n=12), fspec.blackbody(3000.0, n=12), rtol=1e-12)


def test_builtin_illuminant_a_matches_colour_science():
    lam, power = fspec.builtin_table("a")
    expected = colour.SDS_ILLUMINANTS["A"][lam]
    np.testing.assert_allclose(power, expected, rtol=1e-4)


# --- bad input --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: fspec.project([400.0, 500.0], [1.0, 1.0], n=0), "supported coefficient counts are 1 to 32"),
        (lambda: fspec.project([400.0, 500.0], [1.0, 1.0], n=33), "supported coefficient counts are 1 to 32"),
        (lambda: fspec.project([500.0, 400.0], [1.0, 1.0]), "spectrum 0: wavelength of sample 2 is not larger"),
        (lambda: fspec.project([400.0, 500.0], [[1.0, 1.0], [1.0, np.nan]]), "spectrum 1: value of sample 2 is NaN"),
        (lambda: fspec.project([400.0, 500.0], [1.0, -1.0]), "value of sample 2 is negative"),
        (lambda: fspec.project([400.0, 500.0, 600.0], [1.0, 1.0]), "wavelengths_nm of shape (3,)"),
        (lambda: fspec.project([400.0, 500.0], [1.0, 1.0], range_nm=(830.0, 360.0)), "range_nm (830, 360)"),
        (lambda: fspec.project([400.0, 500.0], ["a", "b"]), "expected an array of numbers"),
        (lambda: fspec.blackbody(-5.0), "temperature -5 K"),
        (lambda: fspec.evaluate(np.ones(4), [900.0]), "wavelength 900 nm is outside the range 360 to 830 nm"),
        (lambda: fspec.mese(np.ones(4), [np.nan]), "outside the range"),
        (lambda: fspec.to_xyz(np.ones(4), route="bogus"), 'route "bogus"'),
        (lambda: fspec.to_xyz(np.ones(4), range_nm=(300.0, 900.0)), "inside the CIE table"),
        (lambda: fspec.to_xyz([1.0, np.inf]), "row 0, element 1 is NaN or infinite"),
        (lambda: fspec.upsample_rgb([1.0, 0.0, 0.0, 0.0]), "expected 3"),
        (lambda: fspec.upsample_rgb([0.5, 0.5, 0.5], kind="glow"), 'kind "glow"'),
        (lambda: fspec.product(np.ones(4), np.ones(5)), "a has 4 coefficients, b 5"),
        (lambda: fspec.product(np.ones((2, 4)), np.ones((3, 4))), "do not broadcast"),
        (lambda: fspec.builtin("d66"), '"d66": unknown built-in spectrum name'),
        (lambda: fspec.builtin_table("blackbody-3000"), "is a blackbody"),
        (lambda: fspec.to_xyz(np.ones((0, 4))), "empty array"),
    ],
)
def test_bad_input_raises_value_error_with_one_line(call, message):
    with pytest.raises(ValueError) as raised:
        call()
    text = str(raised.value)
    assert message in text
    assert "\n" not in text
