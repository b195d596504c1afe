"""The PSF grid's PNG for viewing: its mosaic (`PSFGrid.preview`) drawn as a plot whose axes say where
each PSF is — the field angle of its node in degrees — and whose title gives the tiles' physical size
in µm, the wavelengths and the scaling (each PSF to its own peak). matplotlib is imported only here."""

from __future__ import annotations

import math
import os

import numpy as np

MAX_TICKS = 9  # node labels per axis; a larger grid labels every k-th node
MARGIN_PX = 8  # between the outermost label and the edge of the image
MIN_SIDE_PX = 480  # a smaller mosaic is drawn at a whole multiple of its size, at least this on its longer side


def _ticks(count: int, tile: int) -> tuple[np.ndarray, np.ndarray]:
    """(indices of the labelled nodes, their centres in mosaic pixels)."""
    nodes = np.unique(np.linspace(0, count - 1, min(count, MAX_TICKS)).round().astype(int))
    return nodes, (nodes + 0.5) * tile


def colour_note(wavelengths_nm) -> str:
    """How the wavelengths are shown: three as R, G, B (longest red), else their mean in grey."""
    names = ", ".join(f"{w:g}" for w in sorted(wavelengths_nm, reverse=True))
    return f"R, G, B = {names} nm" if len(wavelengths_nm) == 3 else f"grey: mean of {names} nm"


def plot_grid(grid, image: np.ndarray, path: str | os.PathLike, dpi: int = 100) -> None:
    """Write `image` (the mosaic of `grid`, linear [0, 1], H×W or H×W×3) to `path` as a PNG with its
    axes in field degrees (node centres labelled) and a title naming tile size, pitch and wavelengths."""
    from matplotlib.figure import Figure

    from ..imageio import atomic_path, check_finite, srgb_encode

    check_finite(np.asarray(image), str(path))
    height, width = image.shape[:2]
    ny, nx = grid.shape
    shown = np.clip(srgb_encode(np.clip(image, 0.0, 1.0)), 0.0, 1.0)
    zoom = max(1, -(-MIN_SIDE_PX // max(width, height)))  # a small mosaic drawn larger, each pixel a block
    fig = Figure(dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(shown, cmap="gray", vmin=0, vmax=1, interpolation="nearest", extent=(0, width, height, 0))
    cols, x_at = _ticks(nx, width // nx)
    rows, y_at = _ticks(ny, height // ny)
    ax.set_xticks(x_at, [f"{grid.fields_deg[ny // 2, c, 0]:.3g}" for c in cols])
    ax.set_yticks(y_at, [f"{grid.fields_deg[r, nx // 2, 1]:.3g}" for r in rows])
    ax.set_xlabel("field x (deg), node centres")
    ax.set_ylabel("field y (deg)")
    ax.set_title(
        f"{ny}×{nx} nodes, each PSF {grid.size} px × {grid.pitch_um:g} µm = {grid.size * grid.pitch_um:g} µm "
        f"wide, scaled to its peak; {colour_note(grid.wavelengths_nm)}",
        fontsize=8,
    )
    _fit_margins(fig, ax, zoom * width, zoom * height)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)


def _fit_margins(fig, ax, width: int, height: int, pad: int = MARGIN_PX) -> None:
    """Size the figure around `ax` (the mosaic, drawn `width` × `height` px) so that its tick labels, axis
    labels and title lie inside it, `pad` px from each edge, whatever their length."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    ax.set_position((0, 0, 1, 1))
    fig.set_size_inches(width / fig.dpi, height / fig.dpi)
    box = ax.get_tightbbox(FigureCanvasAgg(fig).get_renderer())  # in pixels, the axes at (0, 0, width, height)
    left, bottom = pad - min(box.x0, 0.0), pad - min(box.y0, 0.0)
    wide = math.ceil(left + max(box.x1, width) + pad)  # whole pixels: the PNG is this size
    high = math.ceil(bottom + max(box.y1, height) + pad)
    fig.set_size_inches(wide / fig.dpi, high / fig.dpi)
    ax.set_position((left / wide, bottom / high, width / wide, height / high))
