"""Error against run time of the PSF-grid convolution (the paper's patch method; interp) and the direct
render, against a converged direct render of the doublet (`solas-mi report error-vs-time`).

Run: .venv/bin/python benchmarks/bench_error_vs_time.py [--scale 0.5] [--ref-spp 1536] [--out DIR]
Default: the bundled photograph at half size (640×480, spanning ±2°, pixel 10.9 µm), geometric PSFs,
reference 2 × 768 spp; patch 8×6 / 32×24, interp 4×3 … 64×48, render 3 … 768 spp. About 10 minutes
on 2 idle cores (the reference render is most of it). Writes table.md, table.csv, error_vs_time.png and
report.json to out/bench/error_vs_time/ and prints the Markdown table.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    from solas_mi.validation import commands

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scale", type=float, default=0.5, help="image scale (1 = 1280x960)")
    ap.add_argument("--ref-spp", type=int, default=1536)
    ap.add_argument("--spp", default=None, help="render spp, comma-separated (default 3,12,48,192,768)")
    ap.add_argument("--psf", default="geometric")
    ap.add_argument("--out", default=str(ROOT / "out" / "bench" / "error_vs_time"))
    a = ap.parse_args()
    argv = [
        "report",
        "error-vs-time",
        "solas-doublet",
        str(ROOT / "scenes" / "images" / "rocket.png"),
        "-o",
        a.out,
        "--scale",
        str(a.scale),
        "--ref-spp",
        str(a.ref_spp),
        "--psf",
        a.psf,
    ]
    if a.spp:
        argv += ["--spp", a.spp]
    parser = argparse.ArgumentParser(prog="bench_error_vs_time")
    commands.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return int(args.run(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
