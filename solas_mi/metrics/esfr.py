"""ISO 12233 e-SFR of one slanted-edge ROI, MTF50 and MTF10 (spec §1–2).

The edge is located row by row and fitted; every pixel, projected onto its distance from the edge,
fills a 4× oversampled edge-spread function (ESF), whose derivative (the line-spread function, LSF)
is windowed and Fourier transformed. Mode "2023" follows ISO 12233:2023 as sfrmat5 implements it
(5th-order edge fit, Tukey window over the whole ROI); mode "2017" follows ISO 12233:2017 as sfrmat3
does (linear fit, Hamming window). What cannot be measured is flagged, never returned as a number.

Units: positions in px, frequencies in cycles/px (cy/px) along the edge normal, angles in degrees.
Input pixel values must be linear in scene luminance (decode sRGB before calling). The standards and
sfrmat5/sfrmat3, which the edge fits, windows and rounding follow: docs/details/sharpness.md, References.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage as ndi
from scipy.special import fdtrc

from ..errors import SolasError
from .esfr_result import EsfrResult
from .roi import STEP_ROW_LIMIT, clipped_fraction, linear_pixels, luminance, step_rows

MODES: tuple[str, ...] = ("2023", "2017")
OVERSAMPLING = 4  # ESF bins per px (horizontal distance)
CLIP_LIMIT = 0.005  # fraction of clipped pixels that rejects a ROI
EMPTY_BIN_LIMIT = 0.8  # fraction of empty ESF bins that rejects a ROI (fewer than 4 phases)
LEVEL_SMOOTHING_PX = 2.0  # Gaussian sd of the denoising before the level percentiles
ANGLE_WARN_DEG = 1.0  # half-width of the warning band around 45° and the critical angles
CRITICAL_TANGENTS = (1 / 2, 1 / 3, 1 / 4)
LOW_CONTRAST = 0.2
HIGH_NOISE = 0.05  # noise sd as a fraction of the step
LSF_WIDTHS_ACROSS = 12  # ROI narrower than ±6 LSF widths biases MTF50 upward
FIT_P_VALUE = 0.01  # significance the 5th-order terms must reach on noisy edges
FIT_MOVE_PX = 0.1  # edge shift by the 5th-order terms that matters


def matlab_round(x: float) -> int:
    """Round halves away from zero, as MATLAB's round does (Python rounds halves to even)."""
    return int(math.copysign(math.floor(abs(x) + 0.5), x))


def check_mode(mode: str) -> None:
    """SolasError unless `mode` is one of MODES."""
    if mode not in MODES:
        raise SolasError(f"mode {mode!r} is not supported: allowed {', '.join(MODES)}")


def _window(pos: np.ndarray, centre: np.ndarray | float, half_width: np.ndarray | float, kind: str) -> np.ndarray:
    """Cosine window centred on `centre`, reaching its end value `half_width` px away.

    "tukey": Tukey α = 1 (Hann), "hamming": Hamming; both span the whole array.
    """
    c = np.cos(np.pi * np.clip((pos - centre) / half_width, -1.0, 1.0))
    return 0.5 + 0.5 * c if kind == "tukey" else 0.54 + 0.46 * c


def _crossing(freq: np.ndarray, sfr: np.ndarray, level: float) -> float | None:
    """First frequency where the SFR falls below `level` (linear interpolation); None above 0.5 cy/px."""
    below = np.flatnonzero(sfr[1:] < level) + 1
    if below.size == 0:
        return None
    i = below[0]
    f = freq[i - 1] + (sfr[i - 1] - level) / (sfr[i - 1] - sfr[i]) * (freq[i] - freq[i - 1])
    return float(f) if f <= 0.5 else None


def _fit_edge(loc: np.ndarray, ok: np.ndarray, order: int) -> np.polynomial.Polynomial:
    """Least-squares x_edge = P(y) over the rows `ok`, in centred/scaled row coordinates."""
    y = np.flatnonzero(ok).astype(np.float64)
    return np.polynomial.Polynomial.fit(y, loc[ok], order)


def _angle_warnings(theta: float) -> list[str]:
    out = []
    if theta > 45.0 + ANGLE_WARN_DEG:
        out.append(
            f"edge angle {theta:.2f}° from the ROI's axis exceeds 45°: choose a ROI whose opposite "
            "borders the edge crosses at less than 45°"
        )
    if abs(theta - 45.0) < ANGLE_WARN_DEG:
        out.append(f"edge angle {theta:.2f}° is within {ANGLE_WARN_DEG}° of 45°: expect −1…−4 % SFR error")
    for t in CRITICAL_TANGENTS:
        crit = math.degrees(math.atan(t))
        if abs(theta - crit) < ANGLE_WARN_DEG:
            out.append(
                f"edge angle {theta:.2f}° is within {ANGLE_WARN_DEG}° of the critical angle "
                f"{crit:.2f}° (tan θ = 1/{round(1 / t)}): expect −1…−4 % SFR error"
            )
    return out


# long: the public API's numpydoc docstring is half of it
def esfr(
    roi: np.ndarray,
    *,
    mode: str = "2023",
    full_scale: float | None = 1.0,
    channel: int | None = None,
) -> EsfrResult:
    """The ISO 12233 e-SFR of a ROI holding one slanted edge that crosses two opposite borders.

    Each stage fills its part of the result, or its `reason` when the ROI fails it (the result is then
    returned, not valid): what cannot be measured is flagged, never returned as a number.

    Parameters
    ----------
    roi : numpy.ndarray
        H×W or H×W×C values linear in scene luminance, at least 8×8 px.
    mode : str, default "2023"
        One of `MODES`: "2023", 5th-order edge fit and Tukey α = 1 windows (sfrmat5); "2017", linear fit
        and Hamming (sfrmat3).
    full_scale : float or None, default 1.0
        The saturation level; None: no upper clip test.
    channel : int, optional
        Measure this colour channel instead of luminance.

    Returns
    -------
    EsfrResult
        The SFR over frequencies in cy/px along the edge normal, MTF50 and MTF10 (cy/px), the edge's angle
        (degrees) and the diagnostics.

    Raises
    ------
    SolasError
        For an unknown mode, or a ROI that is not an image of finite values of at least 8×8 px.

    Examples
    --------
    >>> from solas_mi.metrics import slanted_edge
    >>> from solas_mi.metrics.esfr import esfr
    >>> result = esfr(slanted_edge((100, 100), angle_deg=5.0, sigma_px=1.0))
    >>> result.valid, round(result.mtf50, 3), round(result.angle_deg, 2)
    (True, 0.18, 5.0)
    """
    check_mode(mode)
    data = linear_pixels(roi, "ROI")
    kind = "tukey" if mode == "2023" else "hamming"
    res = EsfrResult(mode=str(mode), valid=False)
    res.clipped_fraction = clipped_fraction(data, full_scale)
    a, sign = _oriented(luminance(data, channel), res)
    if not _edge_levels(a, sign, res):
        return res
    edge = _edge_fit(a, sign, mode, kind, res)
    if edge is None:
        return res
    edge_x, line = edge
    n_used = _phase_rows(a.shape[0], line, res)
    if n_used is None:
        return res
    esf = _esf(a[:n_used], edge_x[:n_used], res)
    if esf is None or not _sfr(esf, sign, kind, res):
        return res
    _judge(res, a.shape[1])
    return res


def _oriented(a: np.ndarray, res: EsfrResult) -> tuple[np.ndarray, float]:
    """The luminance `a` turned so that the edge is near-vertical (res.orientation), and the derivative
    sign that makes the LSF positive."""
    band = max(1, min(5, min(a.shape) // 8))
    test_v = abs(a[-band:].mean() - a[:band].mean())
    test_h = abs(a[:, -band:].mean() - a[:, :band].mean())
    if test_v > test_h:
        a = a.T
        res.orientation = "horizontal"
    else:
        res.orientation = "vertical"
    sign = -1.0 if a[:, :band].mean() > a[:, -band:].mean() else 1.0
    return a, sign


def _edge_levels(a: np.ndarray, sign: float, res: EsfrResult) -> bool:
    """Contrast, noise and the rows that are single steps (res); False (res.reason) for a clipped or
    flat ROI or one that is not one step edge."""
    # Edge levels: 5th/95th percentiles of the ROI denoised by a small Gaussian (noise would widen them).
    p5, p95 = np.percentile(ndi.gaussian_filter(a, LEVEL_SMOOTHING_PX, mode="nearest"), [5, 95])
    step = p95 - p5
    res.contrast = float(step / (p95 + p5)) if p95 + p5 > 0 else 0.0
    dv = np.diff(a, axis=0)
    noise_sd = 1.4826 * float(np.median(np.abs(dv - np.median(dv)))) / math.sqrt(2.0)
    if res.clipped_fraction > CLIP_LIMIT:
        res.reason = (
            f"clipped ROI: {100 * res.clipped_fraction:.2f} % of pixels at 0 or full scale "
            f"(limit {100 * CLIP_LIMIT:.1f} %); clipping inflates MTF50"
        )
        return False
    if step <= 0.0:
        res.reason = "no edge: the ROI is flat"
        return False
    res.noise = noise_sd / step
    res.step_rows_fraction, no_run = step_rows(a / step, sign, res.noise)
    if res.step_rows_fraction < STEP_ROW_LIMIT:
        what = "no edge found" if no_run >= 0.5 else "not one step edge (two edges, texture or a line)"
        res.reason = (
            f"{what}: only {100 * res.step_rows_fraction:.0f} % of rows are single steps "
            f"(need ≥ {100 * STEP_ROW_LIMIT:.0f} %)"
        )
        return False
    return True


def _row_centroids(a: np.ndarray, sign: float, kind: str):
    """centroids(centre) → (each row's centroid of the derivative windowed about `centre`, where it
    has one), and the derivative samples' positions (px; sample j sits between pixels j and j+1)."""
    d = 0.5 * np.diff(a, axis=1) * sign
    pos = np.arange(a.shape[1] - 1) + 0.5

    def centroids(centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        half = np.maximum(centre - pos[0], pos[-1] - centre)[:, None]
        w = _window(pos[None, :], centre[:, None], half, kind)
        if kind == "tukey":
            w = 0.95 * w + 0.05  # sfrmat5 keeps a floor for stable edge finding
        dw = d * w
        total = dw.sum(axis=1)
        ok = total > 0
        return np.where(ok, (dw @ pos) / np.where(ok, total, 1.0), np.nan), ok

    return centroids, pos


def _edge_fit(a: np.ndarray, sign: float, mode: str, kind: str, res: EsfrResult):
    """(the fitted edge's column in each row, its straight-line fit), or None (res.reason): row
    centroids of the windowed derivative, edge fit, re-centred windows, refit."""
    nlin, npix = a.shape
    centroids, pos = _row_centroids(a, sign, kind)
    rows = np.arange(nlin, dtype=np.float64)
    order = 5 if mode == "2023" else 1
    centre = np.full(nlin, (npix - 1) / 2.0)
    for first_pass in (True, False):  # windows centred on the ROI, then on the fitted edge
        loc, ok = centroids(centre)
        if np.count_nonzero(ok) < max(order + 3, nlin // 2):
            res.reason = "no edge found: the derivative has no positive centroid in most rows"
            return None
        if first_pass:
            centre = np.clip(_fit_edge(loc, ok, order)(rows), pos[0], pos[-1])
    line = _fit_edge(loc, ok, 1)
    fit, res.fit_order = _supported_fit(loc, ok, rows, order, line, res)
    res.fit_residual_px = float(np.sqrt(np.mean((loc[ok] - fit(rows[ok])) ** 2)))
    edge_x = fit(rows)
    if edge_x.min() < 0 or edge_x.max() > npix - 1:
        res.reason = "the fitted edge leaves the ROI: it must cross two opposite borders"
        return None
    return edge_x, line


def _supported_fit(loc, ok, rows, order: int, line, res: EsfrResult):
    """(fit, its order): the edge fit of `order`, or the straight `line` when an F-test finds the
    higher order not supported by the data and it moves the edge (a warning in res)."""
    if order == 1:
        return line, 1
    fit = _fit_edge(loc, ok, order)
    n_ok = int(np.count_nonzero(ok))
    rss1 = float(np.sum((loc[ok] - line(rows[ok])) ** 2))
    rss5 = float(np.sum((loc[ok] - fit(rows[ok])) ** 2))
    dfd = n_ok - order - 1
    f_stat = math.inf if rss5 <= 0 else ((rss1 - rss5) / (order - 1)) / (rss5 / dfd)
    p_value = float(fdtrc(order - 1, dfd, f_stat)) if math.isfinite(f_stat) else 0.0
    moved = float(np.max(np.abs(fit(rows) - line(rows))))
    if p_value > FIT_P_VALUE and moved > FIT_MOVE_PX:
        res.warnings.append(
            f"5th-order edge fit not supported by the data (p = {p_value:.2f}, it moves the edge "
            f"{moved:.2f} px): noisy edge, fell back to a linear fit"
        )
        return line, 1
    return fit, order


def _phase_rows(nlin: int, line, res: EsfrResult) -> int | None:
    """The rows used, an integer number of phase cycles of the edge (res.angle_deg, res.rows_used),
    or None (res.reason) for an edge too close to 0°."""
    slope = float(line.convert().coef[1])  # dx/dy of the straight-line fit
    theta = math.degrees(math.atan(abs(slope)))
    res.angle_deg = theta
    if nlin * abs(slope) < 1.0:
        res.reason = (
            f"edge angle {theta:.3f}° is below atan(1/rows) = {math.degrees(math.atan(1 / nlin)):.3f}° "
            "(too close to 0°): less than one phase cycle, no SFR can be measured"
        )
        return None
    res.rows_used = min(nlin, matlab_round(math.floor(nlin * abs(slope)) / abs(slope)))
    return res.rows_used


def _esf(a: np.ndarray, px_edge: np.ndarray, res: EsfrResult) -> np.ndarray | None:
    """The 4× oversampled ESF of rows `a` from the horizontal distance of every pixel to the fitted
    edge `px_edge` (res.empty_bins), or None (res.reason) when too many bins are empty."""
    npix = a.shape[1]
    dist = np.arange(npix)[None, :] - px_edge[:, None]
    nn = OVERSAMPLING * npix
    mid = (npix - 1 - px_edge.min() - px_edge.max()) / 2.0
    start = matlab_round(OVERSAMPLING * mid) - nn // 2
    k = np.ceil(OVERSAMPLING * dist).astype(np.int64) - start
    inside = (k >= 0) & (k < nn)
    counts = np.bincount(k[inside], minlength=nn)
    sums = np.bincount(k[inside], weights=a[inside], minlength=nn)
    filled = counts > 0
    res.empty_bins = int(nn - np.count_nonzero(filled))
    if res.empty_bins > EMPTY_BIN_LIMIT * nn:
        res.reason = (
            f"{res.empty_bins} of {nn} ESF bins are empty: the edge angle {res.angle_deg:.2f}° samples too few phases"
        )
        return None
    idx = np.arange(nn)
    esf = np.interp(idx, idx[filled], sums[filled] / counts[filled])
    if res.empty_bins:
        res.warnings.append(f"{res.empty_bins} of {nn} ESF bins were empty and filled from neighbours")
    return esf


def _sfr(esf: np.ndarray, sign: float, kind: str, res: EsfrResult) -> bool:
    """The SFR of `esf` (res.freq in cy/px along the normal, res.sfr, res.esf, res.lsf_width_px): its
    LSF centred on its peak, windowed over the whole ROI; False (res.reason) for an LSF of no area."""
    nn = len(esf)
    idx = np.arange(nn)
    lsf = np.empty(nn)
    lsf[1:-1] = 0.5 * (esf[2:] - esf[:-2]) * sign
    lsf[0], lsf[-1] = lsf[1], lsf[-2]
    peak = float(np.mean(np.flatnonzero(lsf == lsf.max())))
    shift = matlab_round(nn // 2 - peak)
    centred = np.zeros(nn)
    if shift >= 0:
        centred[shift:] = lsf[: nn - shift]
    else:
        centred[: nn + shift] = lsf[-shift:]
    delta = math.cos(math.radians(res.angle_deg)) / OVERSAMPLING  # bin width along the normal, px
    res.lsf_width_px = float(np.sum(centred) / np.max(centred) * delta)
    spectrum = np.abs(np.fft.rfft(centred * _window(idx, nn // 2, nn // 2, kind)))
    if spectrum[0] <= 0:
        res.reason = "no edge found: the LSF has no positive area"
        return False
    n_out = nn // 4 + 1  # up to 1/cos θ cy/px, as sfrmat
    sfr = spectrum[:n_out] / spectrum[0]
    x = 2.0 * np.pi * np.arange(1, n_out) / nn
    sfr[1:] *= np.minimum(x / np.sin(x), 10.0)  # response of the [0.5, 0, −0.5] derivative
    res.freq = np.arange(n_out) / (nn * delta)
    res.sfr = sfr
    res.esf = esf
    return True


def _judge(res: EsfrResult, npix: int) -> None:
    """A measured SFR: valid, its warnings (angle, contrast, noise, ROI width) and MTF50/MTF10."""
    res.valid = True
    res.warnings.extend(_angle_warnings(res.angle_deg))
    if res.contrast < LOW_CONTRAST:
        res.warnings.append(f"low edge contrast {res.contrast:.2f} (< {LOW_CONTRAST}): SFR error is high")
    if res.noise > HIGH_NOISE:
        res.warnings.append(f"noisy edge: noise sd is {100 * res.noise:.1f} % of the step")
    across = npix * math.cos(math.radians(res.angle_deg))
    if across < LSF_WIDTHS_ACROSS * res.lsf_width_px:
        res.warnings.append(
            f"ROI spans {across:.0f} px across the edge, less than ±{LSF_WIDTHS_ACROSS // 2} LSF widths "
            f"({LSF_WIDTHS_ACROSS * res.lsf_width_px:.0f} px): MTF50 is biased upward"
        )
    res.mtf50 = _crossing(res.freq, res.sfr, 0.5)
    res.mtf10 = _crossing(res.freq, res.sfr, 0.1)
    if res.mtf50 is None:
        res.mtf50_reason = "not found"
        res.warnings.append("MTF50 not found: the SFR stays above 0.5 up to 0.5 cy/px")
