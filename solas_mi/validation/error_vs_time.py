"""Error against run time (`solas-mi report error-vs-time`): how close each way of degrading an image
comes to the converged direct render, and what it costs.

Cases: the SOLAS paper's `patch` convolution (8×6 and 32×24 blocks), the seamless `interp`
convolution on grids of 4×3 … 64×48 nodes, and the direct render itself at a range of samples per
pixel. The reference is a high-spp render averaged from several seeds (`crossval.reference`); each
error is the relative RMSE against it with the reference's own noise removed in quadrature (a render's
error includes its own noise: that is its error). Times: the PSF grid's computation and the
convolution apart (a grid is computed once per lens and reused for every image); the render's time is
its sample loop. Convolution times are the median of `repeats` runs.

Outputs: table.md, table.csv, error_vs_time.png (log x: seconds; y: relative RMSE), report.json.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolasError
from ..imageio import write_text
from .crossval import (
    DEFAULT_CASES,
    PSF_KINDS,
    Errors,
    Row,
    compare,
    convolve,
    csv_text,
    load_input,
    noise_variance_map,
    psf_grid_for,
    reference,
    render,
    render_units,
)

DEFAULT_RENDER_SPP = (3, 12, 48, 192, 768)  # 3·4^k: each line's third a perfect square (stratifies best)
DEFAULT_INTERP_GRIDS = ((4, 3), (8, 6), (16, 12), (32, 24), (64, 48))  # (columns, rows)
DEFAULT_PATCH_GRIDS = ((8, 6), (32, 24))


def _grids(text: str | None, default, what: str) -> tuple[tuple[int, int], ...]:
    from ..options import parse_wxh

    if text is None:
        return tuple(default)
    out = []
    for item in text.split(","):
        if item.strip():
            rows, cols = parse_wxh(item, what)
            out.append((cols, rows))
    return tuple(out)


def _ints(text: str | None, default, what: str) -> tuple[int, ...]:
    if text is None:
        return tuple(default)
    try:
        values = tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise SolasError(f"{what} {text!r} must be comma-separated positive integers") from None
    if not values or min(values) < 1:
        raise SolasError(f"{what} {text!r} must be comma-separated positive integers")
    return values


def error_vs_time(lens, image: np.ndarray, out: str | Path | None, ref_spp: int = 1536, seeds: int = 2,
                  render_spp=DEFAULT_RENDER_SPP, interp_grids=DEFAULT_INTERP_GRIDS,
                  patch_grids=DEFAULT_PATCH_GRIDS, kind: str = "geometric", fov_deg: float | None = None,
                  boundary: str = "edge", repeats: int = 3, variant: str | None = None, log=print) -> list[Row]:
    """The error of every case against the reference and its run time; writes the table and plot to
    `out` (None: nothing written)."""
    from ..convolution.kernels import channel_wavelengths, check_boundary
    from ..optics.camera import check_fov

    fov = check_fov(lens.field_deg if fov_deg is None else fov_deg)
    check_boundary(boundary)
    if kind not in PSF_KINDS:
        raise SolasError(f"PSF kind {kind!r} must be one of {', '.join(PSF_KINDS)}")
    if not (isinstance(repeats, int) and repeats >= 1):
        raise SolasError(f"repeats {repeats!r} must be a positive integer")
    h, w = image.shape[:2]
    out_dir = Path(out) if out is not None else None
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    # warm-ups: Dr.Jit kernels of the tracer and of the render compile on first use, not in the timings
    psf_grid_for(lens, kind, (2, 2), w, h, fov)
    render(lens, image[: max(8, h // 8), : max(8, w // 8)], 3, 0, fov, boundary, variant)

    log(f"error-vs-time: {w}x{h} px, reference {ref_spp} spp in {seeds} renders")
    ref = reference(lens, image, ref_spp, fov, seeds, boundary, variant)
    ref_rms = math.sqrt(float(np.mean(ref.image ** 2)))
    var_map = noise_variance_map(ref.renders)
    log(f"error-vs-time: reference {ref.seconds:.1f} s, noise {100 * ref.noise / ref_rms:.3f} %")

    def err(img) -> Errors:
        return compare(img, ref.image, ref.noise, var_map)

    rows: list[Row] = []
    scale = None
    cases = [("patch", g) for g in patch_grids] + [("interp", g) for g in interp_grids]
    grids: dict[tuple[int, int], tuple[Any, float]] = {}
    for method, blocks in cases:
        if blocks not in grids:
            grids[blocks] = psf_grid_for(lens, kind, blocks, w, h, fov)
        grid, psf_s = grids[blocks]
        if scale is None:
            scale = render_units(lens, [grid.wavelengths_nm[k] for k in channel_wavelengths(grid, 3)], fov)
        times = []
        for _ in range(repeats):
            img, s = convolve(image, grid, method, lens, fov, boundary, scale)
            times.append(s)
        name = f"{method} {blocks[0]}x{blocks[1]}"
        rows.append(Row(name, method, kind, f"{blocks[0]}x{blocks[1]}", psf_s, statistics.median(times), err(img)))
        log(f"error-vs-time: {name}: {100 * rows[-1].errors.rel_rmse_denoised:.3f} %, PSF {psf_s:.2f} s, "
            f"convolution {rows[-1].conv_seconds:.3f} s")
    for k, spp in enumerate(render_spp):
        r = render(lens, image, int(spp), 7 + k, fov, boundary, variant)
        rows.append(Row(f"render {spp} spp", "render", "—", "—", 0.0, r.seconds, err(r.image), spp=int(spp)))
        log(f"error-vs-time: render {spp} spp: {100 * rows[-1].errors.rel_rmse_denoised:.3f} %, {r.seconds:.1f} s")
    if out_dir is not None:
        note = (f"{w}x{h} px, {kind} PSFs. Reference: mean of {seeds} direct renders, {ref.spp} spp in all "
                f"({ref.seconds:.1f} s), noise {100 * ref.noise / ref_rms:.3f} % of RMS(reference), removed in "
                f"quadrature in \"− noise\" and the annuli. PSF s: computing the PSF grid (once per lens); run s: "
                f"the convolution (median of {repeats}) or the render.")
        write_text(out_dir / "table.md", table_markdown(rows, note))
        write_text(out_dir / "table.csv", csv_text(rows))
        plot(rows, out_dir / "error_vs_time.png", f"{lens.name}, {w}x{h} px: error against the converged render")
        write_text(out_dir / "report.json", json.dumps({
            "lens": lens.name, "lens_hash": lens.hash, "sensor": [w, h], "fov_deg": fov, "psf": kind,
            "boundary": boundary, "reference_spp": ref.spp, "reference_seeds": seeds,
            "reference_seconds": ref.seconds, "reference_noise_rel": ref.noise / ref_rms,
            "render_units_k": [float(v) for v in scale], "rows": [r.flat() for r in rows]}, indent=1))
    return rows


def table_markdown(rows: list[Row], note: str = "") -> str:
    lines = ["| case | PSF grid s | run s | total s | rel. RMSE − noise | centre | middle | edge | rel. RMSE | "
             "PSNR dB | SSIM |", "|" + "---|" * 11]
    for r in rows:
        e = r.errors
        ann = " | ".join(f"{100 * e.annuli_denoised[n]:.3f} %" if n in e.annuli_denoised else "—"
                         for n in ("centre", "middle", "edge"))
        psf = f"{r.psf_seconds:.2f}" if r.method != "render" else "—"
        lines.append(f"| {r.name} | {psf} | {r.conv_seconds:.3f} | {r.seconds:.2f} | "
                     f"{100 * e.rel_rmse_denoised:.3f} % | {ann} | {100 * e.rel_rmse:.3f} % | {e.psnr_db:.2f} | "
                     f"{e.ssim:.5f} |")
    if note:
        lines += ["", note]
    return "\n".join(lines) + "\n"


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


def run_error_vs_time(args: argparse.Namespace) -> int:
    from ..optics.lens import Lens
    from ..options import parse_wxh

    lens = Lens.load(args.lens)
    sensor = parse_wxh(args.sensor, "--sensor") if args.sensor else None
    image = load_input(args.image, sensor, args.scale, args.linear)
    rows = error_vs_time(lens, image, args.output, args.ref_spp, args.seeds,
                         _ints(args.spp, DEFAULT_RENDER_SPP, "--spp"),
                         _grids(args.interp_grids, DEFAULT_INTERP_GRIDS, "--interp-grids"),
                         _grids(args.patch_grids, DEFAULT_PATCH_GRIDS, "--patch-grids"), args.psf, args.fov_deg,
                         args.boundary, args.repeats, args.variant, log=lambda s: print(s, flush=True))
    print(table_markdown(rows))
    print(f"wrote {args.output}/table.md, table.csv, error_vs_time.png, report.json")
    return 0


def register(sub: Any) -> None:
    """Add the `report` subcommand (`report error-vs-time`)."""
    from ..convolution.kernels import BOUNDARIES
    from ..render.loop import VARIANTS

    report = sub.add_parser("report", help="reports: error against run time").add_subparsers(
        dest="report_command", required=True)
    p = report.add_parser(
        "error-vs-time", help="error of patch / interp convolution and of the direct render against run time",
        description="Relative RMSE against a converged direct render (noise removed) and run time of the paper's "
                    "patch convolution, the interp convolution on grids of increasing size and the direct render "
                    "at increasing spp; writes table.md, table.csv, error_vs_time.png (log x) and report.json.")
    p.add_argument("lens", help="shipped lens name (solas-doublet) or a .toml lens file")
    p.add_argument("image", help="input image (PNG/JPEG sRGB, EXR linear)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--sensor", help="resample the image to COLSxROWS first (area average)")
    size.add_argument("--scale", type=float, help="resample the image by this factor in (0, 1] first")
    p.add_argument("--ref-spp", type=int, default=1536, help="reference spp, all seeds together (default 1536)")
    p.add_argument("--seeds", type=int, default=2, help="renders the reference is averaged from (>= 2)")
    p.add_argument("--spp", help="render spp to time, comma-separated (default 3,12,48,192,768)")
    p.add_argument("--interp-grids", help="interp grids COLSxROWS, comma-separated (default 4x3,8x6,16x12,32x24,64x48)")
    p.add_argument("--patch-grids", help="patch grids COLSxROWS, comma-separated (default 8x6,32x24)")
    p.add_argument("--psf", choices=PSF_KINDS, default="geometric", help="PSF kind (default geometric: the render "
                                                                        "is a ray render, without diffraction)")
    p.add_argument("--repeats", type=int, default=3, help="convolution runs to take the median time of")
    p.add_argument("--fov-deg", type=float, help="half the horizontal field the image spans (default: the lens's)")
    p.add_argument("--boundary", choices=BOUNDARIES, default="edge")
    p.add_argument("--linear", action="store_true", help="PNG/JPEG values are already linear")
    p.add_argument("--variant", choices=VARIANTS, help="Mitsuba variant of the render")
    p.set_defaults(run=run_error_vs_time)


__all__ = ["DEFAULT_CASES", "error_vs_time", "register"]
