"""What every analysis figure shares: a matplotlib `Figure` without pyplot (no window, no global state),
a grid of panels laid out so that no label is cut, a title naming the lens and the analysis, one
colour per field or wavelength, and the PNG written at one resolution."""

from __future__ import annotations

import math

DPI = 110
PANEL_SIZE = (4.6, 3.5)  # inches per panel
LINESTYLES = {"tangential": "-", "sagittal": "--"}


def figure(result, panels: int = 1, columns: int = 2, size: tuple[float, float] = PANEL_SIZE, **kwargs):
    """A Figure of `panels` axes in rows of at most `columns`, titled with `result`'s lens and analysis;
    the figure and its axes (a flat list, `panels` long)."""
    from matplotlib.figure import Figure

    cols = max(1, min(columns, panels))
    rows = math.ceil(panels / cols)
    fig = Figure(figsize=(size[0] * cols, size[1] * rows + 0.5), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False, **kwargs).ravel()
    for ax in axes[panels:]:
        ax.set_visible(False)
    fig.suptitle(f"{result.lens}: {result.name}")
    return fig, list(axes[:panels])


def colours(n: int) -> list:
    """n distinct colours (matplotlib's tab10, then viridis for more)."""
    from matplotlib import colormaps

    if n <= 10:
        return [colormaps["tab10"](i) for i in range(n)]
    return [colormaps["viridis"](i / max(1, n - 1)) for i in range(n)]


def wavelength_colour(wavelength_nm: float):
    """A colour for a wavelength: blue at 450 nm and shorter, red at 650 nm and longer (a visible cue)."""
    from matplotlib import colormaps

    return colormaps["turbo"](min(1.0, max(0.0, (wavelength_nm - 430.0) / 240.0)) * 0.9 + 0.05)


def legend(ax, **kwargs) -> None:
    """A legend beside the axes when it has entries, in a small font."""
    handles, _ = ax.get_legend_handles_labels()
    if handles:
        ax.legend(fontsize="small", **kwargs)


def save(fig, path: str) -> None:
    """Write `fig` as a PNG to `path` (its bounding box around everything drawn: nothing is cut)."""
    fig.savefig(path, format="png", dpi=DPI, bbox_inches="tight", pad_inches=0.1)
