"""`make demo`: the bundled doublet's paraxial table, its nine PSFs and an 8×8 PSF grid, and a
slanted-edge target of known MTF measured by the e-SFR."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from contextlib import redirect_stdout

from .cli import main as solas_mi
from .imageio import atomic_path


def cli(argv: list[str]) -> None:
    """Run one solas-mi command; stop the demo when it fails."""
    if solas_mi(argv) != 0:
        raise SystemExit(f"demo step failed: solas-mi {' '.join(argv)}")


def run(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for name, extra in (("lens_info.txt", []), ("lens_info.json", ["--json"])):
        with atomic_path(out / name) as tmp, open(tmp, "w") as f, redirect_stdout(f):
            cli(["lens", "info", "solas-doublet", *extra])
    print((out / "lens_info.txt").read_text())
    psfs = out / "psf"
    for field in (0, 2, -2):
        for wl in (486, 531, 656):
            cli(["psf", "solas-doublet", "--field-deg", f"0,{field}", "--wavelength-nm", str(wl), "--pitch-um", "0.5",
                 "--size", "160", "--normalize", "peak", "-o", str(psfs / f"psf_{field:+d}deg_{wl}nm.exr")])
    cli(["psf-grid", "solas-doublet", "--grid", "8x8", "--wavelengths", "656,531,486", "--pitch-um", "0.5",
         "--size", "160", "-o", str(out / "psf_grid_8x8.exr")])
    edge = out / "sfr" / "edge_5deg_sigma1px.png"
    cli(["sfr-target", "-o", str(edge), "--angle-deg", "5", "--sigma-px", "1", "--size", "128x128"])
    cli(["sfr", str(edge)])
    print(json.dumps({"results": str(out.resolve()), "paraxial": "lens_info.txt", "psfs": "psf/*.exr|png",
                      "grid": "psf_grid_8x8.exr|png", "slanted edge": "sfr/edge_5deg_sigma1px.png"}, indent=2))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="out", help="results folder")
    run(Path(ap.parse_args().out))


if __name__ == "__main__":
    main()
