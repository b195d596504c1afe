"""Whole-command timings of the CUDA variant on a machine with an NVIDIA GPU (run there by hand:
`python benchmarks/gpu_cuda.py > benchmarks/results/gpu_cuda.md`; `make bench` does not run it, since
CI machines have no GPU). Each row runs a fresh `python -m solas_mi` process and times it whole, Python
start and scene set-up included. "cold" is the first run with an empty Dr.Jit kernel cache (a fresh
HOME, where Dr.Jit keeps it); "warm" runs reuse the compiled kernels, with a different seed each time
(the seed is a kernel input, not a literal, so a new seed compiles nothing).
"""

from __future__ import annotations

import datetime
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from solas_mi.render.labels import LABELS

ROOT = Path(__file__).resolve().parent.parent
EVERY_LABEL = ",".join(LABELS)
IMAGE = ROOT / "scenes" / "images" / "rocket.png"
STREET = ROOT / "scenes" / "street" / "street.xml"
JOBS = {
    "render-image, solas-doublet, 1280×960, 64 spp": [
        "render-image",
        "solas-doublet",
        str(IMAGE),
        "--sensor",
        "1280x960",
        "--spp",
        "64",
    ],
    "render-image, solas-doublet, 1280×960, 256 spp": [
        "render-image",
        "solas-doublet",
        str(IMAGE),
        "--sensor",
        "1280x960",
        "--spp",
        "256",
    ],
    "render street.xml --lens solas-doublet, 64 spp": ["render", str(STREET), "--lens", "solas-doublet", "--spp", "64"],
    f"render street.xml --lens solas-doublet --labels {EVERY_LABEL}, 64 spp": [
        "render",
        str(STREET),
        "--lens",
        "solas-doublet",
        "--spp",
        "64",
        "--labels",
        EVERY_LABEL,
    ],
}


def timed(args: list[str], home: str, seed: int, out: str) -> float:
    env = dict(os.environ, HOME=home)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "solas_mi", *args, "--seed", str(seed), "--force", "-o", out],
        check=True,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - start


def main() -> None:
    gpu = (
        subprocess.run(
            ["nvidia-smi", "--query-gpu=name", "--format=csv,noheader"], capture_output=True, text=True
        ).stdout.strip()
        or "no NVIDIA GPU found"
    )
    print(
        f"<!-- written by benchmarks/gpu_cuda.py; do not edit -->\n`python benchmarks/gpu_cuda.py`, "
        f"{datetime.date.today().isoformat()}, {gpu}, {os.cpu_count()} CPU cores:\n"
    )
    print("| command | variant | cold (s) | warm median (s) | warm min–max (s) | warm runs |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "out.exr")
        for label, args in JOBS.items():
            for variant in ("cuda_ad_spectral", "llvm_ad_spectral"):
                if variant == "llvm_ad_spectral" and not label.startswith("render street"):
                    continue  # the CPU row for comparison: the street scene (render-image on 16 cores: minutes)
                home = tempfile.mkdtemp(dir=tmp)  # an empty kernel cache for this job and variant
                job = [*args, "--variant", variant]
                cold = timed(job, home, 1, out)
                warm = [timed(job, home, seed, out) for seed in (2, 3, 4)[: 3 if variant.startswith("cuda") else 1]]
                print(
                    f"| {label} | {variant} | {cold:.1f} | {statistics.median(warm):.1f} | "
                    f"{min(warm):.1f}–{max(warm):.1f} | {len(warm)} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
