"""Point spread functions: the conventions every PSF shares (`base`), one module per method
(`fraunhofer`, `geometric`), the registry naming them with their own options (`registry`; a later
stage registers its own, as render does "render"), `psf` for one field (`methods`), PSF grids over
the field (`grid`), their PSFs and file (`grid_file.PSFGrid`) and their options as one value
(`spec.GridSpec`), the two-reflection ghosts (`stray_light`: `ghosts`), the stray-light PSF (`stray_psf`) and
ghost grids over the field (`ghost_nodes.ghost_grid`, `ghost_grid_file.GhostGrid`), and the `psf` / `psf-grid` / `ghosts` /
`ghost-grid` commands (`commands`).

    psf(lens, (0, 2), 531.0, pitch_um=0.5, size=160)              # one PSF
    psf_grid(lens, grid=(32, 32), wavelengths_nm=[656, 531, 486])  # PSFGrid; .write / PSFGrid.read
    psf_grid(lens, GridSpec(grid=(24, 32), method="geometric", rays=256))
    ghosts(lens, (0, 2)).table()                                    # GhostReport: every ghost's energy, place
    ghost_grid(lens).at((3, 4)).image(10.0, 512)                    # GhostGrid: the ghosts of any field
"""

from ..lazy import lazy_exports

__all__ = [
    "METHODS",
    "PSF",
    "GridSpec",
    "PSFGrid",
    "psf",
    "psf_grid",
    "ghosts",
    "GhostReport",
    "ghost_grid",
    "GhostGrid",
]
__getattr__ = lazy_exports(
    __name__,
    {
        "METHODS": ".registry",
        "PSF": ".base",
        "GridSpec": ".spec",
        "PSFGrid": ".grid_file",
        "psf": ".methods",
        "psf_grid": ".grid",
        "ghosts": ".stray_light",
        "GhostReport": ".stray_light",
        "ghost_grid": ".ghost_nodes",
        "GhostGrid": ".ghost_grid_file",
    },
)
