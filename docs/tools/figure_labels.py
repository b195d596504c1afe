"""The figure of docs/details/labels.md, "Labels through degrade": discs with ids in a 640x432 pinhole frame
through wide-angle-22mm, the top-left corner of the degraded frame (where the lens moves them most, 4.5 px)
with each disc's ids before (red) and after the warp (green) outlined.

    .venv/bin/python docs/tools/figure_labels.py docs/labels_degrade.png
"""

from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from solas_mi import Lens
from solas_mi.convolution.labels import warp_labels
from solas_mi.convolution.mapping import mapping_for
from solas_mi.convolution.methods import degrade
from solas_mi.psf.grid import psf_grid
from solas_mi.psf.spec import GridSpec

W, H, R, CROP = 640, 432, 9, (slice(0, 96), slice(0, 144))


def main(path: str) -> None:
    lens = Lens.load("wide-angle-22mm")
    grid = psf_grid(
        lens,
        GridSpec(
            grid=(11, 9),
            size=41,
            method="geometric",
            rays=96,
            field_sampling="edges",
            wavelengths_nm=(lens.primary_wavelength,),
            field_range_deg=(40.0, 29.0),
            pitch_um=8.0,
        ),
    )
    rows, cols = np.mgrid[:H, :W]
    ids = np.zeros((H, W))
    for k, (cy, cx) in enumerate(((y, x) for y in range(20, H, 36) for x in range(20, W, 36)), start=1):
        ids[(rows - cy) ** 2 + (cols - cx) ** 2 <= R**2] = k
    image = degrade((ids > 0).astype(float), grid)
    layers, _, meta = warp_labels({"instance": (ids[..., None], "ids")}, mapping_for(grid, W, H), "edge")
    fig, ax = plt.subplots(figsize=(7.2, 4.9), dpi=100)
    ax.imshow(image[CROP], cmap="gray", vmin=0, vmax=1, interpolation="nearest")
    for layer, colour, name in ((ids, "red", "ids as given"), (layers["instance.id"], "lime", "ids warped")):
        ax.contour(layer[CROP] > 0, levels=[0.5], colors=colour, linewidths=1.0)
        ax.plot([], [], color=colour, label=name)
    ax.set_title(
        f"wide-angle-22mm, {W}x{H} frame, top-left corner: the lens moves the discs by up to "
        f"{meta['max_chief_ray_offset_px']:.1f} px",
        fontsize=9,
    )
    ax.legend(loc="lower right", fontsize=8)
    ax.set_xlabel("column (px)")
    ax.set_ylabel("row (px)")
    fig.tight_layout()
    fig.savefig(path)


if __name__ == "__main__":
    main(sys.argv[1])
