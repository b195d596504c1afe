"""Cross-validation of the two degradation engines (`solas-mi crossval`): the direct spectral render
through the lens geometry against the PSF-grid convolution, on the same input image and the same camera.

The pipeline: the input image (`inputs`) is degraded by the direct render, converged from several
seeds (`reference`), and by each convolution case (`engines`: PSF method × convolution method × grid),
all in render units (the ideal camera's irradiance, `engines` explains them); each case is scored
against the reference with its noise removed (`scores`) and tabulated (`tables`). Besides the tables,
each case leaves its image and an error map: (image − reference)/RMS(reference) per channel as EXR
and its magnitude as a heat-map PNG with the annuli (`metrics.annuli`) drawn.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import jsonio
from ..convolution.kernels import check_boundary
from ..errors import SolasError
from ..metrics.annuli import ANNULI, corner_radius
from ..optics.camera import check_fov
from ..outputs import safe_name
from ..progress import Progress
from .engines import PSF_SAMPLING, Case, convolve, grid_units, ideal, psf_grid_for
from .reference import Reference, check_reference, noise_variance_map, read_reference, reference, write_reference
from .scores import compare
from .tables import Row, crossval_markdown, csv_text

DEFAULT_CASES = ("interp:geometric:32x24", "patch:geometric:32x24", "patch:geometric:8x6",
                 "interp:fraunhofer:32x24", "patch:fraunhofer:32x24", "patch:fraunhofer:8x6")


def write_rgb_exr(path: Path, image: np.ndarray, meta: dict) -> None:
    from ..imageio import image_channels, write_exr

    write_exr(path, image_channels(np.asarray(image, dtype=np.float32)), meta)


def write_error_map(out: Path, stem: str, image: np.ndarray, ref: np.ndarray, ref_rms: float, meta: dict) -> None:
    """stem_error.exr: signed (image − reference)/RMS(reference) per channel; stem_error.png: its magnitude
    (mean |·| over channels) as a heat map (0 … 5 %) with the annuli drawn."""
    rel = (np.asarray(image, dtype=np.float64) - ref) / ref_rms
    write_rgb_exr(out / f"{stem}_error.exr", rel, dict(meta, values="(image - reference) / RMS(reference)"))
    heat_png(out / f"{stem}_error.png", np.abs(rel).mean(axis=-1), f"{stem}: |image − reference| / RMS(reference)")


def heat_png(path: Path, data: np.ndarray, title: str, vmax: float = 0.05) -> None:
    """`data` (H, W) as a heat map from 0 to `vmax` (shown in per cent), with the inner borders of the
    automotive annuli (`metrics.annuli`) drawn as circles."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    from ..imageio import atomic_path

    h, w = data.shape
    fig, ax = plt.subplots(figsize=(8, 8 * h / w + 0.6), dpi=100)
    im = ax.imshow(data, cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
    for f in ANNULI["automotive"][:-1]:
        ax.add_patch(Circle(((w - 1) / 2, (h - 1) / 2), f * corner_radius(h, w), fill=False, color="cyan", lw=0.8,
                            ls="--"))
    ax.set(title=title, xlabel="x (px)", ylabel="y (px)")
    ax.title.set_fontsize(9)
    bar = fig.colorbar(im, ax=ax, fraction=0.03, pad=0.01, format=lambda v, _: f"{100 * v:.0f} %")
    bar.set_label("error, % of the reference's RMS")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


@dataclass
class CrossvalResult:
    rows: list[Row]
    reference: Reference
    meta: dict


# many parameters: the comparison's settings, each a flag of `solas-mi crossval` with its default (the reference's spp
# and seeds, the cases, field, boundary, variant, baseline, reuse of a reference)
def crossval(lens, image: np.ndarray, out: str | Path | None, spp: int = 1024, seeds: int = 2,
             cases: tuple[str, ...] = DEFAULT_CASES, fov_deg: float | None = None, boundary: str = "edge",
             variant: str | None = None, baseline: bool = True, reuse: bool = False, log=print) -> CrossvalResult:
    """Degrade `image` (linear H×W×3, the sensor's grid) by the direct render (reference, `spp` in
    `seeds` renders) and by each convolution case; write the error maps and tables to `out` (None:
    write nothing). reuse: take `out`/reference.exr if it was rendered with the same settings."""
    fov = check_fov(lens.field_deg if fov_deg is None else fov_deg)
    check_boundary(boundary)
    parsed = [Case.parse(c) if isinstance(c, str) else c for c in cases]
    if not parsed:
        raise SolasError("no convolution case given")
    h, w = image.shape[:2]
    out_dir = Path(out) if out is not None else None
    check_reference(spp, seeds)
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    common = {"lens": lens.name, "lens_hash": lens.hash, "fov_deg": fov, "sensor": [w, h], "boundary": boundary}
    ref, var_map = _reference(lens, image, out_dir, common, spp, seeds, variant, reuse, log)
    log(f"crossval: reference noise {100 * ref.noise / ref.rms:.3f} % of RMS")
    rows, grids, scale = _case_rows(lens, image, parsed, ref, var_map, common, out_dir, log)
    if baseline:
        err = compare(ideal(image, fov, scale), ref.image, ref.noise, var_map)
        rows.append(Row("ideal (no blur)", "none", "—", "—", 0.0, 0.0, err))
    if ref.renders:  # one of the reference's own renders against the other(s): what the render's noise costs
        half = compare(ref.renders[0], np.mean(ref.renders[1:], axis=0))
        rows.append(Row(f"render {ref.spp // seeds} spp (vs the other seed{'s' if seeds > 2 else ''})", "render",
                        "—", "—", 0.0, ref.seconds / seeds, half, spp=ref.spp // seeds))
    meta = dict(common, reference_spp=ref.spp, reference_seeds=seeds, reference_seconds=ref.seconds,
                reference_noise_rel=ref.noise / ref.rms, render_units_k=[float(k) for k in scale],
                psf_sampling={k: {"pitch_um": p, "size": s} for k, (p, s) in PSF_SAMPLING.items()},
                fraunhofer_window={f"{b[0]}x{b[1]}": g.meta.get("window_captured_fraction")
                                   for (kind, b), (g, _) in grids.items() if kind == "fraunhofer"},
                rows=[r.flat() for r in rows])
    if out_dir is not None:
        _write_tables(out_dir, rows, ref, seeds, meta)
    return CrossvalResult(rows, ref, meta)


def _reference(lens, image: np.ndarray, out_dir: Path | None, common: dict, spp: int, seeds: int,
               variant: str | None, reuse: bool, log):
    """(the reference, its per-pixel noise variance map): `out_dir`/reference.exr when `reuse` finds it
    rendered with the same settings, else rendered now (and written there)."""
    expect = dict(common, spp=spp // seeds * seeds, seeds=seeds, response="lines", fresnel="off")
    stored = read_reference(out_dir / "reference.exr", expect) if reuse and out_dir is not None else None
    if stored is not None:
        ref, var_map = stored
        log(f"crossval: reusing {out_dir / 'reference.exr'} ({ref.spp} spp, rendered in {ref.seconds:.1f} s)")
        return ref, var_map
    w, h = common["sensor"]
    log(f"crossval: {w}x{h} px, reference {spp} spp in {seeds} renders")
    with Progress("crossval: reference", spp // seeds * seeds, "spp") as bar:
        ref = reference(lens, image, spp, common["fov_deg"], seeds, common["boundary"], variant, progress=bar)
    var_map = noise_variance_map(ref.renders)
    if out_dir is not None:
        write_reference(out_dir / "reference.exr", ref, var_map, common)
    return ref, var_map


def _case_rows(lens, image: np.ndarray, cases: list, ref, var_map, common: dict, out_dir: Path | None, log):
    """(a Row per convolution case against the reference, the PSF grids by (kind, blocks) with their
    seconds, the render units `grid_units`); each case's image and error map written to `out_dir`."""
    w, h = common["sensor"]
    fov, boundary = common["fov_deg"], common["boundary"]
    grids: dict[tuple[str, tuple[int, int]], tuple[Any, float]] = {}
    rows: list[Row] = []
    scale = None
    for case in cases:
        key = (case.kind, case.blocks)
        if key not in grids:
            grids[key] = psf_grid_for(lens, case.kind, case.blocks, w, h, fov)
        grid, psf_s = grids[key]
        if scale is None:
            scale = grid_units(lens, grid, fov)
        img, conv_s = convolve(image, grid, case.method, lens, fov, boundary, scale)
        err = compare(img, ref.image, ref.noise, var_map)
        blocks = f"{case.blocks[0]}x{case.blocks[1]}"
        rows.append(Row(case.name, case.method, case.kind, blocks, psf_s, conv_s, err))
        log(f"crossval: {case.name}: rel. RMSE {100 * err.rel_rmse:.3f} % ({100 * err.rel_rmse_denoised:.3f} % "
            f"without noise), PSF grid {psf_s:.1f} s, convolution {conv_s:.2f} s")
        if out_dir is not None:
            stem = safe_name(case.name)
            m = dict(common, case=case.name, psf_seconds=psf_s, conv_seconds=conv_s)
            write_rgb_exr(out_dir / f"{stem}.exr", img, m)
            write_error_map(out_dir, stem, img, ref.image, ref.rms, m)
    return rows, grids, scale


def _write_tables(out_dir: Path, rows: list, ref, seeds: int, meta: dict) -> None:
    """table.md, table.csv and crossval.json into `out_dir`."""
    from ..imageio import write_text

    note = (f"Reference: mean of {seeds} direct renders, {ref.spp} spp in all ({ref.seconds:.1f} s), noise "
            f"{100 * ref.noise / ref.rms:.3f} % of RMS(reference); \"− noise\" and the annuli remove it in "
            "quadrature. PSF s: computing the PSF grid; run s: the convolution (or render).")
    write_text(out_dir / "table.md", crossval_markdown(rows, note))
    write_text(out_dir / "table.csv", csv_text(rows))
    write_text(out_dir / "crossval.json", jsonio.dumps(meta, indent=1))
