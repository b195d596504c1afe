"""Lens physics: the prescription and its glass (`lens`, `glass`), first-order data (`paraxial`),
the Float64 sequential tracer (`tracer`), real-ray aiming and the pupil function (`pupil`), spot
diagrams (`spot`), the exit-pupil bound a sensor samples (`exit_pupil`), image irradiance
(`illumination`), distortion and the closest projection (`distortion`) and the ideal camera an input
image stands for (`camera`). Lens file formats: `formats` (the readers and writers by extension,
registered here, each format's module beside it). `commands`: `lens info`, `lens convert`.

A lens is data; analyses take it as their first argument: `paraxial(lens, 531.0)`,
`spot(lens, (0, 2), 531.0)` (also exported by `solas_mi` itself).
"""

from ..lazy import lazy_exports
from . import codev, lens_toml, pbrt_dat, zemax
from .formats import READERS, WRITERS, read_toml_lens, text_reader

__all__ = ["Lens"]
__getattr__ = lazy_exports(__name__, {"Lens": ".lens"})

# The lens file formats, in the order messages list them. Registered here, where Python runs before any
# module of this package is used: the readers import `Lens` (they solve apertures with the tracer), which
# reads files through these registries.
READERS.register(".toml", read_toml_lens, summary="our TOML lens file: every key `Lens.from_dict` knows")
READERS.register(".zmx", text_reader(zemax.read_spec), summary="Zemax OpticStudio sequential lens file (`zemax`)")
READERS.register(".seq", text_reader(codev.read_spec), summary="CODE V sequence file (`codev`)")
READERS.register(
    ".dat",
    text_reader(pbrt_dat.read_spec),
    check=pbrt_dat.check_read,
    summary="pbrt lens table: radius, thickness, n_d, aperture per row (`pbrt_dat`)",
)
WRITERS.register(
    ".toml",
    lens_toml.dumps,
    holds=("coatings", "blades", "surfaces without rotational symmetry", "coordinate breaks"),
    summary="our TOML lens file, numbers in full: it reads back as the same lens (`lens_toml`)",
)
WRITERS.register(
    ".zmx",
    zemax.dumps,
    holds=("coatings", "surfaces without rotational symmetry", "coordinate breaks"),
    summary="Zemax OpticStudio sequential lens file (`zemax`)",
)
WRITERS.register(
    ".dat", pbrt_dat.dumps, summary="pbrt lens table, spherical surfaces and an object at infinity only (`pbrt_dat`)"
)
