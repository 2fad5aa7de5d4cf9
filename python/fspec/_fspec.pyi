"""Type stubs of the native module ``fspec._fspec`` (src/ of this package).

Every array argument is a flat, C-contiguous ``float64`` array; the Python
half (``fspec/__init__.py``) reshapes. Functions raise ``ValueError`` with a
one-line message on bad input.
"""

from typing import List, Optional, Tuple, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "MAX_COEFFS", "CIE_RANGE_NM", "VISIBLE_RANGE_NM", "project_tabulated", "project_blackbody",
    "upsample_rgb", "project_builtin", "builtin_names", "builtin_table", "product", "evaluate",
    "mese", "bounded_mese", "to_xyz", "tabulated_xyz", "xyz_to_linear_srgb", "linear_srgb_to_xyz",
    "srgb_encode", "srgb_decode", "render", "builtin_scenes", "MAX_WAVELENGTHS",
    "sample_wavelengths", "sampled_to_xyz", "control_variate", "TABLE_ROWS", "FourierTable",
    "dielectric_table", "conductor_table",
]

_F64 = npt.NDArray[np.float64]
_F32 = npt.NDArray[np.float32]
_Range = Tuple[float, float]

MAX_COEFFS: int
CIE_RANGE_NM: _Range
VISIBLE_RANGE_NM: _Range

def project_tabulated(range_nm: _Range, lambda_nm: _F64, values: _F64, samples: int, n: int) -> _F64:
    """Rows of ``samples`` values (polylines) projected onto ``n`` coefficients;
    ``lambda_nm`` is one shared row or one row per spectrum."""

def project_blackbody(range_nm: _Range, temperatures_k: _F64, n: int) -> _F64:
    """Peak-normalised blackbodies projected onto ``n`` coefficients each."""

def upsample_rgb(range_nm: _Range, kind: str, rgb: _F64, n: int) -> _F64:
    """Rows of linear sRGB as spectra of ``kind`` ("reflectance", "unbounded", "illuminant")."""

def project_builtin(range_nm: _Range, name: str, n: int) -> _F64:
    """The ``n`` coefficients of a built-in spectrum."""

def builtin_names() -> List[Tuple[str, str]]:
    """``(name, description)`` of every tabulated built-in spectrum."""

def builtin_table(name: str) -> Tuple[_F64, _F64]:
    """``(wavelengths_nm, values)`` of a tabulated built-in spectrum."""

def product(a: _F64, b: _F64, n: int) -> _F64:
    """Row-by-row truncated products of rows of ``n`` coefficients."""

def evaluate(range_nm: _Range, coeffs: _F64, n: int, lambda_nm: _F64) -> _F64:
    """The truncated series of each row at every wavelength (rows of ``len(lambda_nm)``)."""

def mese(range_nm: _Range, coeffs: _F64, n: int, lambda_nm: _F64) -> _F64:
    """The unbounded MESE density of each row at every wavelength."""

def bounded_mese(range_nm: _Range, coeffs: _F64, n: int, lambda_nm: _F64) -> _F64:
    """The bounded MESE reconstruction of each row at every wavelength."""

def to_xyz(range_nm: _Range, route: str, coeffs: _F64, n: int) -> _F64:
    """XYZ (rows of 3) of rows of ``n`` coefficients by ``route``."""

def tabulated_xyz(range_nm: _Range, lambda_nm: _F64, values: _F64, samples: int) -> _F64:
    """XYZ (rows of 3) of rows of tabulated values over shared wavelengths."""

def xyz_to_linear_srgb(xyz: _F64) -> _F64: ...
def linear_srgb_to_xyz(rgb: _F64) -> _F64: ...
def srgb_encode(linear: _F64) -> _F64: ...
def srgb_decode(encoded: _F64) -> _F64: ...

def render(
    arguments: List[str], color: str, coefficients: bool
) -> Tuple[_F32, Optional[_F32], _Range, int, int, List[Tuple[bool, str]]]:
    """``fspec render`` with command-line ``arguments``: the ``(H, W, 3)`` image,
    the ``(H, W, N)`` coefficient planes if asked for, the spectral range, the
    passes done, the rejected samples and the notices ``(is_warning, text)``."""

def builtin_scenes() -> List[Tuple[str, str]]:
    """``(name, description)`` of every built-in scene."""

MAX_WAVELENGTHS: int
TABLE_ROWS: int

def sample_wavelengths(range_nm: _Range, strategy_name: str, u: _F64, count: int) -> Tuple[_F64, _F64]:
    """Rows of ``count`` uniform numbers in [0, 1) -> ``(lambda_nm, pdf_per_nm)``, flat."""

def sampled_to_xyz(values: _F64, lambda_nm: _F64, pdf_per_nm: _F64, count: int) -> _F64:
    """Rows of ``count`` sampled values -> XYZ, 3 per row."""

def control_variate(method: str, y: _F64, c: _F64, mu: _F64, samples: int, batch: int) -> Tuple[_F64, _F64]:
    """``(estimate, plain)`` per estimator; ``method`` "running", "cross-fit" or "cross-fit-color"."""

@final
class FourierTable:
    """A Fourier table of ``TABLE_ROWS`` rows of ``n`` coefficients over cos theta."""

    @property
    def n(self) -> int: ...
    def lookup(self, cos_theta: _F64) -> _F64:
        """Coefficients at each cos theta in [0, 1], row after row."""
    def rows(self) -> _F64:
        """Every row's coefficients, ``TABLE_ROWS * n`` values."""

def dielectric_table(range_nm: _Range, lambda_nm: _F64, eta: _F64, n: int, from_inside: bool) -> FourierTable:
    """Fresnel reflectance of a dielectric of relative index ``eta`` tabulated at ``lambda_nm``."""

def conductor_table(
    range_nm: _Range, lambda_nm: _F64, eta: _F64, k: _F64, n: int, outside_index: float
) -> FourierTable:
    """Fresnel reflectance of a conductor of index ``eta + i k`` tabulated at ``lambda_nm``."""
