"""Degraded vs rendered flare (issue 39's acceptance): for three coated lenses (`with_typical_ar`), a frame of a
sun and two headlights rendered with a pinhole camera and degraded with the lens's ghosts (`degrade --ghosts`)
against the lens camera's render of the same scene with ghosts (`render --lens --ghosts`); the comparison is
`solas_mi.validation.flare_routes` (its docstring says what is compared and how).

Run: .venv/bin/python benchmarks/bench_flare_routes.py [--size 96x72] [--spp 64] [--path-spp 64] [--paths 3]

Acceptance: each compared ghost's centroid within 2 px and light within 10 %, the flare label's hit masks'
IoU >= 0.8.
"""

from __future__ import annotations

import argparse
import tempfile
import time

LENSES = ("double-gauss-50mm", "wide-angle-22mm", "nikkor-fisheye")


def run(*args) -> None:
    """One solas-mi command, in this process, its report on stderr (stdout is the results' tables); SystemExit unless
    it succeeds."""
    import contextlib
    import sys

    from solas_mi.cli import main as solas_mi

    with contextlib.redirect_stdout(sys.stderr):
        code = solas_mi([str(a) for a in args])
    if code != 0:
        raise SystemExit(f"solas-mi {' '.join(map(str, args))} failed")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="96x72")
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--path-spp", type=int, default=64)
    parser.add_argument("--paths", type=int, default=3)
    args = parser.parse_args()
    from solas_mi import Lens
    from solas_mi.optics.typical_ar import with_typical_ar
    from solas_mi.validation.flare_routes import HIT_RATIO, compare

    size = tuple(int(v) for v in args.size.split("x"))
    print(f"frame {size[0]}x{size[1]}, render --ghosts at {args.spp} spp, each ghost alone at {args.path_spp} spp")
    print()
    print(
        "| lens | half fov (deg) | sources | ghost (j, i) | centroid gap (px) | light degraded | light rendered | ratio |"
    )
    print("|---|---|---|---|---|---|---|---|")
    found = []
    for name in LENSES:
        with tempfile.TemporaryDirectory(prefix="solas-flare-") as folder:
            start = time.perf_counter()
            result = compare(with_typical_ar(Lens.load(name)), folder, run, size, args.spp, args.path_spp, args.paths)
            found.append((result, time.perf_counter() - start))
        for row in result.paths:
            print(
                f"| {name} | {result.half_fov_deg:g} | {row['sources']} | {tuple(row['path'])} | "
                f"{row['centroid_px']:.2f} | {row['light_degraded']:.3g} | {row['light_rendered']:.3g} | "
                f"{row['light_ratio']:.3f} |"
            )
    print()
    print(f"| lens | hit mask IoU (ratio > {HIT_RATIO:g}) | hit pixels degraded | rendered | flare light degraded | "
          "rendered | worst centroid gap (px) | worst light gap | seconds |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for result, seconds in found:
        gap, light = result.worst()
        print(
            f"| {result.lens} | {result.iou:.3f} | {result.hit_pixels[0]} | {result.hit_pixels[1]} | "
            f"{result.flare_light[0]:.3g} | {result.flare_light[1]:.3g} | {gap:.2f} | {100 * light:.1f} % | "
            f"{seconds:.0f} |"
        )


if __name__ == "__main__":
    main()
