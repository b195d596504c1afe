"""The settings of a render through a lens as one typed value: `RenderSpec` (frozen, checked when
built). `render_image`, `write_scene` and the render batch take it; the commands build it in one
place (`RenderSpec.from_args`) from flags that are made from its fields (`RenderSpec.add_flags`,
`options.OptionSpec`), so a render option is added by adding one field here: its default, its check
and its flag.

A batch sweeps over some of its fields with `dataclasses.replace`; each item's settings are
`as_dict()` in the manifest and read back with `from_dict`. Light: no Mitsuba or Dr.Jit here.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any, cast

from ..errors import SolasError
from ..optics.camera import BOUNDARIES, MAPPINGS
from ..options import OptionSpec, option, parse_wxh, wxh_text
from .labels import LABELS, parse_labels
from .mitsuba import MAX_SEED, VARIANTS, check_name

FRESNEL_MODES = ("transmit", "sample", "off")  # sellmeier_dielectric's `fresnel` (it reads them from here)
AUTO_MIN_RINGS = (
    32  # the fewest rings the automatic count (`render.mesh.mesh_rings`) gives; denser meshes render slower
)
# rings per cap mesh: 4·rings² vertices each. Measured (solas-doublet, meshes built and written, 2 cores):
# 256 rings 0.6 s, 39 MB of PLY, 0.26 GB peak; 512 rings 2.8 s, 157 MB, 0.86 GB; 1024 rings 10 s, 629 MB,
# 3.3 GB; 4096 rings would be 16x that (53 GB). The scene PSFs converged long before (32: 0.2 %, README)
MIN_RINGS, MAX_RINGS = 2, 512
MAX_SPP = 1 << 20


def _sensor(text: str) -> tuple[int, int]:
    return parse_wxh(text, "--sensor")


def _focus(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise SolasError(f"focus distance {text!r} must be a positive number of world units or inf") from None


@dataclass(frozen=True)
class RenderSpec(OptionSpec):
    """How to render through a lens, checked when built.

    `render_image`, `write_scene` and the render batch take it; the render commands make one flag of each
    field and build it from them.

    Parameters
    ----------
    sensor : (int, int), default (960, 1280)
        The sensor's pixels, (rows, columns) (a list, or "COLSxROWS" text, is read as such).
    pitch_um : float, optional
        The pixel pitch (µm); default: the sensor's width spans the field.
    fov_deg : float, optional
        Half the horizontal field the input image spans (degrees, below 180); default: the lens's.
    response : str, default "srgb"
        The camera response: srgb, lines, mono:<nm>, table:<file.csv> (`render.response`).
    boundary : str, default "edge"
        The object outside the image, one of `optics.camera.BOUNDARIES`.
    fresnel : str, default "transmit"
        Fresnel losses, one of `FRESNEL_MODES`.
    rings : int, optional
        Rings of each cap mesh (`MIN_RINGS` to `MAX_RINGS`); default: `render.mesh.mesh_rings`'s.
    mapping : str, default "rectilinear"
        The input image's projection, one of `optics.camera.MAPPINGS`.
    spp : int, default 64
        Samples per pixel (1 to `MAX_SPP`).
    variant : str, optional
        The Mitsuba variant, one of `render.mitsuba.VARIANTS`; default: `render.mitsuba.variant_for`'s.
    seed : int, default 0
        The sampler's seed (a batch's base seed).
    focus_distance : float, optional
        A scene file's lens camera focused this far (world units, inf allowed; `render.user_scene`); not
        an image's render. Default: the lens file's.
    labels : str, default ""
        A scene file's label layers (`render.labels`: names of `LABELS`, comma-separated); "": none.

    Raises
    ------
    SolasError
        For a value out of its range or not among its choices.

    Examples
    --------
    >>> from solas_mi.render import RenderSpec
    >>> spec = RenderSpec(sensor=(24, 32), spp=16)
    >>> spec.replace(spp=4).as_dict()["spp"], spec.sensor
    (4, (24, 32))
    """

    sensor: tuple[int, int] = option(
        "sensor pixels, columns x rows", (960, 1280), parse=_sensor, metavar="WxH", shown=wxh_text
    )
    pitch_um: float | None = option(
        "pixel pitch (µm; default: the sensor's width spans the field)", parse=float, metavar="P"
    )
    fov_deg: float | None = option(
        "half the horizontal field the image spans (degrees; default: the lens's)", parse=float
    )
    response: str = option("camera response: srgb, lines, mono:<nm>, table:<file.csv>", "srgb")
    boundary: str = option(
        "the object outside the image: edge (repeat the border), reflect, zero (black)", "edge", choices=BOUNDARIES
    )
    fresnel: str = option(
        "Fresnel losses (a coated surface's: its coating's): transmit (weight by transmittance), sample (ghost "
        "paths too), off",
        "transmit",
        choices=FRESNEL_MODES,
    )
    rings: int | None = option(
        f"rings of each cap mesh ({MIN_RINGS}..{MAX_RINGS}; default: from the lens, so that the "
        "meshes blur a point by under a quarter of the Airy radius)",
        parse=int,
    )
    mapping: str = option(
        "projection of the input image at infinity: rectilinear, or for wide and fisheye lenses "
        "equidistant, equisolid, equirectangular (an environment image spanning +-fov-deg)",
        "rectilinear",
        choices=MAPPINGS,
    )
    spp: int = option("samples per pixel", 64, parse=int, metavar="N")
    variant: str | None = option(
        "Mitsuba variant (default: cuda_ad_spectral with a GPU, else llvm_ad_spectral; a "
        "mono variant needs a response of one wavelength, mono:<nm>)",
        choices=VARIANTS,
    )
    seed: int = option("the sampler's seed (a batch's base seed: each item's derives from it)", 0, parse=int)
    focus_distance: float | None = option(
        "scene files: focus distance in world units (inf: infinity; default: the lens file's image plane)",
        parse=_focus,
        metavar="D",
    )
    labels: str = option(
        f"scene files through a lens: label layers traced along each pixel's chief ray into the EXR, "
        f"comma-separated: {', '.join(LABELS)} (default: none)",
        "",
        metavar="LIST",
    )

    def __post_init__(self) -> None:
        set_ = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (frozen: normalised once)
        set_("sensor", parse_wxh(tuple(self.sensor) if isinstance(self.sensor, list) else self.sensor, "sensor"))
        for name in ("pitch_um", "fov_deg", "focus_distance"):
            set_(name, _optional_positive(name, getattr(self, name), allow_inf=name == "focus_distance"))
        if self.fov_deg is not None and not self.fov_deg < 180.0:  # a fisheye's environment image spans the most
            raise SolasError(f"fov_deg {self.fov_deg!r} must be below 180 degrees (half the field the image spans)")
        if not isinstance(self.response, str) or not self.response.strip():
            raise SolasError(f"camera response {self.response!r} must be srgb, lines, mono:<nm> or table:<file.csv>")
        for name in ("boundary", "fresnel", "mapping"):
            allowed = cast(tuple, self.flags([name])[name].choices)  # these three flags' choices are tuples
            if getattr(self, name) not in allowed:
                raise SolasError(f"{name} {getattr(self, name)!r} must be one of {', '.join(allowed)}")
        set_("labels", ",".join(parse_labels(self.labels)))
        if self.rings is not None:
            check_rings(self.rings)
        _check_int("samples per pixel", self.spp, 1, MAX_SPP)
        _check_int("seed", self.seed, 0, MAX_SEED)
        if self.variant is not None:
            check_name(self.variant)

    def replace(self, **changes) -> RenderSpec:
        """A copy with some fields changed, checked.

        Parameters
        ----------
        **changes
            Field name → value.

        Returns
        -------
        RenderSpec
            The copy.

        Raises
        ------
        SolasError
            For a name that is not a field, or a bad value.
        """
        unknown = set(changes) - set(self.fields_by_name())
        if unknown:
            raise SolasError(
                f"unknown render setting(s) {', '.join(sorted(unknown))}: the settings are "
                f"{', '.join(self.fields_by_name())}"
            )
        return replace(self, **changes)

    def as_dict(self) -> dict[str, Any]:
        """The fields as JSON values (a batch's manifest).

        Returns
        -------
        dict
            Field name → value; the sensor as [rows, columns], an infinite focus distance as "inf".
        """
        out = asdict(self)
        out["sensor"] = list(self.sensor)
        if self.focus_distance is not None and math.isinf(self.focus_distance):
            out["focus_distance"] = "inf"  # JSON has no infinity; Mitsuba reads "inf"
        return out

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> RenderSpec:
        """The spec of `as_dict`'s values.

        Parameters
        ----------
        values : dict
            Field name → value; keys that are not fields are ignored.

        Returns
        -------
        RenderSpec
            The spec, checked.
        """
        known = {k: v for k, v in values.items() if k in cls.fields_by_name()}
        if known.get("focus_distance") == "inf":
            known["focus_distance"] = math.inf
        return cls(**known)


def check_rings(rings) -> int:
    """`rings` (rings per cap mesh), or SolasError unless it is an integer in MIN_RINGS..MAX_RINGS."""
    _check_int(
        "cap rings",
        rings,
        MIN_RINGS,
        MAX_RINGS,
        why=f" (a cap mesh has 4·rings² vertices: {MAX_RINGS} rings are 1 M per cap)",
    )
    return rings


def _check_int(what: str, value, low: int, high: int, why: str = "") -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise SolasError(f"{what} {value!r} must be an integer from {low} to {high}{why}")


def _optional_positive(name: str, value, allow_inf: bool = False) -> float | None:
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not number > 0 or (math.isinf(number) and not allow_inf):
        raise SolasError(
            f"{name} {value!r} must be a positive number" + (" or inf" if allow_inf else "") + " (or not given)"
        )
    return number
