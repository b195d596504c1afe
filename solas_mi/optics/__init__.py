"""Lens physics: the prescription and its glass (`lens`, `glass`), first-order data (`paraxial`),
the Float64 sequential tracer (`tracer`), real-ray aiming and the pupil function (`pupil`), spot
diagrams (`spot`), the exit-pupil bound a sensor samples (`exit_pupil`), image irradiance
(`illumination`), distortion and the closest projection (`distortion`) and the ideal camera an input
image stands for (`camera`). Lens file formats: `zemax` (.zmx), `codev` (.seq, read), `pbrt_dat` (.dat), `lens_toml` (our
TOML, written). `commands`: `lens info`, `lens convert`.

A lens is data; analyses take it as their first argument: `paraxial(lens, 531.0)`,
`spot(lens, (0, 2), 531.0)` (also exported by `solas_mi` itself).
"""
from ..lazy import lazy_exports
from . import codev, zemax  # noqa: F401 - add the .seq and .zmx readers (and .zmx writer) to formats

__all__ = ["Lens"]
__getattr__ = lazy_exports(__name__, {"Lens": ".lens"})
