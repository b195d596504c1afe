"""Steps (d) and (e) of the street experiment (`run`): NS-SFR of each degraded image against the ideal
one with the PSF grid's prediction per edge, and the relative error maps of the convolution against
the lens renders, near and far; then the tables (Markdown, CSV, JSON) and the figure-5 plots.

A table row is one image and one annulus, for all edges or the far ones (every pixel of the ROI beyond
FAR_M): n (edges measured), the mean MTF50 of the ideal image and of the degraded one, the
degraded one's median, the mean change (degraded − ideal, same ROIs) and the mean MTF50 predicted by
the PSF grid (`prediction`) on the same ROIs. MTF50 in cy/px.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ... import jsonio
from ...metrics.annuli import ANNULUS_NAMES
from ...outputs import safe_name
from .prediction import edge_normal_deg, predicted_mtf50

FAR_M = 50.0  # objects beyond this distance (m) are the far field
APERTURE = "gaussian"  # the scene's film filter (scenes/street/street.xml)
COLUMNS = ("image", "annulus", "edges", "n", "ideal_mean", "mean", "median", "change")


def _mean(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.mean(values)) if values else None


def sfr_rows(name: str, report, far: list[bool], predicted: dict[str, list[float | None]]) -> list[dict]:
    """Table rows of one image's report (ROIs in report order; `far` and each grid's `predicted` per ROI)."""
    rows = []
    for ring, ring_name in enumerate(ANNULUS_NAMES):
        for subset in ("all", "far"):
            pick = [i for i, m in enumerate(report.rois) if m.annulus == ring and (subset == "all" or far[i])]
            before = [report.rois[i].before.mtf50 for i in pick]
            after = [report.rois[i].after.mtf50 for i in pick]
            rows.append(
                {
                    "image": name,
                    "annulus": ring_name,
                    "edges": subset,
                    "n": len(pick),
                    "ideal_mean": _mean(before),
                    "mean": _mean(after),
                    "median": float(np.median(after)) if after else None,
                    "change": _mean([a - b for a, b in zip(after, before)]),
                    **{f"predicted {g}": _mean([p[i] for i in pick]) for g, p in predicted.items()},
                }
            )
    return rows


def error_stats(image: np.ndarray, render: np.ndarray, near: np.ndarray, far: np.ndarray) -> dict:
    """Relative error (image − render)/RMS(render): its RMS over all, near and far pixels, and the counts."""
    rel = (image.astype(np.float64) - render) / np.sqrt(np.mean(render.astype(np.float64) ** 2))
    return {
        "rel_rmse_all": float(np.sqrt(np.mean(rel**2))),
        "rel_rmse_near": float(np.sqrt(np.mean(rel[near] ** 2))) if near.any() else None,
        "rel_rmse_far": float(np.sqrt(np.mean(rel[far] ** 2))) if far.any() else None,
        "near_pixels": int(near.sum()),
        "far_pixels": int(far.sum()),
        "map": rel,
    }


def measure(outcome, grids: dict, lay, near_focus_m: float, out: Path) -> list[dict]:
    """Fill outcome.reports and outcome.errors, write the plots and the error maps to `out`; return the
    SFR table's rows (`write_tables`).
    `grids`: label → PSF grid whose predicted MTF50 is tabulated ("predicted LABEL")."""
    from ...metrics.nssfr import natural_scene_sfr, plot_report
    from ...validation.crossval import heat_png

    ideal, depth = outcome.images["ideal"], outcome.depth
    rows: list[dict] = []
    known: dict[tuple, tuple[bool, dict]] = {}  # ROI → (far, predicted MTF50 per grid): the same edges each time
    for name, img in outcome.images.items():
        if name == "ideal":
            continue
        rep = natural_scene_sfr(ideal, compare=img, full_scale=None)
        for m in rep.rois:
            if m.roi not in known:
                x, y, w, h = m.roi
                normal = edge_normal_deg(m.before.orientation, m.before.angle_deg)
                known[m.roi] = (
                    bool(depth[y : y + h, x : x + w].min() > FAR_M),
                    {
                        g: predicted_mtf50(grid, lay, x + (w - 1) / 2, y + (h - 1) / 2, normal, APERTURE)
                        for g, grid in grids.items()
                    },
                )
        far = [known[m.roi][0] for m in rep.rois]
        predicted = {g: [known[m.roi][1][g] for m in rep.rois] for g in grids}
        outcome.reports[name] = rep
        rows += sfr_rows(name, rep, far, predicted)
        plot_report(rep, ideal, out / f"fig5_{safe_name(name)}.png")
    near = depth < 1.5 * near_focus_m
    far_px = depth > FAR_M
    for conv in [n for n in outcome.images if n.startswith("interp")]:
        for name in [n for n in outcome.images if n.startswith("render")]:
            stats = error_stats(outcome.images[conv], outcome.images[name], near, far_px)
            rel = stats.pop("map")
            heat_png(
                out / f"error_{safe_name(conv)}_vs_{safe_name(name)}.png",
                np.abs(rel),
                f"|{conv} − {name}| / RMS({name})",
                vmax=0.2,
            )
            outcome.errors[f"{conv} vs {name}"] = dict(stats, near_m=1.5 * near_focus_m, far_m=FAR_M)
    outcome.meta.update(rejected={n: r.rejected for n, r in outcome.reports.items()})
    return rows


def _fmt(v, digits: int = 3) -> str:
    return "—" if v is None else f"{v:.{digits}f}" if isinstance(v, float) else str(v)


def _pct(v) -> str:
    return "—" if v is None else f"{100 * v:.2f} %"


def write_tables(out: Path, rows: list[dict], outcome) -> None:
    """street.md (SFR table, error table, step times), street.csv (the SFR table), street.json (all)."""
    from ...imageio import write_text

    columns = list(rows[0]) if rows else list(COLUMNS)
    predicted = [c for c in columns if c.startswith("predicted")]
    md = [
        "| image | annulus | edges | n | ideal MTF50 | MTF50 mean | median | change | " + " | ".join(predicted) + " |",
        "|---|---|---|" + "---:|" * (5 + len(predicted)),
    ]
    md += ["| " + " | ".join(_fmt(r[c]) for c in columns) + " |" for r in rows]
    md += [
        "",
        "| convolution vs render | rel. RMSE: all | near | far | near px | far px |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for name, e in outcome.errors.items():
        parts = [_pct(e[k]) for k in ("rel_rmse_all", "rel_rmse_near", "rel_rmse_far")]
        md.append(f"| {name} | " + " | ".join(parts) + f" | {e['near_pixels']} | {e['far_pixels']} |")
    layered = {n: e for n, e in outcome.errors.items() if "intervals" in e}
    if layered:  # step (g): error against the number of depth layers and run time, render noise removed
        md += [
            "",
            "| depth-aware convolution (render noise removed) | nodes | near | far | near, raw | far, raw | "
            "near, pinhole depth | far, pinhole depth | seconds |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        md += [
            f"| {n} | {e['nodes']} | "
            + " | ".join(
                _pct(e.get(k))
                for k in (
                    "rel_rmse_near",
                    "rel_rmse_far",
                    "rel_rmse_near_raw",
                    "rel_rmse_far_raw",
                    "rel_rmse_near_pinhole_depth",
                    "rel_rmse_far_pinhole_depth",
                )
            )
            + f" | {e['seconds']:.2f} |"
            for n, e in layered.items()
        ]
        md += [
            "",
            "Near and far: pixels both the ideal depth map and the render's own (through the lens) put nearer "
            "than near_m or beyond far_m; pinhole depth: by the ideal depth map alone.",
        ]
    md += ["", "| step | seconds |", "|---|---:|"] + [f"| {k} | {v:.1f} |" for k, v in outcome.seconds.items()]
    write_text(out / "street.md", "\n".join(md) + "\n")
    csv = [",".join(columns)] + [",".join("" if r[c] is None else str(r[c]) for c in columns) for r in rows]
    write_text(out / "street.csv", "\n".join(csv) + "\n")
    write_text(
        out / "street.json",
        jsonio.dumps(dict(outcome.meta, sfr=rows, errors=outcome.errors, seconds=outcome.seconds), indent=1),
    )
