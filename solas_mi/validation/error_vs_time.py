"""Error against run time (`solas-mi report error-vs-time`): how close each way of degrading an image
comes to the converged direct render, and what it costs.

Cases: the SOLAS paper's `patch` convolution (8×6 and 32×24 blocks), the seamless `interp`
convolution on grids of 4×3 … 64×48 nodes, and the direct render itself at a range of samples per
pixel. The reference is a high-spp render averaged from several seeds (`reference.reference`); each
error is the relative RMSE against it with the reference's own noise removed in quadrature (a render's
error includes its own noise: that is its error). Times: the PSF grid's computation and the
convolution apart (a grid is computed once per lens and reused for every image); the render's time is
its sample loop. Convolution times are the median of `repeats` runs.

Outputs: table.md, table.csv, error_vs_time.png (log x: seconds; y: relative RMSE), report.json.
"""
from __future__ import annotations

import statistics
from pathlib import Path
from typing import Any

import numpy as np

from .. import jsonio
from ..convolution.kernels import check_boundary
from ..errors import SolasError
from ..imageio import write_text
from ..optics.camera import check_fov
from ..progress import Progress
from .engines import check_kind, convolve, grid_units, psf_grid_for, render
from .reference import check_reference, noise_variance_map, reference
from .scores import Errors, compare
from .tables import Row, csv_text, error_vs_time_markdown

DEFAULT_RENDER_SPP = (3, 12, 48, 192, 768)  # 3·4^k: each line's third a perfect square (stratifies best)
DEFAULT_INTERP_GRIDS = ((4, 3), (8, 6), (16, 12), (32, 24), (64, 48))  # (columns, rows)
DEFAULT_PATCH_GRIDS = ((8, 6), (32, 24))


# many parameters: the experiment's settings, each a flag of `solas-mi error-vs-time` with its default (the
# reference's spp and seeds, the renders' spp, the interp and patch grids, PSF kind, field, boundary, repeats, variant)
def error_vs_time(lens, image: np.ndarray, out: str | Path | None, ref_spp: int = 1536, seeds: int = 2,
                  render_spp=DEFAULT_RENDER_SPP, interp_grids=DEFAULT_INTERP_GRIDS,
                  patch_grids=DEFAULT_PATCH_GRIDS, kind: str = "geometric", fov_deg: float | None = None,
                  boundary: str = "edge", repeats: int = 3, variant: str | None = None, log=print) -> list[Row]:
    """The error of every case against the reference and its run time; writes the table and plot to
    `out` (None: nothing written)."""
    fov = check_fov(lens.field_deg if fov_deg is None else fov_deg)
    check_boundary(boundary)
    check_kind(kind)
    if not (isinstance(repeats, int) and repeats >= 1):
        raise SolasError(f"repeats {repeats!r} must be a positive integer")
    check_reference(ref_spp, seeds)
    h, w = image.shape[:2]
    out_dir = Path(out) if out is not None else None
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    # warm-ups: Dr.Jit kernels of the tracer and of the render compile on first use, not in the timings
    psf_grid_for(lens, kind, (2, 2), w, h, fov)
    render(lens, image[: max(8, h // 8), : max(8, w // 8)], 3, 0, fov, boundary, variant)

    log(f"error-vs-time: {w}x{h} px, reference {ref_spp} spp in {seeds} renders")
    with Progress("error-vs-time: reference", ref_spp // seeds * seeds, "spp") as bar:
        ref = reference(lens, image, ref_spp, fov, seeds, boundary, variant, progress=bar)
    ref_rms = ref.rms
    var_map = noise_variance_map(ref.renders)
    log(f"error-vs-time: reference {ref.seconds:.1f} s, noise {100 * ref.noise / ref_rms:.3f} %")

    def err(img) -> Errors:
        return compare(img, ref.image, ref.noise, var_map)

    rows, scale = _convolution_rows(lens, image, kind, patch_grids, interp_grids, fov, boundary, repeats, err, log)
    for k, spp in enumerate(render_spp):
        r = render(lens, image, int(spp), 7 + k, fov, boundary, variant)
        rows.append(Row(f"render {spp} spp", "render", "—", "—", 0.0, r.seconds, err(r.image), spp=int(spp)))
        log(f"error-vs-time: render {spp} spp: {100 * rows[-1].errors.rel_rmse_denoised:.3f} %, {r.seconds:.1f} s")
    if out_dir is not None:
        _write_report(out_dir, lens, rows, ref, kind, fov, boundary, repeats, scale)
    return rows


def _convolution_rows(lens, image: np.ndarray, kind: str, patch_grids, interp_grids, fov: float, boundary: str,
                      repeats: int, err, log) -> tuple[list[Row], Any]:
    """(a Row per grid of `patch_grids` and `interp_grids`: its PSF grid's seconds, the median of `repeats` convolutions
    and the error `err(image)`; the render units `grid_units`). One PSF grid per block count."""
    h, w = image.shape[:2]
    rows: list[Row] = []
    scale = None
    cases = [("patch", g) for g in patch_grids] + [("interp", g) for g in interp_grids]
    grids: dict[tuple[int, int], tuple[Any, float]] = {}
    for method, blocks in cases:
        if blocks not in grids:
            grids[blocks] = psf_grid_for(lens, kind, blocks, w, h, fov)
        grid, psf_s = grids[blocks]
        if scale is None:
            scale = grid_units(lens, grid, fov)
        times = []
        for _ in range(repeats):
            img, s = convolve(image, grid, method, lens, fov, boundary, scale)
            times.append(s)
        name = f"{method} {blocks[0]}x{blocks[1]}"
        rows.append(Row(name, method, kind, f"{blocks[0]}x{blocks[1]}", psf_s, statistics.median(times), err(img)))
        log(f"error-vs-time: {name}: {100 * rows[-1].errors.rel_rmse_denoised:.3f} %, PSF {psf_s:.2f} s, "
            f"convolution {rows[-1].conv_seconds:.3f} s")
    return rows, scale


def _write_report(out_dir: Path, lens, rows: list[Row], ref, kind: str, fov: float, boundary: str, repeats: int,
                  scale) -> None:
    """table.md, table.csv, error_vs_time.png and report.json into `out_dir`: the image's size and the
    reference's seeds are the reference's (`ref`, its mean image and renders)."""
    h, w = ref.image.shape[:2]
    seeds = len(ref.renders)
    ref_rms = ref.rms
    note = (f"{w}x{h} px, {kind} PSFs. Reference: mean of {seeds} direct renders, {ref.spp} spp in all "
            f"({ref.seconds:.1f} s), noise {100 * ref.noise / ref_rms:.3f} % of RMS(reference), removed in "
            f"quadrature in \"− noise\" and the annuli. PSF s: computing the PSF grid (once per lens); run s: "
            f"the convolution (median of {repeats}) or the render.")
    write_text(out_dir / "table.md", error_vs_time_markdown(rows, note))
    write_text(out_dir / "table.csv", csv_text(rows))
    plot(rows, out_dir / "error_vs_time.png", f"{lens.name}, {w}x{h} px: error against the converged render")
    write_text(out_dir / "report.json", jsonio.dumps({
        "lens": lens.name, "lens_hash": lens.hash, "sensor": [w, h], "fov_deg": fov, "psf": kind,
        "boundary": boundary, "reference_spp": ref.spp, "reference_seeds": seeds,
        "reference_seconds": ref.seconds, "reference_noise_rel": ref.noise / ref_rms,
        "render_units_k": [float(v) for v in scale], "rows": [r.flat() for r in rows]}, indent=1))


def plot(rows: list[Row], path: Path, title: str) -> None:
    """Relative RMSE (noise removed) against seconds, log x (and log y): filled markers at PSF grid +
    convolution time, open markers at the convolution alone."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..imageio import atomic_path

    fig, ax = plt.subplots(figsize=(7.5, 5), dpi=120)
    styles = {"patch": ("tab:red", "s"), "interp": ("tab:blue", "o"), "render": ("tab:green", "^")}
    floor = 1e-4
    for method, (colour, marker) in styles.items():
        rs = [r for r in rows if r.method == method]
        if not rs:
            continue
        y = [max(floor, r.errors.rel_rmse_denoised) for r in rs]
        label = {"patch": "patch (paper)", "interp": "interp", "render": "direct render"}[method]
        if method == "render":
            ax.plot([r.seconds for r in rs], y, marker=marker, color=colour, label=label + " (spp)")
            for r, v in zip(rs, y):
                ax.annotate(str(r.spp), (r.seconds, v), textcoords="offset points", xytext=(4, 4), fontsize=7)
            continue
        ax.plot([r.seconds for r in rs], y, marker=marker, color=colour, ls="-" if method == "interp" else "none",
                label=label + ": PSF grid + convolution")
        ax.plot([r.conv_seconds for r in rs], y, marker=marker, color=colour, mfc="none",
                ls=":" if method == "interp" else "none", label=label + ": convolution only")
        for r, v in zip(rs, y):
            ax.annotate(r.grid, (r.seconds, v), textcoords="offset points", xytext=(4, -9), fontsize=7)
    ax.axhline(0.01, color="0.6", lw=0.8, ls="--")
    from matplotlib.ticker import FuncFormatter, LogLocator

    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: ""))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{100 * v:g} %"))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: ""))
    ax.set_xlabel("seconds (2-core CPU)")
    ax.set_ylabel("relative RMSE vs converged render (noise removed)")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
