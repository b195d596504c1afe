"""A comparison sheet of degraded images: each image whole, then crops of its centre and its
periphery enlarged, side by side (the layout of the SOLAS paper's figure 4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..imageio import atomic_path, srgb_encode


def crop_boxes(height: int, width: int, size: tuple[int, int] = (120, 160)) -> dict[str, tuple[int, int, int, int]]:
    """(row, column, rows, columns) of a centre crop and a periphery crop (upper-left, inset by 2 %)."""
    h, w = size
    inset_r, inset_c = int(0.02 * height), int(0.02 * width)
    return {"centre": ((height - h) // 2, (width - w) // 2, h, w), "periphery": (inset_r, inset_c, h, w)}


def comparison_sheet(images: dict[str, np.ndarray], path: str | Path, title: str = "") -> None:
    """Write a PNG sheet: one column per named linear image (H×W×3, all the same size); rows: the
    whole image, its centre crop, its periphery crop (crops marked on the whole images)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    names = list(images)
    height, width = next(iter(images.values())).shape[:2]
    boxes = crop_boxes(height, width)
    fig, axes = plt.subplots(3, len(names), figsize=(4.2 * len(names), 9.6), squeeze=False)
    for j, name in enumerate(names):
        rgb = np.clip(srgb_encode(np.clip(images[name], 0.0, None)), 0.0, 1.0)
        axes[0, j].imshow(rgb)
        axes[0, j].set_title(name, fontsize=11)
        for i, (crop, (r, c, h, w)) in enumerate(boxes.items(), start=1):
            axes[0, j].add_patch(Rectangle((c, r), w, h, fill=False, edgecolor="yellow", linewidth=1))
            axes[i, j].imshow(rgb[r : r + h, c : c + w], interpolation="nearest")
            axes[i, j].set_title(f"{crop} crop", fontsize=9)
    for ax in axes.ravel():
        ax.set_xticks([])
        ax.set_yticks([])
    if title:
        fig.suptitle(title, fontsize=12)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
