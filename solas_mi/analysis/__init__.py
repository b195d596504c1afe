"""Lens analyses: the plots an optical engineer opens first, each a function of a lens returning a frozen
result (`base.Result`: its numbers, `table()`, `plot()`, `write(png)` with JSON and CSV beside it) and a
`solas-mi lens <name>` command. The registry naming them with the options each takes (`registry.ANALYSES`),
the options defined once (`options`) and checked (`inputs`); one module per family: `mtf`, `mtf_field`
and `through_focus` (the diffraction OTF from the pupil's autocorrelation, `otf`), `field_curvature`,
`distortion`, `colour` (lateral colour, relative illumination), `fans` (ray and OPD fans, `rays`),
`wavefront` (with `zernike`), `spots`, `energy`; `report` (every analysis and an index page),
`figures` (what the figures share), `commands` (the CLI).

    ANALYSES["mtf"].function(lens, fields_deg=[0, 14], pixel_pitch_um=3.0).write("mtf.png")
"""

from ..lazy import lazy_exports

__all__ = ["ANALYSES", "Result", "Table"]
__getattr__ = lazy_exports(__name__, {"ANALYSES": ".registry", "Result": ".base", "Table": ".base"})
