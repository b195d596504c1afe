"""Which camera model holds each shipped lens: every model of `optics.calibration.MODELS` fitted to each
shipped lens's chief-ray mapping (`solas-mi lens calibrate`'s work) over a 640×480 sensor whose width spans
the lens's field (a fisheye's: its image diameter), at the lens's primary wavelength, object at the lens
file's distance. The table gives the RMS and largest residual over every imaged pixel and whether the
model holds the lens to 0.1 px (its largest residual below that); a model that cannot hold the field is
named as refused. The residual maps (one figure per lens, a panel per model, log colour scale) are
written to docs/validation/calibration/ for the documentation.

Run: .venv/bin/python benchmarks/bench_calibration.py [--columns 640 --rows 480]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from solas_mi.errors import SolasError
from solas_mi.optics.calibration import MODELS, Sensor, chief_map
from solas_mi.optics.calibration.fit import fit, residual_map
from solas_mi.optics.calibration.models import model
from solas_mi.optics.camera import film_pitch_um
from solas_mi.optics.lens import Lens, shipped_lenses

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "validation" / "calibration"
HOLDS_PX = 0.1


def figure(name: str, maps: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    fig, axes = plt.subplots(2, 3, figsize=(12, 6.4), constrained_layout=True)
    for ax, model_name in zip(axes.ravel(), MODELS.names()):
        ax.set_title(model_name, fontsize=10)
        ax.set_xticks([])
        ax.set_yticks([])
        err = maps.get(model_name)
        if err is None:
            ax.text(0.5, 0.5, "refused: cannot hold the field", ha="center", va="center", transform=ax.transAxes)
            continue
        shown = np.clip(np.where(np.isfinite(err), err, np.nan), 1e-9, None)
        image = ax.imshow(shown, norm=LogNorm(vmin=1e-6, vmax=10.0), cmap="viridis")
    fig.colorbar(image, ax=axes, shrink=0.8, label="residual (px)")
    fig.suptitle(f"{name}: residual of each camera model over the sensor (white: outside the image circle)")
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--columns", type=int, default=640)
    parser.add_argument("--rows", type=int, default=480)
    args = parser.parse_args()
    FIGURES.mkdir(parents=True, exist_ok=True)
    print(
        f"| lens | model | RMS (px) | max (px) | max at (px) | max at (deg) | holds to {HOLDS_PX:g} px | "
        "fitted | image circle (px) |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name in shipped_lenses():
        lens = Lens.load(name)
        cmap = chief_map(lens, Sensor(args.columns, args.rows, film_pitch_um(lens, args.columns)))
        circle = cmap.describe()["image_circle_radius_px"]
        maps = {}
        for model_name in MODELS:
            try:
                cal = fit(cmap, model_name)
            except SolasError:
                print(f"| {name} | {model_name} | — | — | — | — | refused: cannot hold the field | — | — |")
                continue
            maps[model_name] = residual_map(model(model_name), cal.values, cmap, cal.projection)
            print(
                f"| {name} | {model_name} | {cal.rms_px:.2e} | {cal.max_px:.2e} | ({cal.max_at_px[0]:g}, "
                f"{cal.max_at_px[1]:g}) | {cal.max_at_deg:.1f} | {'yes' if cal.max_px < HOLDS_PX else 'no'} | "
                f"{', '.join(cal.fitted)} | {'—' if circle is None else f'{circle:.1f}'} |",
                flush=True,
            )
        figure(name, maps, FIGURES / f"{name}.png")


if __name__ == "__main__":
    main()
