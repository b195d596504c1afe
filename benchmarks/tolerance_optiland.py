"""The spread of a tolerance Monte Carlo against optiland's (an independent code with its own Monte Carlo and
sampler): the Cooke triplet's EFL (primary wavelength, paraxial) over N samples of radius (normal, σ a percent of
R, on every surface) and thickness (uniform ± a limit, on every surface but the last) errors, drawn by
`optics.tolerance` and by optiland's `tolerancing.MonteCarlo` on the same distributions; beside both, the
linear propagation Σ (∂EFL/∂p σ_p)² of `optics.tolerance.paraxial_sensitivity`. The standard deviations
agree within their sampling error (about 1/√(2N) each) when the two draws follow the same distributions.

    python3 -m venv .optiland-venv && .optiland-venv/bin/pip install optiland
    .venv/bin/python benchmarks/tolerance_optiland.py [--samples 3000] [--seeds 1 2 3] [--optiland-python PY]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from bench_optiland import request  # noqa: E402

from solas_mi import Lens  # noqa: E402
from solas_mi.optics import tolerance as tol  # noqa: E402
from solas_mi.optics.paraxial import paraxial  # noqa: E402

# optiland's perturbations of `symmetric_spec`'s distributions (`d`: the request, `problem`: its Tolerancing)
PERTURB = """for i, r in enumerate(d["radii"], start=1):
    sampler = DistributionSampler("normal", seed=100 + i, loc=r, scale=abs(r) * d["percent"] / 100)
    problem.add_perturbation("radius", sampler, surface_number=i)
for i, t in enumerate(d["thicknesses"], start=1):
    sampler = DistributionSampler("uniform", seed=200 + i, low=t - d["limit"], high=t + d["limit"])
    problem.add_perturbation("thickness", sampler, surface_number=i)
"""

THEIRS = """
import json, sys
import numpy as np
sys.path.insert(0, {here!r})
from optiland_reference import build
from optiland.tolerancing.core import Tolerancing
from optiland.tolerancing.monte_carlo import MonteCarlo
from optiland.tolerancing.perturbation import DistributionSampler
d = json.load(open({path!r}))
optic = build(d["spec"])
problem = Tolerancing(optic)
problem.add_operand("f2", input_data={{"optic": optic}})
{perturb}
mc = MonteCarlo(problem)
mc.run(d["samples"])
results = mc.get_results()
efl = np.asarray(results[[c for c in results.columns if "f2" in str(c)][0]], dtype=float)
print(json.dumps([float(efl.mean()), float(efl.std(ddof=1))]))
"""


def symmetric_spec(lens, percent: float, limit: float):
    """Radius errors (normal, σ `percent` of R, untruncated as optiland's) on every surface and thickness errors
    (uniform ± `limit` mm) on every surface but the last."""
    last = len(lens.surfaces)
    radius = {"kind": "radius", "surfaces": "all", "percent": percent, "truncate": 20.0}
    thickness = {"kind": "thickness", "surfaces": list(range(1, last)), "mm": limit, "distribution": "uniform"}
    return tol.spec_from_dict(lens, {"tolerance": [radius, thickness]})


def run_optiland(lens, args, script: str, **extra) -> list:
    """`script` (`THEIRS`'s kind: {here}, {path} and {perturb} filled in) run by `args.optiland_python` on the
    request for `lens` and `args`' distributions (and `extra` entries): the JSON list its last line prints."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "lens.json"
        data = {
            "spec": request(lens),
            "percent": args.percent,
            "limit": args.limit,
            "samples": args.samples,
            "radii": [s.radius for s in lens.surfaces],
            "thicknesses": [s.thickness for s in lens.surfaces[:-1]],
        }
        path.write_text(json.dumps({**data, **extra}))
        filled = script.format(here=str(HERE), path=str(path), perturb=PERTURB)
        done = subprocess.run([args.optiland_python, "-c", filled], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=3000)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--percent", type=float, default=0.5, help="σ of the radii (percent of R)")
    ap.add_argument("--limit", type=float, default=0.05, help="± limit of the thicknesses (mm)")
    ap.add_argument("--optiland-python", default=os.environ.get("OPTILAND_PYTHON", ".optiland-venv/bin/python"))
    args = ap.parse_args()
    lens = Lens.load("cooke-triplet")
    last = len(lens.surfaces)
    spec = symmetric_spec(lens, args.percent, args.limit)
    variance = 0.0
    for row, term in zip(tol.paraxial_sensitivity(lens, spec), spec.terms):
        sigma = (
            abs(lens.surfaces[term.surface].radius) * args.percent / 100
            if term.kind == "radius"
            else args.limit / math.sqrt(3)
        )
        variance += (row["defl_dparameter"] * sigma) ** 2
    nominal = paraxial(lens, lens.primary_wavelength).efl_mm
    print(
        f"Cooke triplet EFL ({nominal:.4f} mm nominal) over {args.samples} samples: radius σ {args.percent:g} % of "
        f"R on {last} surfaces (normal), thickness ± {args.limit:g} mm on {last - 1} (uniform)\n"
    )
    print("| draw | mean (mm) | standard deviation (mm) |\n|---|---|---|")
    print(f"| linear propagation (`paraxial_sensitivity`) | {nominal:.4f} | {math.sqrt(variance):.4f} |")
    for seed in args.seeds:
        efl = [
            paraxial(d, d.primary_wavelength).efl_mm
            for d in (tol.draw(lens, spec, seed, i)[0] for i in range(args.samples))
        ]
        print(f"| solas-mi, seed {seed} | {np.mean(efl):.4f} | {np.std(efl, ddof=1):.4f} |", flush=True)
    mean, std = run_optiland(lens, args, THEIRS)
    print(f"| optiland `tolerancing.MonteCarlo` | {mean:.4f} | {std:.4f} |")
    print(f"\nsampling error of a standard deviation: about {100 / math.sqrt(2 * args.samples):.1f} % each")


if __name__ == "__main__":
    main()
