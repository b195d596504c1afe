"""Natural-scene SFR (NS-SFR, the SOLAS paper's SS-SFR): slanted edges found in an image, the e-SFR
of each, and MTF50 statistics per radial annulus; a before/after comparison measures identical ROIs
(spec §4), reported per annulus (`nssfr_report.NsSfrReport`). `plot_report` draws the SOLAS paper's
figure 5.

ROIs are (x, y, w, h) in px; radii are fractions of R, the centre-to-corner distance; MTF50 in cy/px.
The method follows van Zwanenberg et al.'s NS-SFR (JIST 65(6), 2021) and the SOLAS paper's SS-SFR; the
references: docs/details/sharpness.md, References.
"""
from __future__ import annotations

import math
import os
from collections import Counter
from collections.abc import Sequence

import numpy as np
from scipy import ndimage as ndi
from skimage.feature import canny

from ..errors import SolasError
from .annuli import ANNULI, ANNULUS_NAMES, annulus_index, radius_fraction
from .esfr import EsfrResult, esfr, matlab_round
from .nssfr_report import CURVE_FREQ, AnnulusStats, NsSfrReport, RoiMeasurement
from .roi import Roi, crop, linear_pixels, luminance

CONTRAST_BANDS: dict[str, tuple[float, float]] = {"automotive": (0.1, 0.9), "chart": (0.55, 0.65)}
ANGLE_RANGE_DEG = (2.5, 42.5)
MAX_OVERSHOOT = 1.4  # a local SFR maximum above this is implausible
MIN_MTF50 = 0.1  # cy/px; lower values are rejected unless the whole image is that soft
POLY_ORDER = 4
POLY_DEVIATION = 0.2  # SFR deviation from its 4th-order fit that counts as a bad frequency
POLY_BAD_FRACTION = 0.1  # fraction of bad frequencies that rejects a curve
NS_MARGINS = (10,)  # px each side of an edge's bounding box (spec §4.3)
CHART_MARGINS = (32, 24, 16, 10)  # widest first: chart ROIs as wide as the layout allows
ROW_GUARD_PX = 10  # rows kept this far from rows where another edge enters the ROI
CANNY_SIGMA = 1.5
CANNY_THRESHOLDS = (0.04, 0.1)  # on the Sobel magnitude of the image scaled to its 99.9th percentile


def _longest_run(flags: np.ndarray) -> tuple[int, int]:
    """(start, stop) of the longest run of True values; (0, 0) if none."""
    d = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    if starts.size == 0:
        return 0, 0
    i = int(np.argmax(stops - starts))
    return int(starts[i]), int(stops[i])


def _segment_rois(
    mask: np.ndarray, edges: np.ndarray, margins: Sequence[int], max_rows: int | None, min_rows: int
) -> list[Roi]:
    """ROIs (x, y, w, h) around the near-vertical edge segments of `mask`.

    A segment's rows are trimmed to the longest run free of other edge pixels inside the ROI and
    at least ROW_GUARD_PX rows from such pixels (isolation from texture and from the adjacent sides
    of a square); the ROI spans the segment's columns widened by the chosen margin each side.
    """
    _height, width = mask.shape
    labels, _ = ndi.label(mask, structure=np.ones((3, 3), bool))
    out: list[Roi] = []
    for label, box in enumerate(ndi.find_objects(labels), start=1):
        if box is None or box[0].stop - box[0].start < min_rows:
            continue
        box_rows, box_cols = box
        segment = labels[box] == label
        row_has_edge = segment.any(axis=1)
        first_col = segment.argmax(axis=1) + box_cols.start
        last_col = segment.shape[1] - 1 - segment[:, ::-1].argmax(axis=1) + box_cols.start

        def clean(top: int, bottom: int, pad: int) -> tuple[int, int, int, int] | None:
            """Rows top…bottom trimmed clear of other edges `pad` columns about it: (top, bottom, left, right)."""
            while bottom - top >= min_rows:
                rows = slice(top - box_rows.start, bottom - box_rows.start)
                if not row_has_edge[rows].any():
                    return None
                lo, hi = first_col[rows][row_has_edge[rows]].min(), last_col[rows][row_has_edge[rows]].max()
                left, right = max(0, lo - pad), min(width, hi + 1 + pad)
                dirty = (edges[top:bottom, left:right] & (labels[top:bottom, left:right] != label)).any(axis=1)
                dirty = ndi.maximum_filter1d(dirty, 2 * ROW_GUARD_PX + 1, mode="constant")
                if not dirty.any():
                    if min(lo - left, right - 1 - hi) < pad // 2:
                        return None  # the edge runs too close to the image border
                    return top, bottom, left, right
                run_start, run_stop = _longest_run(~dirty)
                top, bottom = top + run_start, top + run_stop
            return None

        spans = {pad: clean(box_rows.start, box_rows.stop, pad) for pad in margins}
        narrow = spans[min(margins)]
        if narrow is None:
            continue
        margin, widest = max(((pad, span) for pad, span in spans.items() if span is not None
                              and span[1] - span[0] >= 0.5 * (narrow[1] - narrow[0])), key=lambda found: found[0])
        top, bottom = widest[:2]
        n_rows = bottom - top
        if max_rows is None or n_rows <= max_rows:
            starts = [top]
            size = n_rows
        else:
            count = math.ceil((n_rows - max_rows) / (max_rows / 2)) + 1
            starts = [matlab_round(start) for start in np.linspace(top, bottom - max_rows, count)]
            size = max_rows
        for start in starts:
            span = clean(start, start + size, margin)
            if span is not None:
                y0, y1, x0, x1 = span
                out.append((int(x0), int(y0), int(x1 - x0), int(y1 - y0)))
    return out


def find_edge_rois(
    luma: np.ndarray,
    *,
    margins: Sequence[int] = NS_MARGINS,
    max_rows: int | None = 128,
    min_rows: int = 20,
) -> list[Roi]:
    """Candidate slanted-edge ROIs (x, y, w, h) in a linear luminance image (spec §4.1–4.3).

    Canny edges are split into near-vertical and near-horizontal by gradient direction; segments
    shorter than `min_rows` px are dropped; ROIs hold rows free of other edges within the margin and
    are split into overlapping pieces of ≤ `max_rows` rows (None: no split). With several margins,
    the widest that keeps at least half the rows of the narrowest is used.
    """
    scale = float(np.percentile(luma, 99.9))
    if not scale > 0:
        return []
    img = luma / scale
    edges = canny(img, sigma=CANNY_SIGMA, low_threshold=CANNY_THRESHOLDS[0], high_threshold=CANNY_THRESHOLDS[1])
    smooth = ndi.gaussian_filter(img, CANNY_SIGMA)
    near_vertical = edges & (np.abs(ndi.sobel(smooth, axis=1)) >= np.abs(ndi.sobel(smooth, axis=0)))
    rois = _segment_rois(near_vertical, edges, margins, max_rows, min_rows)
    transposed = _segment_rois((edges & ~near_vertical).T, edges.T, margins, max_rows, min_rows)
    rois += [(y, x, h, w) for x, y, w, h in transposed]
    return sorted(rois)


def _curve_problem(res: EsfrResult) -> str | None:
    """Why an SFR curve is implausible (spec §4.6), or None."""
    m = res.freq <= 0.5
    f, s = res.freq[m], res.sfr[m]
    peaks = (s[1:-1] >= s[:-2]) & (s[1:-1] >= s[2:]) & (s[1:-1] > MAX_OVERSHOOT)
    if peaks.any():
        return f"SFR local maximum above {MAX_OVERSHOOT}"
    fit = np.polynomial.Polynomial.fit(f, s, POLY_ORDER)
    if np.mean(np.abs(s - fit(f)) > POLY_DEVIATION) > POLY_BAD_FRACTION:
        return f"SFR deviates > {POLY_DEVIATION} from a 4th-order fit at many frequencies"
    return None


# long: the public API's numpydoc docstring is half of it
def natural_scene_sfr(
    image: np.ndarray,
    *,
    compare: np.ndarray | None = None,
    annuli: str = "automotive",
    mode: str = "2023",
    contrast: str = "automotive",
    full_scale: float | None = 1.0,
) -> NsSfrReport:
    """The natural-scene SFR of an image: edges found, an e-SFR each, MTF50 statistics per annulus.

    Parameters
    ----------
    image : numpy.ndarray
        H×W[×C] linear values, at least `roi.MIN_ROI_PX` a side.
    compare : numpy.ndarray, optional
        Another image of the same size, measured on the same ROIs (before/after).
    annuli : str, default "automotive"
        The annuli, a scheme of `annuli.ANNULI`: "automotive" (0.24 / 0.6 / 1.0 R) or "equal-area".
    mode : str, default "2023"
        The e-SFR mode (`esfr.MODES`).
    contrast : str, default "automotive"
        The band of (p95 − p5)/(p95 + p5) an edge's contrast must lie in, a key of `CONTRAST_BANDS`.
    full_scale : float or None, default 1.0
        The saturation level; None: none.

    Returns
    -------
    NsSfrReport
        The ROIs measured and MTF50 statistics (cy/px) per annulus, before and after; the ROIs rejected
        per reason.

    Raises
    ------
    SolasError
        For an unknown scheme, band or mode, or images of different sizes or not images.

    Examples
    --------
    >>> from solas_mi.metrics import natural_scene_sfr, slanted_edge
    >>> report = natural_scene_sfr(slanted_edge((240, 320), 5.0, 1.0), compare=slanted_edge((240, 320), 5.0, 2.0))
    >>> [(annulus.name, annulus.count) for annulus in report.before]
    [('centre', 1), ('middle', 2), ('edge', 0)]
    """
    if annuli not in ANNULI:
        raise SolasError(f"annuli scheme {annuli!r} is not supported: allowed {', '.join(ANNULI)}")
    if contrast not in CONTRAST_BANDS:
        raise SolasError(f"contrast band {contrast!r} is not supported: allowed {', '.join(CONTRAST_BANDS)}")
    image = linear_pixels(image, "image")
    if compare is not None:
        compare = linear_pixels(compare, "comparison image")
        if compare.shape[:2] != image.shape[:2]:
            raise SolasError(
                f"comparison image is {compare.shape[1]}×{compare.shape[0]} px, the image is "
                f"{image.shape[1]}×{image.shape[0]} px: they must be the same size"
            )
    rejected: Counter[str] = Counter()
    found = _edge_rois(image, mode, contrast, full_scale, rejected)
    measured = _measured(found, image.shape[:2], annuli, compare, mode, full_scale, rejected)
    edges_r = (0.0, *ANNULI[annuli])

    def stats(pick: str) -> list[AnnulusStats]:
        return [
            AnnulusStats.of(name, edges_r[i], edges_r[i + 1],
                            [getattr(m, pick) for m in measured if m.annulus == i])
            for i, name in enumerate(ANNULUS_NAMES)
        ]

    return NsSfrReport(
        shape=image.shape[:2], scheme=annuli, mode=str(mode), rois=measured, before=stats("before"),
        after=stats("after") if compare is not None else None, rejected=dict(rejected),
    )


def _edge_rois(image: np.ndarray, mode: str, contrast: str, full_scale: float | None,
               rejected: Counter[str]) -> list[tuple[Roi, EsfrResult]]:
    """The edge ROIs of `image` whose e-SFR passes the NS-SFR tests (contrast band, angle, curve, and
    no outlier MTF50 far below the others'); each rejection counted in `rejected` by its reason."""
    c_lo, c_hi = CONTRAST_BANDS[contrast]
    found: list[tuple[Roi, EsfrResult]] = []
    for roi in find_edge_rois(luminance(image)):
        res = esfr(crop(image, roi), mode=mode, full_scale=full_scale)
        edge_contrast, angle_deg = res.contrast, res.angle_deg  # both measured in a valid result
        why: str | None
        if not res.valid or edge_contrast is None or angle_deg is None:
            why = "invalid e-SFR"
        elif not c_lo < edge_contrast < c_hi:
            why = f"contrast outside ({c_lo}, {c_hi})"
        elif not ANGLE_RANGE_DEG[0] <= angle_deg <= ANGLE_RANGE_DEG[1]:
            why = f"angle outside {ANGLE_RANGE_DEG[0]}–{ANGLE_RANGE_DEG[1]}°"
        elif res.mtf50 is None:
            why = "MTF50 not found"
        else:
            why = _curve_problem(res)
        if why:
            rejected[why] += 1
        else:
            found.append((roi, res))
    if found:
        floor = min(MIN_MTF50, 0.5 * float(np.median([r.mtf50 for _, r in found])))
        low = [f for f in found if f[1].mtf50 < floor]  # type: ignore[operator]  # each found has an MTF50
        if low:
            rejected[f"MTF50 below {MIN_MTF50} cy/px in a sharper image"] += len(low)
            found = [f for f in found if f[1].mtf50 >= floor]  # type: ignore[operator]  # each found has one
    return found


def _measured(found: list[tuple[Roi, EsfrResult]], shape: tuple[int, int], annuli: str, compare: np.ndarray | None,
              mode: str, full_scale: float | None, rejected: Counter[str]) -> list[RoiMeasurement]:
    """Each ROI of `found` placed in its annulus of an image of `shape` (rows, columns), with the same
    ROI's e-SFR in `compare` when given (a ROI invalid there is counted in `rejected` and dropped)."""
    height, width = shape
    measured: list[RoiMeasurement] = []
    for roi, res in found:
        x, y, w, h = roi
        r = float(radius_fraction(x + (w - 1) / 2, y + (h - 1) / 2, height, width))
        m = RoiMeasurement(roi, r, int(annulus_index(r, annuli)), res)
        if compare is not None:
            after = esfr(crop(compare, roi), mode=mode, full_scale=full_scale)
            if not after.valid or after.mtf50 is None:
                rejected["comparison image: invalid e-SFR or MTF50 not found"] += 1
                continue
            m.after = after
        measured.append(m)
    return measured


def plot_report(report: NsSfrReport, image: np.ndarray, path: str | os.PathLike) -> None:
    """PNG like the SOLAS paper's figure 5: annuli and ROIs over the image; mean SFR per annulus
    against frequency in cy/px, 0–0.5 (solid: image, dashed: comparison image). 1300×520 px."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, Rectangle

    from ..imageio import atomic_path, srgb_encode

    colours = ("tab:green", "tab:orange", "tab:red")
    lin = np.asarray(image, dtype=np.float64)
    if lin.ndim == 3:
        lin = lin[:, :, :3] if lin.shape[2] >= 3 else lin[:, :, 0]
    top = float(np.percentile(lin, 99.5)) or 1.0
    shown = srgb_encode(lin / top)
    fig = Figure(figsize=(13, 5.2), layout="constrained")
    ax_img, ax_sfr = fig.subplots(1, 2, width_ratios=(1.25, 1))
    ax_img.imshow(shown, cmap="gray", vmin=0, vmax=1)
    height, width = report.shape
    centre = ((width - 1) / 2, (height - 1) / 2)
    for stats, colour in zip(report.before, colours):
        ax_img.add_patch(Circle(centre, stats.r_outer * report.radius_px, fill=False, color=colour, lw=1.5))
    for m in report.rois:
        x, y, w, h = m.roi
        ax_img.add_patch(Rectangle((x - 0.5, y - 0.5), w, h, fill=False, color=colours[m.annulus], lw=1))
    ax_img.set_xlim(-0.5, width - 0.5)
    ax_img.set_ylim(height - 0.5, -0.5)
    ax_img.set(title=f"edge ROIs in {report.scheme} annuli", xlabel="x (px)", ylabel="y (px)")
    after: Sequence[AnnulusStats | None] = report.after or [None] * len(report.before)
    for stats, post, colour in zip(report.before, after, colours):
        if stats.curve is None:
            continue
        ax_sfr.plot(CURVE_FREQ, stats.curve, "-", color=colour,
                    label=f"{stats.name} (n={stats.count}) MTF50 {stats.mean_mtf50:.3f}")
        if post is not None and post.curve is not None:
            ax_sfr.plot(CURVE_FREQ, post.curve, "--", color=colour,
                        label=f"{stats.name} compared: MTF50 {post.mean_mtf50:.3f}")
    ax_sfr.axhline(0.5, color="0.6", lw=0.8)
    ax_sfr.set_xlim(0, 0.5)
    ax_sfr.set_ylim(0, 1.1)
    ax_sfr.set_xlabel("frequency (cy/px)")
    ax_sfr.set_ylabel("mean SFR (modulation, 1 at 0 cy/px)")
    ax_sfr.set_title("mean SFR per annulus (solid: image, dashed: comparison)")
    if ax_sfr.get_legend_handles_labels()[0]:  # no curves when no edge was measured
        ax_sfr.legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
