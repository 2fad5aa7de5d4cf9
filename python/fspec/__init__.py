"""fspec: Fourier-series spectral rendering from Python.

A spectrum over a wavelength range ``[l0, l1]`` (nm) is carried as ``n``
cosine coefficients ``c_0 ... c_{n-1}``: with the phase
``phi(l) = pi (l - l0) / (l1 - l0) - pi``, the spectrum is
``s(l) ~ c_0 + 2 sum_{j>=1} c_j cos(j phi)``, so ``c_0`` is its mean over the
range. Spectra are multiplied by a truncated convolution (:func:`product`)
and converted to colour once (:func:`to_xyz`); the renderer (:func:`render`)
carries every path's throughput this way.

Every function is vectorised over numpy arrays: the last axis holds one
spectrum's coefficients (or samples, or colour channels), the leading axes
are a batch of any shape, and the result keeps that batch shape. Inputs may
be any array-like; results are ``float64`` (images ``float32``). Bad input
raises ``ValueError`` with the library's one-line message, naming the
offending spectrum's index in the flattened batch; a scene file that does
not exist raises ``FileNotFoundError``.

The default range is the CIE 1931 table's, 360-830 nm (:data:`VISIBLE_RANGE_NM`),
the range of the renderer's built-in scenes and the one colour conversions
require ranges to lie within.
"""

from __future__ import annotations

import logging
import os
import warnings
from typing import List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _fspec

__all__ = [
    "MAX_COEFFS",
    "VISIBLE_RANGE_NM",
    "CIE_RANGE_NM",
    "Rendered",
    "project",
    "blackbody",
    "upsample_rgb",
    "builtin",
    "builtin_table",
    "builtin_names",
    "builtin_scenes",
    "product",
    "evaluate",
    "mese",
    "bounded_mese",
    "to_xyz",
    "tabulated_xyz",
    "xyz_to_linear_srgb",
    "linear_srgb_to_xyz",
    "srgb_encode",
    "srgb_decode",
    "to_srgb",
    "MAX_WAVELENGTHS",
    "TABLE_ROWS",
    "sample_wavelengths",
    "sampled_to_xyz",
    "ControlVariateEstimate",
    "control_variate",
    "FourierTable",
    "render",
]

#: The largest coefficient count (every count from 1 up to it is supported).
MAX_COEFFS: int = _fspec.MAX_COEFFS
#: The default spectral range, nm: the CIE 1931 table's, as the renderer's.
VISIBLE_RANGE_NM: Tuple[float, float] = _fspec.VISIBLE_RANGE_NM
#: The CIE 1931 2-degree table's range, nm; colour needs ranges inside it.
CIE_RANGE_NM: Tuple[float, float] = _fspec.CIE_RANGE_NM

ArrayLike = Union[np.ndarray, Sequence[float], Sequence[Sequence[float]], float]
Range = Tuple[float, float]

_log = logging.getLogger("fspec")


def _range(range_nm: Range) -> Range:
    try:
        low, high = range_nm
        return float(low), float(high)
    except (TypeError, ValueError) as error:
        raise ValueError(f"range_nm {range_nm!r}: expected (min_nm, max_nm)") from error


def _floats(values: ArrayLike, name: str) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: expected an array of numbers") from error
    return array


def _rows(values: ArrayLike, width: Optional[int], name: str) -> Tuple[np.ndarray, Tuple[int, ...], int]:
    """``values`` as flat C-contiguous float64, its batch shape and row width."""
    array = _floats(values, name)
    if array.ndim == 0:
        raise ValueError(f"{name}: expected at least one axis, got a scalar")
    if width is not None and array.shape[-1] != width:
        raise ValueError(f"{name}: the last axis has {array.shape[-1]} elements, expected {width}")
    if array.size == 0:
        raise ValueError(f"{name}: empty array")
    return np.ascontiguousarray(array).reshape(-1), array.shape[:-1], array.shape[-1]


def _coeff_count(n: int) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"n = {n!r}: expected a whole number of coefficients")
    return int(n)


def project(
    wavelengths_nm: ArrayLike,
    values: ArrayLike,
    n: int = 12,
    range_nm: Range = VISIBLE_RANGE_NM,
) -> np.ndarray:
    """Projects tabulated spectra onto ``n`` Fourier coefficients.

    Each spectrum is the polyline through its samples, held flat beyond the
    first and last one; the projection of a polyline is computed exactly.

    Args:
        wavelengths_nm: shape ``(K,)``, shared by every spectrum, or the
            shape of ``values``, one row per spectrum; strictly increasing,
            positive.
        values: shape ``(..., K)``; finite and non-negative.
        n: coefficient count, 1 to :data:`MAX_COEFFS`.
        range_nm: the range the coefficients describe.

    Returns:
        Coefficients of shape ``(..., n)``.
    """
    flat_values, batch, samples = _rows(values, None, "values")
    lam = _floats(wavelengths_nm, "wavelengths_nm")
    if lam.shape != (samples,) and lam.shape != batch + (samples,):
        raise ValueError(
            f"wavelengths_nm of shape {lam.shape} for values of shape {batch + (samples,)}: "
            f"give ({samples},) or the shape of values"
        )
    out = _fspec.project_tabulated(
        _range(range_nm), np.ascontiguousarray(lam).reshape(-1), flat_values, samples, _coeff_count(n)
    )
    return out.reshape(batch + (n,))


def blackbody(temperature_k: ArrayLike, n: int = 12, range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """Fourier coefficients of blackbodies (Planck's law), each normalised to 1 at its peak.

    Args:
        temperature_k: temperatures in kelvin, any shape ``S``; finite, positive.
        n: coefficient count.
        range_nm: the range the coefficients describe.

    Returns:
        Coefficients of shape ``S + (n,)``.
    """
    temperatures = _floats(temperature_k, "temperature_k")
    out = _fspec.project_blackbody(
        _range(range_nm), np.ascontiguousarray(temperatures).reshape(-1), _coeff_count(n)
    )
    return out.reshape(temperatures.shape + (n,))


def upsample_rgb(
    rgb: ArrayLike,
    n: int = 12,
    kind: str = "reflectance",
    range_nm: Range = VISIBLE_RANGE_NM,
) -> np.ndarray:
    """Spectra of linear sRGB colours (Jakob & Hanika 2019), as ``n`` coefficients.

    Args:
        rgb: linear (not gamma-encoded) sRGB, shape ``(..., 3)``.
        n: coefficient count.
        kind: ``"reflectance"`` (channels clamped to [0, 1], a spectrum in
            [0, 1]), ``"unbounded"`` (any brightness, as emission) or
            ``"illuminant"`` (times D65 normalised to Y = 1, so ``(1, 1, 1)``
            is the sRGB white).
        range_nm: must lie inside :data:`CIE_RANGE_NM`.

    Returns:
        Coefficients of shape ``(..., n)``.
    """
    flat, batch, _ = _rows(rgb, 3, "rgb")
    out = _fspec.upsample_rgb(_range(range_nm), kind, flat, _coeff_count(n))
    return out.reshape(batch + (n,))


def builtin(name: str, n: int = 12, range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """Coefficients of a built-in spectrum: a CIE illuminant (``"d65"``,
    ``"a"``, ``"fl2"``, ...), a ColorChecker patch (``"colorchecker-1"`` ...
    ``"colorchecker-24"``), a colour-matching function (``"cie-x"``), a metal's
    index (``"gold-n"``, ``"gold-k"``), ``"equal-energy"`` or
    ``"blackbody-<kelvin>"``. :func:`builtin_names` lists the tabulated ones.

    Returns:
        Coefficients of shape ``(n,)``.
    """
    return _fspec.project_builtin(_range(range_nm), str(name), _coeff_count(n))


def builtin_table(name: str) -> Tuple[np.ndarray, np.ndarray]:
    """The samples ``(wavelengths_nm, values)`` of a tabulated built-in spectrum."""
    return _fspec.builtin_table(str(name))


def builtin_names() -> dict:
    """The tabulated built-in spectra: ``{name: description}``."""
    return dict(_fspec.builtin_names())


def builtin_scenes() -> dict:
    """The renderer's built-in scenes: ``{name: description}``."""
    return dict(_fspec.builtin_scenes())


def product(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """The truncated product ``a * b`` of spectra given as coefficients.

    The exact product of the two truncated series, truncated again to ``n``
    terms (the renderer's multiplication of throughputs). ``a`` and ``b``
    broadcast against each other; their last axes must both be ``n``.

    Returns:
        Coefficients of the broadcast shape.
    """
    a_array, b_array = _floats(a, "a"), _floats(b, "b")
    if a_array.ndim == 0 or b_array.ndim == 0:
        raise ValueError("a and b: expected arrays of coefficients, got a scalar")
    if a_array.shape[-1] != b_array.shape[-1]:
        raise ValueError(f"a has {a_array.shape[-1]} coefficients, b {b_array.shape[-1]}")
    try:
        a_array, b_array = np.broadcast_arrays(a_array, b_array)
    except ValueError as error:
        raise ValueError(f"a of shape {a_array.shape} and b of shape {b_array.shape} do not broadcast") from error
    flat_a, batch, n = _rows(a_array, None, "a")
    flat_b, _, _ = _rows(b_array, None, "b")
    return _fspec.product(flat_a, flat_b, n).reshape(batch + (n,))


def _reconstruct(function, coeffs: ArrayLike, wavelengths_nm: ArrayLike, range_nm: Range) -> np.ndarray:
    flat, batch, n = _rows(coeffs, None, "coeffs")
    lam = _floats(wavelengths_nm, "wavelengths_nm")
    out = function(_range(range_nm), flat, n, np.ascontiguousarray(lam).reshape(-1))
    return out.reshape(batch + lam.shape)


def evaluate(coeffs: ArrayLike, wavelengths_nm: ArrayLike, range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """The truncated series of spectra at wavelengths.

    Args:
        coeffs: shape ``(..., n)``.
        wavelengths_nm: shape ``W``, each inside ``range_nm``.

    Returns:
        Values of shape ``(...) + W``.
    """
    return _reconstruct(_fspec.evaluate, coeffs, wavelengths_nm, range_nm)


def mese(coeffs: ArrayLike, wavelengths_nm: ArrayLike, range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """The maximum-entropy spectral estimate (Peters et al. 2019) at wavelengths:
    a non-negative density with the given coefficients as its moments (for
    emission spectra, where the truncated series rings below zero).

    Shapes as :func:`evaluate`.
    """
    return _reconstruct(_fspec.mese, coeffs, wavelengths_nm, range_nm)


def bounded_mese(coeffs: ArrayLike, wavelengths_nm: ArrayLike, range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """The bounded MESE reconstruction, with values in [0, 1] (for reflectances).

    Shapes as :func:`evaluate`.
    """
    return _reconstruct(_fspec.bounded_mese, coeffs, wavelengths_nm, range_nm)


def to_xyz(coeffs: ArrayLike, route: str = "zeroth", range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """CIE 1931 XYZ of spectra given as coefficients, normalised so that the
    constant spectrum 1 has Y = 1 (``X = int s xbar dl / int ybar dl``).

    Args:
        coeffs: shape ``(..., n)``.
        route: ``"zeroth"`` (the 3 x n kernel: the zeroth coefficient of the
            product with the colour-matching functions, exact for their
            piecewise-linear table), ``"series"`` (the series evaluated at
            every 1 nm table wavelength), ``"lut"`` (the same with tabulated
            cosines) or ``"mese"`` (the MESE density integrated; the one
            non-linear route, for spectra with narrow peaks).
        range_nm: must lie inside :data:`CIE_RANGE_NM`.

    Returns:
        XYZ of shape ``(..., 3)``.
    """
    flat, batch, n = _rows(coeffs, None, "coeffs")
    return _fspec.to_xyz(_range(range_nm), route, flat, n).reshape(batch + (3,))


def tabulated_xyz(wavelengths_nm: ArrayLike, values: ArrayLike, range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """XYZ of tabulated spectra without projection: the exact integral of
    each polyline against the colour-matching functions over ``range_nm``
    (the reference the routes of :func:`to_xyz` approximate).

    Args:
        wavelengths_nm: shape ``(K,)``.
        values: shape ``(..., K)``.

    Returns:
        XYZ of shape ``(..., 3)``.
    """
    flat, batch, samples = _rows(values, None, "values")
    lam = np.ascontiguousarray(_floats(wavelengths_nm, "wavelengths_nm")).reshape(-1)
    return _fspec.tabulated_xyz(_range(range_nm), lam, flat, samples).reshape(batch + (3,))


def _triples(function, values: ArrayLike, name: str) -> np.ndarray:
    flat, batch, _ = _rows(values, 3, name)
    return function(flat).reshape(batch + (3,))


def xyz_to_linear_srgb(xyz: ArrayLike) -> np.ndarray:
    """Linear sRGB (IEC 61966-2-1, D65 white) of XYZ, shape ``(..., 3)``;
    out-of-gamut colours keep channels below 0 or above 1."""
    return _triples(_fspec.xyz_to_linear_srgb, xyz, "xyz")


def linear_srgb_to_xyz(rgb: ArrayLike) -> np.ndarray:
    """XYZ of linear sRGB, shape ``(..., 3)``."""
    return _triples(_fspec.linear_srgb_to_xyz, rgb, "rgb")


def _elementwise(function, values: ArrayLike, name: str) -> np.ndarray:
    array = _floats(values, name)
    return function(np.ascontiguousarray(array).reshape(-1)).reshape(array.shape)


def srgb_encode(linear: ArrayLike) -> np.ndarray:
    """The sRGB transfer function (linear to encoded), any shape; values are
    clamped to [0, 1] first."""
    return _elementwise(_fspec.srgb_encode, linear, "linear")


def srgb_decode(encoded: ArrayLike) -> np.ndarray:
    """The inverse sRGB transfer function (encoded to linear), any shape;
    values are clamped to [0, 1] first."""
    return _elementwise(_fspec.srgb_decode, encoded, "encoded")


def to_srgb(coeffs: ArrayLike, route: str = "zeroth", range_nm: Range = VISIBLE_RANGE_NM) -> np.ndarray:
    """Encoded sRGB in [0, 1] of spectra given as coefficients: :func:`to_xyz`,
    then :func:`xyz_to_linear_srgb`, then :func:`srgb_encode` (clamping
    out-of-gamut channels). Shape ``(..., 3)``."""
    return srgb_encode(xyz_to_linear_srgb(to_xyz(coeffs, route, range_nm)))


#: The largest number of wavelengths per path of :func:`sample_wavelengths`.
MAX_WAVELENGTHS: int = _fspec.MAX_WAVELENGTHS
#: Rows of a :class:`FourierTable` (``cos theta`` in steps of ``1/(TABLE_ROWS - 1)``).
TABLE_ROWS: int = _fspec.TABLE_ROWS


def sample_wavelengths(
    u: ArrayLike, strategy: str = "hero", range_nm: Range = VISIBLE_RANGE_NM
) -> Tuple[np.ndarray, np.ndarray]:
    """Draws wavelengths for sampled spectral transport, as the renderer does.

    Args:
        u: uniform numbers in ``[0, 1)``, shape ``(..., C)``, ``C`` wavelengths
            per path, 1 to :data:`MAX_WAVELENGTHS`.
        strategy: ``"uniform"`` (independent, ``pdf = 1/W``),
            ``"stratified"`` (one in each of ``C`` equal sub-ranges),
            ``"hero"`` (Wilkie et al. 2014: ``u[..., 0]`` rotated by ``W/C``),
            ``"visible"`` (pbrt-v4's visible importance density) or
            ``"visible-hero"`` (hero rotation in that density's CDF).
        range_nm: the range to sample.

    Returns:
        ``(lambda_nm, pdf_per_nm)``, both of the shape of ``u``: the
        wavelengths and the density (per nm) each estimate divides by.
    """
    flat, batch, count = _rows(u, None, "u")
    lam, pdf = _fspec.sample_wavelengths(_range(range_nm), strategy, flat, count)
    return lam.reshape(batch + (count,)), pdf.reshape(batch + (count,))


def sampled_to_xyz(values: ArrayLike, lambda_nm: ArrayLike, pdf_per_nm: ArrayLike) -> np.ndarray:
    """The sampled estimate of XYZ of paths: ``(1/C) sum_i L(l_i) xbar(l_i) / p(l_i) / int ybar``
    (CIE 1931, zero outside 360-830 nm; zero-density wavelengths skipped),
    normalised as :func:`to_xyz` so both estimate the same colour.

    Args:
        values: radiance at the wavelengths, shape ``(..., C)``.
        lambda_nm, pdf_per_nm: as :func:`sample_wavelengths` returns, the
            shape of ``values``.

    Returns:
        XYZ of shape ``(..., 3)``.
    """
    flat, batch, count = _rows(values, None, "values")
    lam, _, _ = _rows(lambda_nm, count, "lambda_nm")
    pdf, _, _ = _rows(pdf_per_nm, count, "pdf_per_nm")
    return _fspec.sampled_to_xyz(flat, lam, pdf, count).reshape(batch + (3,))


class ControlVariateEstimate(NamedTuple):
    """What :func:`control_variate` returns."""

    #: The control-variate estimate of ``E[Y]``.
    estimate: np.ndarray
    #: The plain Monte Carlo mean of the same samples, for comparison.
    plain: np.ndarray


def control_variate(
    y: ArrayLike,
    c: ArrayLike,
    mu: ArrayLike,
    batch: int = 4,
    method: str = "cross-fit",
) -> ControlVariateEstimate:
    """Estimates ``E[Y]`` with the Fourier estimate as a control variate.

    Per sample ``i``: ``y`` the sampled estimate, ``c`` the path's Fourier
    spectrum pushed through the same estimator at the same wavelengths, ``mu``
    its exact value (so ``E[c - mu] = 0``). Samples are fed in order, in
    batches of ``batch``; every method is unbiased (spectral-core's
    ``control_variate`` module proves it).

    Args:
        y, c: shape ``(..., S)`` (``S`` samples per estimator), or
            ``(..., S, 3)`` for ``"cross-fit-color"``.
        mu: broadcast to the shape of ``y``.
        batch: samples per batch (the last batch may be shorter).
        method: ``"cross-fit"`` (two folds of batches, each weighted by the
            other's shrunk ``alpha``: never worse than plain beyond noise),
            ``"cross-fit-color"`` (the same with a 3 x 3 matrix over XYZ) or
            ``"running"`` (batch ``b`` weighted by ``alpha`` from batches
            before it, the paper's estimator).

    Returns:
        A :class:`ControlVariateEstimate` of shape ``(...)``, or ``(..., 3)``
        for colour.
    """
    y_array, c_array = _floats(y, "y"), _floats(c, "c")
    if y_array.shape != c_array.shape:
        raise ValueError(f"y of shape {y_array.shape} and c of shape {c_array.shape}: expected equal shapes")
    try:
        mu_array = np.broadcast_to(_floats(mu, "mu"), y_array.shape)
    except ValueError as error:
        raise ValueError(f"mu does not broadcast to the shape of y, {y_array.shape}") from error
    color = method == "cross-fit-color"
    minimum_axes = 2 if color else 1
    if y_array.ndim < minimum_axes or (color and y_array.shape[-1] != 3):
        expected = "(..., samples, 3)" if color else "(..., samples)"
        raise ValueError(f"y of shape {y_array.shape}: expected {expected}")
    if y_array.size == 0:
        raise ValueError("y: empty array")
    if isinstance(batch, bool) or not isinstance(batch, (int, np.integer)):
        raise ValueError(f"batch = {batch!r}: expected a whole number of samples")
    batch_shape = y_array.shape[:-2] if color else y_array.shape[:-1]
    samples = y_array.shape[-2] if color else y_array.shape[-1]
    y_flat, c_flat, mu_flat = (np.ascontiguousarray(a).reshape(-1) for a in (y_array, c_array, mu_array))
    estimate, plain = _fspec.control_variate(method, y_flat, c_flat, mu_flat, samples, int(batch))
    shape = batch_shape + ((3,) if color else ())
    return ControlVariateEstimate(estimate.reshape(shape), plain.reshape(shape))


class FourierTable:
    """An angle-dependent reflectance as a Fourier table: :data:`TABLE_ROWS`
    rows of ``n`` coefficients over evenly spaced ``cos theta`` in ``[0, 1]``,
    linear between rows (the renderer's angle-dependent materials). Build one
    with :meth:`dielectric` or :meth:`conductor`."""

    def __init__(self, native: "_fspec.FourierTable", range_nm: Range) -> None:
        self._native = native
        #: The spectral range of the coefficients, nm.
        self.range_nm: Range = range_nm

    @property
    def n(self) -> int:
        """Coefficients per row."""
        return int(self._native.n)

    @classmethod
    def dielectric(
        cls,
        wavelengths_nm: ArrayLike,
        eta: ArrayLike,
        n: int = 12,
        range_nm: Range = VISIBLE_RANGE_NM,
        from_inside: bool = False,
    ) -> "FourierTable":
        """Fresnel reflectance of a dielectric interface; ``eta = n_inside /
        n_outside`` tabulated at ``wavelengths_nm`` (linear between samples,
        flat beyond; positive). ``from_inside``: rays arrive from the denser
        side (total internal reflection included)."""
        lam = np.ascontiguousarray(_floats(wavelengths_nm, "wavelengths_nm")).reshape(-1)
        eta_flat = np.ascontiguousarray(_floats(eta, "eta")).reshape(-1)
        native = _fspec.dielectric_table(_range(range_nm), lam, eta_flat, _coeff_count(n), bool(from_inside))
        return cls(native, _range(range_nm))

    @classmethod
    def conductor(
        cls,
        wavelengths_nm: ArrayLike,
        eta: ArrayLike,
        k: ArrayLike,
        n: int = 12,
        range_nm: Range = VISIBLE_RANGE_NM,
        outside_index: float = 1.0,
    ) -> "FourierTable":
        """Fresnel reflectance of a conductor of complex index ``eta + i k``
        (tabulated at ``wavelengths_nm``; ``eta > 0``, ``k >= 0``) seen from a
        medium of index ``outside_index``."""
        lam = np.ascontiguousarray(_floats(wavelengths_nm, "wavelengths_nm")).reshape(-1)
        eta_flat = np.ascontiguousarray(_floats(eta, "eta")).reshape(-1)
        k_flat = np.ascontiguousarray(_floats(k, "k")).reshape(-1)
        native = _fspec.conductor_table(
            _range(range_nm), lam, eta_flat, k_flat, _coeff_count(n), float(outside_index)
        )
        return cls(native, _range(range_nm))

    def lookup(self, cos_theta: ArrayLike) -> np.ndarray:
        """Coefficients at ``cos_theta`` (any shape, each in ``[0, 1]``):
        shape ``cos_theta.shape + (n,)``."""
        array = _floats(cos_theta, "cos_theta")
        out = self._native.lookup(np.ascontiguousarray(array).reshape(-1))
        return out.reshape(array.shape + (self.n,))

    @property
    def rows(self) -> np.ndarray:
        """The table itself, shape ``(TABLE_ROWS, n)``."""
        return self._native.rows().reshape(TABLE_ROWS, self.n)


class Rendered(NamedTuple):
    """A render with its coefficient planes (``render(..., coefficients=True)``)."""

    #: ``(H, W, 3)`` float32: linear sRGB, or XYZ with ``color="xyz"``.
    image: np.ndarray
    #: ``(H, W, N)`` float32: each pixel's mean Fourier coefficients.
    coefficients: np.ndarray
    #: The spectral range of the coefficients, nm.
    range_nm: Tuple[float, float]
    #: Passes rendered (samples per pixel).
    passes: int


def _flag(arguments: List[str], name: str, value: object) -> None:
    if value is None or value is False:
        return
    if value is True:
        arguments.append(f"--{name}")
    else:
        arguments.append(f"--{name}={value}")


def render(
    scene: Union[str, "os.PathLike[str]"] = "cornell",
    *,
    spp: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    transport: str = "fourier",
    coeffs: Optional[Union[int, str]] = None,
    wavelengths: Optional[int] = None,
    sampling: Optional[str] = None,
    sampler: Optional[str] = None,
    to_color: str = "zeroth",
    buffer: str = "spectral",
    max_depth: Optional[int] = None,
    rr_depth: Optional[int] = None,
    seed: Optional[int] = None,
    filter: Optional[str] = None,
    film: Optional[str] = None,
    hide_emitters: bool = False,
    crop: Optional[Tuple[int, int, int, int]] = None,
    threads: Optional[int] = None,
    time_limit: Optional[float] = None,
    defines: Optional[Mapping[str, object]] = None,
    lenient: bool = False,
    illuminant: Optional[str] = None,
    cv_alpha_per_pixel: bool = False,
    color: str = "linear-srgb",
    coefficients: bool = False,
) -> Union[np.ndarray, Rendered]:
    """Renders a scene as ``fspec render`` does and returns the image.

    ``scene`` is a built-in scene name (:func:`builtin_scenes`), a TOML scene
    file, a Mitsuba 3 scene file (``.xml``) or an OBJ file; it loads exactly
    as on the command line. Every keyword is the command line's option of the
    same name (``fspec render --help``); ``None`` leaves the scene's setting,
    else the command line's default (512 x 512, 64 spp, depth 8, seed 0).
    The same settings give the same pixels as ``fspec render ... --out x.exr``.

    Args:
        scene: scene name or path.
        spp, width, height, max_depth (-1: unlimited), rr_depth, seed: as the
            command line.
        transport: ``"fourier"`` (``coeffs`` in 4, 8, 12, 16, 24, 32, or
            ``"auto"``, the default when not given: chosen from the scene's
            spectra as ``fspec render --coeffs auto``),
            ``"sampled"`` (``wavelengths`` in 1, 2, 4, 8, 12, 16, 32),
            ``"cv"`` (control variates; both in 4, 8, 12) or ``"hybrid"``
            (Fourier until a path meets dispersion, sampled after it;
            ``coeffs`` 12, ``wavelengths`` in 1, 4, 8).
        sampling: ``"uniform"``, ``"stratified"``, ``"hero"``, ``"visible"``,
            ``"lights"`` (the scene's lamps; the default of ``"hybrid"``,
            ``"hero"`` the others').
        sampler: ``"sobol"`` (the default, except with ``"cv"``) or
            ``"independent"``.
        to_color: route from coefficients to colour (:func:`to_xyz`).
        buffer: ``"spectral"`` (coefficients per pixel, converted once) or
            ``"rgb"`` (every sample converted).
        filter: ``"box"``, ``"tent"``, ``"gaussian"``; film: ``"sample"``,
            ``"splat"``.
        crop: ``(x, y, w, h)``, a window of the film (the image is ``h x w``).
        threads: worker threads (the image does not depend on it).
        time_limit: seconds after which the render stops after its batch.
        defines: Mitsuba ``$name`` parameters (``-D name=value``).
        lenient: Mitsuba scenes: unsupported plugins become warnings.
        illuminant: the colorchecker scene's light (built-in name or CSV).
        color: ``"linear-srgb"`` or ``"xyz"``.
        coefficients: also return the coefficient planes (Fourier transport,
            spectral buffer).

    Returns:
        The ``(H, W, 3)`` float32 image, or a :class:`Rendered` with the
        coefficient planes when ``coefficients`` is true.

    Raises:
        ValueError: a bad option, scene or setting (the command line's message).
        FileNotFoundError: the scene file does not exist.
        KeyboardInterrupt: Ctrl-C, checked between batches of passes.
    """
    arguments: List[str] = []
    options: List[Tuple[str, object]] = [
        ("spp", spp),
        ("width", width),
        ("height", height),
        ("transport", transport),
        ("coeffs", coeffs),
        ("wavelengths", wavelengths),
        ("sampling", sampling),
        ("sampler", sampler),
        ("to-color", to_color),
        ("buffer", buffer),
        ("max-depth", max_depth),
        ("rr-depth", rr_depth),
        ("seed", seed),
        ("filter", filter),
        ("film", film),
        ("hide-emitters", bool(hide_emitters)),
        ("threads", threads),
        ("time-limit", time_limit),
        ("lenient", bool(lenient)),
        ("illuminant", illuminant),
        ("cv-alpha-per-pixel", bool(cv_alpha_per_pixel)),
    ]
    for name, value in options:
        _flag(arguments, name, value)
    if crop is not None:
        try:
            x, y, w, h = crop
        except (TypeError, ValueError) as error:
            raise ValueError(f"crop {crop!r}: expected (x, y, width, height)") from error
        arguments.append(f"--crop={x},{y},{w},{h}")
    for name, value in (defines or {}).items():
        arguments.append(f"-D{name}={value}")
    arguments += ["--quiet", "--", os.fspath(scene)]
    image, planes, range_nm, passes, rejected, notices = _fspec.render(arguments, color, bool(coefficients))
    for is_warning, text in notices:
        if is_warning:
            warnings.warn(text, RuntimeWarning, stacklevel=2)
        else:
            _log.info(text)
    if rejected:
        # As the command line's summary: the film dropped these samples.
        warnings.warn(f"{rejected} samples rejected (NaN/Inf)", RuntimeWarning, stacklevel=2)
    if coefficients:
        if planes is None:
            raise RuntimeError("internal error in fspec (please report): no coefficient planes")
        return Rendered(image, planes, range_nm, passes)
    return image
