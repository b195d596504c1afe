"""Camera spectral responses: how a sensor turns the wavelength of each path into its channels.

A response samples one wavelength per path (pdf p(λ), λ in nm) and gives each channel the weight
response_c(λ)/p(λ), so the expected pixel value of channel c is ∫ response_c(λ) L(λ) dλ.

- "lines": one wavelength per channel, the lens's design wavelengths (R = longest): the camera the
  PSF-grid convolution assumes (656/531/486 nm for the doublet); "lines:λ1,λ2,…" names them (nm).
- "srgb": linear sRGB (D65) exactly as Mitsuba's `hdrfilm` develops a spectrum: its CIE 1931
  colour-matching functions over its Y normalisation, then its XYZ → sRGB matrix. The D65
  illuminant of luminance 1 (`mi.cie_d65`, what an RGB emitter of (1, 1, 1) emits) gives (1, 1, 1);
  a flat spectrum of radiance 1 gives (1.206, 0.949, 0.910). Sampled over 380–780 nm (the tails
  to 360 and 830 nm, which the film counts, hold 0.1 % of a flat spectrum's X, Y and Z).
- "mono:λ": one channel at a fixed wavelength λ (nm).
- "table:FILE.csv": a camera's RGB sensitivities, rows "wavelength_nm, r, g, b", white-balanced so
  that D65 of luminance 1 gives (1, 1, 1), as under "srgb".

References: the CIE 1931 2° standard observer's colour-matching functions (CIE 015:2018,
"Colorimetry", 4th ed.), the D65 illuminant and the sRGB primaries (IEC 61966-2-1:1999), as
tabulated by Mitsuba 3 (`mi.cie1931_xyz`, `mi.cie_d65`, `mi.xyz_to_srgb`), which its films use.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..userfiles import read_text

SRGB_RANGE_NM = (380.0, 780.0)
# An RGB image as a spectrum: B below the first edge, G up to the second, R above (nm).
RGB_BANDS_NM = (500.0, 590.0)  # within every catalogue and model glass's range
RESPONSES = ("lines", "srgb", "mono:<nm>", "table:<file.csv>")


@dataclass(frozen=True)
class Response:
    """A tabulated response: wavelength bins [lo_nm[i], hi_nm[i]) with channel weights
    weights[i, c] = response_c / p (p = probability density in the bin); `probability` per bin.
    Discrete lines are bins of zero width."""

    name: str
    channels: tuple[str, ...]
    lo_nm: np.ndarray  # (n,)
    hi_nm: np.ndarray  # (n,)
    probability: np.ndarray  # (n,) sums to 1
    weights: np.ndarray  # (n, C)

    def sample(self, u: np.ndarray):
        """Wavelengths (nm) and channel weights (…, C) for uniform samples u in [0, 1) (NumPy)."""
        cdf = np.concatenate([[0.0], np.cumsum(self.probability)])
        i = np.clip(np.searchsorted(cdf, u, side="right") - 1, 0, len(self.probability) - 1)
        frac = (u - cdf[i]) / np.maximum(self.probability[i], 1e-300)
        lam = self.lo_nm[i] + np.clip(frac, 0.0, 1.0) * (self.hi_nm[i] - self.lo_nm[i])
        return lam, self.weights[i]

    @property
    def single_wavelength(self) -> float | None:
        """The response's one wavelength (nm) when it samples only one (mono:λ, lines:λ), else None."""
        one = len(self.lo_nm) == 1 and self.lo_nm[0] == self.hi_nm[0]
        return float(self.lo_nm[0]) if one else None

    def meta(self) -> dict:
        """Name, channels and sampled wavelength range (nm) for a render's metadata."""
        return {
            "response": self.name,
            "channels": list(self.channels),
            "wavelength_range_nm": [float(self.lo_nm.min()), float(self.hi_nm.max())],
        }


def lines(wavelengths_nm) -> Response:
    """One channel per wavelength (nm, distinct); channels ordered longest first (R, G, B for three)."""
    w = np.sort(np.asarray(wavelengths_nm, dtype=np.float64))[::-1]
    n = len(w)
    names = ("R", "G", "B") if n == 3 else tuple(f"{x:g}nm" for x in w)
    text = "lines:" + ",".join(f"{x:g}" for x in w)
    if not n:
        _bad("lines", "no wavelengths")
    if not np.all(np.isfinite(w) & (w > 0)):
        _bad(text, "the wavelengths must be positive numbers of nm")
    if len({f"{x:g}" for x in w}) < n:  # two channels of one name: the image file would keep one of them
        _bad(text, "each wavelength must differ from the others (one channel each)")
    return Response(text, names, w, w, np.full(n, 1.0 / n), np.eye(n) * n)


def mono(wavelength_nm: float) -> Response:
    """One channel "Y" at one wavelength (nm)."""
    w = np.array([float(wavelength_nm)])
    return Response(f"mono:{wavelength_nm:g}", ("Y",), w, w, np.ones(1), np.ones((1, 1)))


def _mitsuba():
    """Mitsuba's scalar RGB module: its colour tables without choosing the process's variant."""
    from ..llvm import select_libllvm

    select_libllvm()
    import mitsuba

    return mitsuba.scalar_rgb


def _d65(lam: np.ndarray) -> np.ndarray:
    """Mitsuba's D65 illuminant of luminance 1 at `lam` (nm; 0 outside its 360–830 nm)."""
    m = _mitsuba()
    return np.array([m.cie_d65(float(x)) for x in lam])


def _tabulated(name: str, lam: np.ndarray, rgb: np.ndarray, balance: bool) -> Response:
    """Tabulated sensitivities (1 nm steps) → response with p ∝ Σ|response|; with `balance`, scaled so
    that D65 of luminance 1 gives (1, 1, 1)."""
    step = np.diff(lam)
    if not (np.all(step > 0)):
        raise SolasError(f"{name}: wavelengths must increase")
    centre = 0.5 * (rgb[1:] + rgb[:-1])
    if balance:
        white = (centre * (0.5 * (_d65(lam[1:]) + _d65(lam[:-1])) * step)[:, None]).sum(axis=0)
        if np.any(white <= 0):
            raise SolasError(f"{name}: a channel has no positive response (D65 white {white.tolist()})")
        centre = centre / white
    density = np.abs(centre).sum(axis=1)
    prob = density * step
    prob /= prob.sum()
    pdf = prob / step
    weights = np.where(pdf[:, None] > 0, centre / np.maximum(pdf, 1e-300)[:, None], 0.0)
    return Response(name, ("R", "G", "B"), lam[:-1], lam[1:], prob, weights)


def srgb() -> Response:
    """Linear sRGB as Mitsuba's hdrfilm develops it (module docstring), over 380–780 nm at 1 nm."""
    m = _mitsuba()
    lam = np.arange(SRGB_RANGE_NM[0], SRGB_RANGE_NM[1] + 0.5)
    xyz = np.array([list(m.cie1931_xyz(float(x))) for x in lam]) * m.MI_CIE_Y_NORMALIZATION
    to_srgb = np.array([list(m.xyz_to_srgb(m.ScalarColor3f(*e))) for e in np.eye(3)]).T
    return _tabulated("srgb", lam, xyz @ to_srgb.T, balance=False)


def _numbers(line: str) -> bool:
    try:
        [float(v) for v in line.split(",")]
    except ValueError:
        return False
    return True


def table(path: str) -> Response:
    """A camera's RGB sensitivities from a CSV file of rows "wavelength_nm, r, g, b" (one header line
    of column names and "#" comment lines allowed), white-balanced for D65."""
    rows = [
        line
        for line in read_text(path, "camera response table").splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if rows and not _numbers(rows[0]):
        rows = rows[1:]  # a header line of column names
    try:
        data = np.loadtxt(rows, delimiter=",", ndmin=2)
    except ValueError:  # never quote the file's text (a scene may name any file)
        raise SolasError(
            f"camera response table {path!r} is not a CSV table of numbers (rows 'wavelength_nm, "
            "r, g, b', one header line allowed)"
        ) from None
    if data.shape[1] != 4 or len(data) < 2:
        raise SolasError(
            f"camera response table {path!r} must have rows 'wavelength_nm, r, g, b' "
            f"(got {data.shape[1]} columns, {len(data)} rows)"
        )
    if not np.isfinite(data).all():
        row = int(np.argwhere(~np.isfinite(data))[0][0]) + 1
        raise SolasError(f"camera response table {path!r}: data row {row} holds a value that is not a finite number")
    if np.any(data[:, 1:] < 0):
        raise SolasError(f"camera response table {path!r}: sensitivities must be >= 0")
    return _tabulated(f"table:{Path(path).name}", data[:, 0], data[:, 1:], balance=True)


def _bad(text: str, why: str):
    raise SolasError(f"camera response {text!r}: {why}; allowed: {', '.join(RESPONSES)}")


def parse(text: str, lens_wavelengths_nm) -> Response:
    """A response from its name (see the module docstring)."""
    kind, _, arg = str(text).partition(":")
    kind = kind.strip().lower()
    if kind == "lines":
        try:
            given = [float(v) for v in arg.split(",")] if arg.strip() else None
        except ValueError:
            _bad(text, "lines needs comma-separated wavelengths in nm, e.g. lines:630,531,465")
        return lines(lens_wavelengths_nm if given is None else given)
    if kind == "srgb" and not arg:
        return srgb()
    if kind == "mono":
        try:
            w = float(arg)
        except ValueError:
            _bad(text, "mono needs a wavelength in nm, e.g. mono:531")
        if not w > 0:
            _bad(text, "the wavelength must be positive")
        return mono(w)
    if kind == "table" and arg:
        return table(arg)
    _bad(text, "unknown response")


def one_wavelength(text: str, lens_wavelengths_nm) -> float | None:
    """The one wavelength (nm) of the response named `text` (`Response.single_wavelength`), without
    reading a table's file or the colour-matching functions: only "mono" and "lines" can have one."""
    kind = str(text).partition(":")[0].strip().lower()
    return parse(text, lens_wavelengths_nm).single_wavelength if kind in ("mono", "lines") else None


def object_spectrum(text: str) -> str:
    """The `image_object` spectrum (plugins/image_object.py) for the response named `text`: "bands"
    for the line responses (lines, mono), whose channel c sees the image's channel c as the PSF-grid
    convolution does; "srgb" (Mitsuba's smooth spectra, the colour convention) for the rest."""
    return "bands" if str(text).partition(":")[0].strip().lower() in ("lines", "mono") else "srgb"


def check_lens(response: Response, lens) -> None:
    """SolasError when a glass of `lens` has no index at some wavelength the response samples."""
    for w in (response.lo_nm.min(), response.hi_nm.max()):
        lens.check_wavelength(float(w))
