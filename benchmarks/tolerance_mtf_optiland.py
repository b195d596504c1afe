"""The spread of a tolerance Monte Carlo's MTF50 against optiland's (an independent tracer with its own Monte
Carlo and sampler): the Cooke triplet's on-axis MTF50 (diffraction, primary wavelength, the image plane where
the design puts it: no compensator) over N samples of radius (normal, σ a percent of R, every surface) and
thickness (uniform ± a limit, every surface but the last) errors, drawn by `optics.tolerance` and measured by
`analysis.mtf.lens_otf`, and drawn by optiland's `tolerancing.MonteCarlo` (its `DistributionSampler`s) and
measured by its `FFTMTF`, an operand registered for the run. The acceptance's claim (a Monte Carlo of 1000 Cooke
triplets has an MTF50 spread that agrees with an independent tolerancing run on the same distributions within
the sampling error) on one field and wavelength: the per-sample quantity whose distribution both codes compute,
at a cost that lets 1000 samples run here (the full 5-field polychromatic run takes about an hour).

    .venv/bin/python benchmarks/tolerance_mtf_optiland.py [--samples 1000] [--seed 1] [--optiland-python PY]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from tolerance_optiland import run_optiland, symmetric_spec  # noqa: E402

from solas_mi import Lens  # noqa: E402
from solas_mi.analysis import inputs  # noqa: E402
from solas_mi.analysis.mtf import lens_otf  # noqa: E402
from solas_mi.optics import tolerance as tol  # noqa: E402

PUPIL_SAMPLES = 64  # ours: the pupil grid; optiland's FFTMTF: rays across the pupil
OPTILAND_GRID = 256  # optiland's FFT grid

THEIRS = """
import json, sys, time
import numpy as np
sys.path.insert(0, {here!r})
from optiland_reference import build
from optiland.mtf import FFTMTF
from optiland.optimization.operand.operand import operand_registry
from optiland.tolerancing.core import Tolerancing
from optiland.tolerancing.monte_carlo import MonteCarlo
from optiland.tolerancing.perturbation import DistributionSampler
d = json.load(open({path!r}))

def crossing(freq, mtf):
    below = np.nonzero(mtf <= 0.5)[0]
    if len(below) == 0:
        return float(freq[-1])
    i = below[0]
    return float(np.interp(0.5, [mtf[i], mtf[i - 1]], [freq[i], freq[i - 1]]))

def mtf50_axis(optic):
    m = FFTMTF(optic, fields=[(0.0, 0.0)], wavelength=d["wavelength_um"], num_rays=d["rays"], grid_size=d["grid"])
    return crossing(np.asarray(m.freq_tang[0] if isinstance(m.freq_tang, list) else m.freq_tang),
                    np.asarray(m.mtf[0][0]))

operand_registry.register("mtf50_axis", mtf50_axis, overwrite=True)
optic = build(d["spec"])
nominal = mtf50_axis(optic)
problem = Tolerancing(optic)
problem.add_operand("mtf50_axis", input_data={{"optic": optic}})
{perturb}
start = time.process_time()
mc = MonteCarlo(problem)
mc.run(d["samples"])
results = mc.get_results()
values = np.asarray(results[[c for c in results.columns if "mtf50" in str(c)][0]], dtype=float)
cpu = (time.process_time() - start) / d["samples"]
print(json.dumps([float(values.mean()), float(values.std(ddof=1)), cpu, nominal]))
"""


def crossing(freq: np.ndarray, mtf: np.ndarray) -> float:
    """The first frequency where `mtf` falls to 1/2 (linear between samples); the last one where it never does."""
    below = np.nonzero(mtf <= 0.5)[0]
    if len(below) == 0:
        return float(freq[-1])
    i = below[0]
    return float(np.interp(0.5, [mtf[i], mtf[i - 1]], [freq[i], freq[i - 1]]))


def ours(lens) -> float:
    """On-axis MTF50 (cycles/mm) of `lens` at its primary wavelength."""
    w = lens.primary_wavelength
    freq = np.linspace(0.0, inputs.cutoff_cy_mm(lens, w), 401)
    otf, _ = lens_otf(lens, (0.0,), (w,), (1.0,), freq, PUPIL_SAMPLES)
    return crossing(freq, np.abs(otf[0, 0]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--percent", type=float, default=0.1, help="σ of the radii (percent of R)")
    ap.add_argument("--limit", type=float, default=0.02, help="± limit of the thicknesses (mm)")
    ap.add_argument("--optiland-python", default=os.environ.get("OPTILAND_PYTHON", ".optiland-venv/bin/python"))
    args = ap.parse_args()
    lens = Lens.load("cooke-triplet")
    spec = symmetric_spec(lens, args.percent, args.limit)
    print(
        f"Cooke triplet on-axis MTF50 at {lens.primary_wavelength:g} nm, no compensator, {args.samples} samples: "
        f"radius σ {args.percent:g} % (normal), thickness ± {args.limit:g} mm (uniform); nominal {ours(lens):.2f} cy/mm"
    )
    start = time.process_time()
    values = np.array([ours(tol.draw(lens, spec, args.seed, i)[0]) for i in range(args.samples)])
    cpu = (time.process_time() - start) / args.samples
    print("| draw | mean (cy/mm) | standard deviation (cy/mm) | CPU-s per sample |\n|---|---|---|---|")
    print(f"| solas-mi, seed {args.seed} | {values.mean():.2f} | {values.std(ddof=1):.2f} | {cpu:.2f} |", flush=True)
    wavelength_um = lens.primary_wavelength * 1e-3
    mean, std, their_cpu, their_nominal = run_optiland(
        lens, args, THEIRS, wavelength_um=wavelength_um, rays=PUPIL_SAMPLES, grid=OPTILAND_GRID
    )
    print(f"| optiland `tolerancing.MonteCarlo`, `FFTMTF` | {mean:.2f} | {std:.2f} | {their_cpu:.2f} |")
    print(f"\noptiland's nominal {their_nominal:.2f} cy/mm")
    print(
        f"\nsampling error of a standard deviation: about {100 / math.sqrt(2 * args.samples):.1f} % each "
        f"(of their difference about {100 * math.sqrt(2) / math.sqrt(2 * args.samples):.1f} %)"
    )


if __name__ == "__main__":
    main()
