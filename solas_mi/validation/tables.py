"""The comparisons' result tables: one `Row` per way of degrading the image (a convolution case, the
render at some spp, the unblurred image), written as Markdown (`crossval_markdown`,
`error_vs_time_markdown`) or CSV (`csv_text`). Errors are given in per cent (PSNR in dB, SSIM
unitless), times in wall-clock seconds with the PSF grid's computation and the run (convolution or
render) apart.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from typing import Any

from ..metrics.annuli import ANNULUS_NAMES
from .scores import Errors


@dataclass
class Row:
    """One line of a results table."""

    name: str
    method: str
    psf: str
    grid: str
    psf_seconds: float
    conv_seconds: float
    errors: Errors
    spp: int | None = None

    @property
    def seconds(self) -> float:
        return self.psf_seconds + self.conv_seconds

    def flat(self) -> dict[str, Any]:
        e = self.errors
        out = {
            "name": self.name,
            "method": self.method,
            "psf": self.psf,
            "grid": self.grid,
            "spp": self.spp,
            "psf_seconds": round(self.psf_seconds, 3),
            "run_seconds": round(self.conv_seconds, 3),
            "total_seconds": round(self.seconds, 3),
            "rel_rmse": e.rel_rmse,
            "rel_rmse_denoised": e.rel_rmse_denoised,
            "rmse": e.rmse,
            "psnr_db": e.psnr_db,
            "ssim": e.ssim,
        }
        for k, v in e.annuli.items():
            out[f"rel_rmse_{k}"] = v
        for k, v in e.annuli_denoised.items():
            out[f"rel_rmse_{k}_denoised"] = v
        return out


def _percent(value: float | None) -> str:
    return "—" if value is None else f"{100 * value:.3f} %"


def _annuli(e: Errors) -> str:
    """The denoised relative RMSE of each annulus, as table cells."""
    return " | ".join(_percent(e.annuli_denoised.get(n)) for n in ANNULUS_NAMES)


def _with_note(lines: list[str], note: str) -> str:
    if note:
        lines += ["", note]
    return "\n".join(lines) + "\n"


def crossval_markdown(rows: list[Row], noise_note: str = "") -> str:
    """`solas-mi crossval`'s table: the cases, their PSF and grid, times, errors."""
    head = (
        "| case | PSF | grid | PSF s | run s | total s | rel. RMSE | rel. RMSE − noise | centre | middle | edge "
        "| PSNR dB | SSIM |"
    )
    lines = [head, "|" + "---|" * 13]
    for r in rows:
        e = r.errors
        lines.append(
            f"| {r.name} | {r.psf} | {r.grid} | {r.psf_seconds:.2f} | {r.conv_seconds:.2f} | {r.seconds:.2f} | "
            f"{_percent(e.rel_rmse)} | {_percent(e.rel_rmse_denoised)} | {_annuli(e)} | {e.psnr_db:.2f} | "
            f"{e.ssim:.5f} |"
        )
    return _with_note(lines, noise_note)


def error_vs_time_markdown(rows: list[Row], note: str = "") -> str:
    """`solas-mi report error-vs-time`'s table: times first, then the errors with the noise removed."""
    lines = [
        "| case | PSF grid s | run s | total s | rel. RMSE − noise | centre | middle | edge | rel. RMSE | "
        "PSNR dB | SSIM |",
        "|" + "---|" * 11,
    ]
    for r in rows:
        e = r.errors
        psf = f"{r.psf_seconds:.2f}" if r.method != "render" else "—"
        lines.append(
            f"| {r.name} | {psf} | {r.conv_seconds:.3f} | {r.seconds:.2f} | "
            f"{_percent(e.rel_rmse_denoised)} | {_annuli(e)} | {_percent(e.rel_rmse)} | {e.psnr_db:.2f} | "
            f"{e.ssim:.5f} |"
        )
    return _with_note(lines, note)


def csv_text(rows: list[Row]) -> str:
    """All of each row's numbers (`Row.flat`), one CSV line a row; columns in order of appearance."""
    flat = [r.flat() for r in rows]
    keys: list[str] = []
    for f in flat:
        keys += [k for k in f if k not in keys]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    w.writerows(flat)
    return buf.getvalue()
