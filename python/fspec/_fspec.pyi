"""Type stubs of the native module ``fspec._fspec`` (src/ of this package).

Every array argument is a flat, C-contiguous ``float64`` array; the Python
half (``fspec/__init__.py``) reshapes. Functions raise ``ValueError`` with a
one-line message on bad input.
"""

from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
F32 = npt.NDArray[np.float32]
Range = Tuple[float, float]

MAX_COEFFS: int
CIE_RANGE_NM: Range
VISIBLE_RANGE_NM: Range

def project_tabulated(range_nm: Range, lambda_nm: F64, values: F64, samples: int, n: int) -> F64:
    """Rows of ``samples`` values (polylines) projected onto ``n`` coefficients;
    ``lambda_nm`` is one shared row or one row per spectrum."""

def project_blackbody(range_nm: Range, temperatures_k: F64, n: int) -> F64:
    """Peak-normalised blackbodies projected onto ``n`` coefficients each."""

def upsample_rgb(range_nm: Range, kind: str, rgb: F64, n: int) -> F64:
    """Rows of linear sRGB as spectra of ``kind`` ("reflectance", "unbounded", "illuminant")."""

def project_builtin(range_nm: Range, name: str, n: int) -> F64:
    """The ``n`` coefficients of a built-in spectrum."""

def builtin_names() -> List[Tuple[str, str]]:
    """``(name, description)`` of every tabulated built-in spectrum."""

def builtin_table(name: str) -> Tuple[F64, F64]:
    """``(wavelengths_nm, values)`` of a tabulated built-in spectrum."""

def product(a: F64, b: F64, n: int) -> F64:
    """Row-by-row truncated products of rows of ``n`` coefficients."""

def evaluate(range_nm: Range, coeffs: F64, n: int, lambda_nm: F64) -> F64:
    """The truncated series of each row at every wavelength (rows of ``len(lambda_nm)``)."""

def mese(range_nm: Range, coeffs: F64, n: int, lambda_nm: F64) -> F64:
    """The unbounded MESE density of each row at every wavelength."""

def bounded_mese(range_nm: Range, coeffs: F64, n: int, lambda_nm: F64) -> F64:
    """The bounded MESE reconstruction of each row at every wavelength."""

def to_xyz(range_nm: Range, route: str, coeffs: F64, n: int) -> F64:
    """XYZ (rows of 3) of rows of ``n`` coefficients by ``route``."""

def tabulated_xyz(range_nm: Range, lambda_nm: F64, values: F64, samples: int) -> F64:
    """XYZ (rows of 3) of rows of tabulated values over shared wavelengths."""

def xyz_to_linear_srgb(xyz: F64) -> F64: ...
def linear_srgb_to_xyz(rgb: F64) -> F64: ...
def srgb_encode(linear: F64) -> F64: ...
def srgb_decode(encoded: F64) -> F64: ...

def render(
    arguments: List[str], color: str, coefficients: bool
) -> Tuple[F32, Optional[F32], Range, int, int, List[Tuple[bool, str]]]:
    """``fspec render`` with command-line ``arguments``: the ``(H, W, 3)`` image,
    the ``(H, W, N)`` coefficient planes if asked for, the spectral range, the
    passes done, the rejected samples and the notices ``(is_warning, text)``."""

def builtin_scenes() -> List[Tuple[str, str]]:
    """``(name, description)`` of every built-in scene."""
