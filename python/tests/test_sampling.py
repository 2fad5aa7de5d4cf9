"""Wavelength sampling, the sampled XYZ estimate, the control-variate
estimators and Fourier tables from Python: against exact integrals,
analytic Fresnel formulas and plain numpy, each statistical test with a
negative control."""

import numpy as np
import pytest

import fspec

VISIBLE = fspec.VISIBLE_RANGE_NM
WIDTH_NM = VISIBLE[1] - VISIBLE[0]
STRATEGIES = ("uniform", "stratified", "hero", "visible", "visible-hero")
#: Standard errors a Monte Carlo mean may stray before a test fails
#: (two-sided, p ~ 6e-5 per check: a fixed seed makes it deterministic).
SIGMAS = 4.0


def paths(count, paths_n=20000, seed=7):
    return np.random.default_rng(seed).random((paths_n, count))


def within_noise(samples, expected):
    """The sample mean of `samples` (rows: paths) is within SIGMAS standard errors of `expected`."""
    mean = samples.mean(axis=0)
    error = samples.std(axis=0, ddof=1) / np.sqrt(samples.shape[0])
    return np.all(np.abs(mean - expected) <= SIGMAS * error + 1e-12)


# --- wavelength sampling ----------------------------------------------------------


def test_uniform_and_stratified_wavelengths_have_the_uniform_density():
    u = paths(4, 1000)
    for strategy in ("uniform", "stratified", "hero"):
        lam, pdf = fspec.sample_wavelengths(u, strategy)
        assert lam.shape == u.shape and pdf.shape == u.shape
        assert np.all((lam >= VISIBLE[0]) & (lam <= VISIBLE[1]))
        np.testing.assert_allclose(pdf, 1.0 / WIDTH_NM, rtol=1e-6)


def test_stratified_puts_one_wavelength_in_each_sub_range():
    lam, _ = fspec.sample_wavelengths(paths(8, 500), "stratified")
    stratum = np.floor((lam - VISIBLE[0]) / (WIDTH_NM / 8)).astype(int)
    np.testing.assert_array_equal(stratum, np.broadcast_to(np.arange(8), lam.shape))


def test_hero_wavelengths_are_rotations_of_the_first():
    lam, _ = fspec.sample_wavelengths(paths(4, 500), "hero")
    offsets = np.mod(lam - lam[:, :1], WIDTH_NM)
    np.testing.assert_allclose(offsets, np.broadcast_to(np.arange(4) * WIDTH_NM / 4, lam.shape), atol=1e-3)


def test_every_strategy_estimates_the_luminance_of_an_equal_energy_spectrum():
    # Y of the constant 1 is 1 by the normalisation; each path's estimate is
    # unbiased, so the mean over paths is 1 within noise.
    for strategy in STRATEGIES:
        lam, pdf = fspec.sample_wavelengths(paths(4), strategy)
        y = fspec.sampled_to_xyz(np.ones_like(lam), lam, pdf)[:, 1]
        assert within_noise(y[:, None], 1.0), strategy
        # Negative control: a density 10 % off biases the estimate beyond noise.
        y_wrong = fspec.sampled_to_xyz(np.ones_like(lam), lam, pdf * 1.1)[:, 1]
        assert not within_noise(y_wrong[:, None], 1.0), strategy


def test_sampled_xyz_of_a_lamp_converges_to_its_exact_xyz():
    lam_table, d65 = fspec.builtin_table("d65")
    exact = fspec.tabulated_xyz(lam_table, d65)
    for strategy in ("stratified", "visible-hero"):
        lam, pdf = fspec.sample_wavelengths(paths(4), strategy)
        xyz = fspec.sampled_to_xyz(np.interp(lam, lam_table, d65), lam, pdf)
        assert within_noise(xyz, exact), strategy
    # Negative control: visible samples divided by the uniform density.
    lam, _ = fspec.sample_wavelengths(paths(4), "visible")
    xyz = fspec.sampled_to_xyz(np.interp(lam, lam_table, d65), lam, np.full_like(lam, 1.0 / WIDTH_NM))
    assert not within_noise(xyz, exact)


def test_visible_density_matches_a_histogram_of_its_samples():
    lam, pdf = fspec.sample_wavelengths(paths(1, 200000, seed=3), "visible")
    lam, pdf = lam[:, 0], pdf[:, 0]
    edges = np.linspace(*VISIBLE, 48)
    counts, _ = np.histogram(lam, edges)
    centres = 0.5 * (edges[1:] + edges[:-1])
    # The density at a bin centre, read back from the samples nearest it.
    expected = np.interp(centres, np.sort(lam), pdf[np.argsort(lam)]) * np.diff(edges) * lam.size
    assert np.all(np.abs(counts - expected) <= SIGMAS * np.sqrt(expected) + 2.0)
    # Negative control: the uniform density does not describe the samples.
    uniform = np.full_like(centres, lam.size / (edges.size - 1))
    assert not np.all(np.abs(counts - uniform) <= SIGMAS * np.sqrt(uniform) + 2.0)


def test_bad_sampling_inputs_raise_value_errors():
    with pytest.raises(ValueError, match=r"outside \[0, 1\)"):
        fspec.sample_wavelengths([[0.5, 1.0]])
    with pytest.raises(ValueError, match="strategy"):
        fspec.sample_wavelengths([[0.5]], "blue-noise")
    with pytest.raises(ValueError, match="supported counts are 1 to 32"):
        fspec.sample_wavelengths(np.full((1, 33), 0.5))
    with pytest.raises(ValueError, match="NaN"):
        fspec.sample_wavelengths([[np.nan]])
    with pytest.raises(ValueError, match="negative"):
        fspec.sampled_to_xyz([[1.0]], [[500.0]], [[-1.0]])
    with pytest.raises(ValueError, match="last axis"):
        fspec.sampled_to_xyz([[1.0, 2.0]], [[500.0]], [[1.0]])


def test_a_double_just_below_one_stays_inside_the_range():
    lam, _ = fspec.sample_wavelengths([[1.0 - 1e-12]], "uniform")
    assert VISIBLE[0] <= lam[0, 0] <= VISIBLE[1]


# --- control variates -------------------------------------------------------------


def lamp_paths_xyz(estimators, samples, seed):
    """Per path: XYZ of a 4000 K blackbody from 4 stratified wavelengths, the
    same estimate of its 4-coefficient Fourier projection (the control), and
    that projection's exact XYZ (mu); shapes (estimators, samples, 3) and (3,)."""
    coeffs = fspec.blackbody(4000.0, n=4)
    mu = fspec.to_xyz(coeffs)
    grid = np.linspace(*VISIBLE, 4701)
    planck = fspec.evaluate(fspec.blackbody(4000.0, n=32), grid)
    lam, pdf = fspec.sample_wavelengths(paths(4, estimators * samples, seed), "stratified")
    y = fspec.sampled_to_xyz(np.interp(lam, grid, planck), lam, pdf)
    c = fspec.sampled_to_xyz(fspec.evaluate(coeffs, lam.reshape(-1)).reshape(lam.shape), lam, pdf)
    return y.reshape(estimators, samples, 3), c.reshape(estimators, samples, 3), mu


def exact_lamp_xyz():
    """The exact XYZ of the lamp :func:`lamp_paths_xyz` samples."""
    grid = np.linspace(*VISIBLE, 4701)
    return fspec.tabulated_xyz(grid, fspec.evaluate(fspec.blackbody(4000.0, n=32), grid))


def lamp_paths(estimators, samples, seed):
    """The luminance (Y) of :func:`lamp_paths_xyz`."""
    y, c, mu = lamp_paths_xyz(estimators, samples, seed)
    return y[..., 1], c[..., 1], mu[1]


def test_plain_estimate_is_the_sample_mean():
    y, c, mu = lamp_paths(50, 32, seed=11)
    for method in ("running", "cross-fit"):
        result = fspec.control_variate(y, c, mu, batch=4, method=method)
        np.testing.assert_allclose(result.plain, y.mean(axis=1), rtol=1e-12)


@pytest.mark.parametrize("method", ["running", "cross-fit"])
def test_control_variate_is_unbiased_and_reduces_the_error_on_a_lamp(method):
    y, c, mu = lamp_paths(400, 32, seed=5)
    exact = exact_lamp_xyz()[1]
    result = fspec.control_variate(y, c, mu, batch=4, method=method)
    # Unbiased: the mean over 400 independent estimators is the exact Y.
    assert within_noise(result.estimate[:, None], exact)
    # The Fourier lamp tracks the lamp, so the spread drops well below plain MC.
    assert result.estimate.std() < 0.5 * result.plain.std()
    # Negative control: an inexact mu (2 % off) biases the estimate beyond noise.
    biased = fspec.control_variate(y, c, mu * 1.02, batch=4, method=method)
    assert not within_noise(biased.estimate[:, None], exact)


def test_cross_fit_does_not_hurt_with_a_useless_control():
    rng = np.random.default_rng(2)
    y = 1.0 + rng.standard_normal((2000, 32))
    c = rng.standard_normal((2000, 32))  # independent of y: rho = 0
    result = fspec.control_variate(y, c, 0.0, batch=4, method="cross-fit")
    assert result.estimate.var() <= 1.1 * result.plain.var()


def test_colour_control_variate_returns_one_colour_per_estimator():
    y, c, mu = lamp_paths_xyz(200, 32, seed=9)
    result = fspec.control_variate(y, c, mu, batch=4, method="cross-fit-color")
    assert result.estimate.shape == (200, 3)
    np.testing.assert_allclose(result.plain, y.mean(axis=1), rtol=1e-12)
    assert np.all(result.estimate.std(axis=0) < 0.5 * result.plain.std(axis=0))
    # Negative control: an inexact mu biases every channel beyond noise.
    exact = exact_lamp_xyz()
    assert within_noise(result.estimate, exact)
    biased = fspec.control_variate(y, c, mu * 1.02, batch=4, method="cross-fit-color")
    assert not within_noise(biased.estimate, exact)


def test_bad_control_variate_inputs_raise_value_errors():
    with pytest.raises(ValueError, match="method"):
        fspec.control_variate([1.0], [1.0], 0.0, method="optimal")
    with pytest.raises(ValueError, match="equal shapes"):
        fspec.control_variate([1.0, 2.0], [1.0], 0.0)
    with pytest.raises(ValueError, match="at least 1"):
        fspec.control_variate([1.0], [1.0], 0.0, batch=0)
    with pytest.raises(ValueError, match="samples, 3"):
        fspec.control_variate([[1.0, 2.0]], [[1.0, 2.0]], 0.0, method="cross-fit-color")
    with pytest.raises(ValueError, match="NaN"):
        fspec.control_variate([np.nan], [1.0], 0.0)


# --- Fourier tables ---------------------------------------------------------------


def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance from the outside, written out (Hecht, Optics, 4.34)."""
    sin_t2 = (1.0 - cos_i**2) / eta**2
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t2))
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return np.where(sin_t2 >= 1.0, 1.0, 0.5 * (r_s**2 + r_p**2))


def fresnel_conductor(cos_i, index):
    """Unpolarised Fresnel reflectance of a complex index, in complex arithmetic."""
    cos_i = cos_i.astype(complex)
    cos_t = np.sqrt(1.0 - (1.0 - cos_i**2) / index**2)
    r_s = (cos_i - index * cos_t) / (cos_i + index * cos_t)
    r_p = (index * cos_i - cos_t) / (index * cos_i + cos_t)
    return 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)


def test_dielectric_table_of_a_constant_index_is_fresnel():
    table = fspec.FourierTable.dielectric([550.0], [1.5], n=8)
    cos_theta = np.linspace(0.02, 1.0, 37)
    coeffs = table.lookup(cos_theta)
    assert coeffs.shape == (37, 8) and table.rows.shape == (fspec.TABLE_ROWS, 8)
    # Linear interpolation between rows 1/179 apart: error below 1e-3.
    np.testing.assert_allclose(coeffs[:, 0], fresnel_dielectric(cos_theta, 1.5), atol=1e-3)
    np.testing.assert_allclose(coeffs[:, 1:], 0.0, atol=1e-6)
    # Negative control: another index is far off.
    assert np.max(np.abs(coeffs[:, 0] - fresnel_dielectric(cos_theta, 1.33))) > 1e-2


def test_dielectric_table_from_inside_reflects_totally_past_the_critical_angle():
    table = fspec.FourierTable.dielectric([550.0], [1.5], n=4, from_inside=True)
    critical = np.sqrt(1.0 - 1.0 / 1.5**2)
    grazing = np.linspace(0.0, critical - 0.02, 10)
    np.testing.assert_allclose(table.lookup(grazing)[:, 0], 1.0, atol=1e-3)


def test_dispersive_dielectric_table_varies_with_wavelength():
    # A dispersive glass (eta falls with wavelength): reflectance is higher in the blue.
    lam = np.array([400.0, 700.0])
    table = fspec.FourierTable.dielectric(lam, [1.55, 1.50], n=12)
    at_normal = table.lookup([1.0])[0]
    values = fspec.evaluate(at_normal, lam)
    np.testing.assert_allclose(values, fresnel_dielectric(np.ones(2), np.array([1.55, 1.50])), rtol=2e-2)
    assert values[0] > values[1]


def test_conductor_table_matches_fresnel_of_a_complex_index():
    table = fspec.FourierTable.conductor([550.0], [0.2], [3.0], n=4)
    cos_theta = np.linspace(0.05, 1.0, 20)
    np.testing.assert_allclose(table.lookup(cos_theta)[:, 0], fresnel_conductor(cos_theta, 0.2 + 3.0j), atol=2e-3)
    assert table.n == 4


def test_bad_table_inputs_raise_value_errors():
    with pytest.raises(ValueError, match="not positive"):
        fspec.FourierTable.dielectric([550.0], [0.0])
    with pytest.raises(ValueError, match="outside"):
        fspec.FourierTable.dielectric([550.0], [1.5]).lookup([1.5])
    with pytest.raises(ValueError, match="negative"):
        fspec.FourierTable.conductor([550.0], [0.2], [-1.0])
    with pytest.raises(ValueError, match="outside_index"):
        fspec.FourierTable.conductor([550.0], [0.2], [3.0], outside_index=0.0)
    with pytest.raises(ValueError, match="supported coefficient counts"):
        fspec.FourierTable.dielectric([550.0], [1.5], n=0)
