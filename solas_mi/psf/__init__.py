"""Point spread functions: the conventions every PSF shares (`base`), one module per method
(`fraunhofer`, `geometric`), the registry naming them (`methods`, with `psf` for one field), PSF
grids over the field (`grid`) and the `psf` / `psf-grid` commands (`commands`).

    psf(lens, (0, 2), 531.0, pitch_um=0.5, size=160)              # one PSF
    psf_grid(lens, grid=(32, 32), wavelengths_nm=[656, 531, 486])  # PSFGrid; .write / PSFGrid.read
"""
from ..lazy import lazy_exports

__all__ = ["METHODS", "PSF", "PSFGrid", "psf", "psf_grid"]
__getattr__ = lazy_exports(__name__, {"METHODS": ".methods", "PSF": ".base", "PSFGrid": ".grid", "psf": ".methods",
                                      "psf_grid": ".grid"})
