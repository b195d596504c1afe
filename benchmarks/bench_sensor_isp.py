"""Speed of the camera stage: a 1280×960 irradiance frame through the sensor (`sensor.capture`: shot,
dark and read noise, PRNU/DSNU, full well, ADC) and the image processor (`isp.develop`: black level,
white balance, demosaicing, CCM, sRGB tone curve), as a batch item does after its render or degrade; and a
1920×1080 frame through the HDR preset `imx490-hdr` (four readouts merged) against its single readout
`imx490` (issue 42: at most 2×).

Run: .venv/bin/python benchmarks/bench_sensor_isp.py [--repeats 7]
Prints, per case, the median and the spread of the runs (s), frames per second, the cores other
processes used meanwhile (timings are only good near 0), and the share of a degrade batch item's time
(batch.degrade.SECONDS_PER_VALUE per value of an RGB frame: reading, degrading, writing); and the figures
`run_all.py` compares run to run (each case's median).
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_convolution import busy_seconds, test_image
from figures import figure

W, H = 1280, 960
FULL_HD = (1920, 1080)  # the HDR camera's frame (issue 42)
EXPOSURE_S = 2.5e-4  # the test image's values (0…1) read as W/m²: 2300–3100 photons per channel at 1 (2 µm pixels)


def cases():
    from solas_mi.isp.demosaic import METHODS
    from solas_mi.isp.pipeline import ISP, develop
    from solas_mi.sensor.capture import capture
    from solas_mi.sensor.files import load_sensor
    from solas_mi.sensor.model import SensorModel

    image = test_image(W, H)
    out = {}
    for cfa in ("RGGB", "RCCB"):
        model = SensorModel(cfa=cfa, pixel_pitch_um=2.0)
        raw = capture(model, image, EXPOSURE_S, 0)
        out[f"sensor ({cfa})"] = lambda m=model: capture(m, image, EXPOSURE_S, 0, 1)
        for method in METHODS:
            isp = ISP(demosaic=method)
            out[f"isp {method} ({cfa})"] = lambda r=raw, m=model, i=isp: develop(r, m, i)
        out[f"sensor + isp default ({cfa})"] = lambda m=model: develop(capture(m, image, EXPOSURE_S, 0, 1), m)
    full_hd = test_image(*FULL_HD)
    for preset in ("imx490", "imx490-hdr"):
        sensor = load_sensor(preset)
        out[f"sensor {preset} {FULL_HD[0]}×{FULL_HD[1]}"] = lambda s=sensor: capture(s, full_hd, EXPOSURE_S, 0, 1)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    from solas_mi.batch.degrade import SECONDS_PER_VALUE

    degrade_s = SECONDS_PER_VALUE * W * H * 3
    print(f"{W}×{H} frame; a degrade batch item of this size: {degrade_s:.2f} s (SECONDS_PER_VALUE)\n")
    print(
        "| case | median (s) | runs min–max (s) | frames/s | share of a degrade item | other processes' load (cores) |"
    )
    print("|---|---|---|---|---|---|")
    medians = {}
    for name, run in cases().items():
        run()  # warm-up: imports, the demosaicer's first call
        times, busy = [], 0.0
        for _ in range(args.repeats):
            b0, t0 = busy_seconds(), time.perf_counter()
            run()
            times.append(time.perf_counter() - t0)
            busy += busy_seconds() - b0 - times[-1]
        median = medians[name] = statistics.median(times)
        print(
            f"| {name} | {median:.3f} | {min(times):.3f}–{max(times):.3f} | {1 / median:.1f} | "
            f"{median / degrade_s:.0%} | {max(busy / sum(times), 0.0):.2f} |"
        )
    print()
    for name, median in medians.items():  # "sensor + isp default (RGGB)" → sensor_isp_default_rggb_s
        figure(re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_") + "_s", median, "s")


if __name__ == "__main__":
    main()
