"""A user's Mitsuba scene file prepared for rendering: the scene's own integrator (stock `path` where it
has none) and, with a lens, its `perspective` (or `thinlens`) sensor replaced by a `lens_camera` at the
same pose (`to_world`), with the same film and sampler.

The default pixel pitch makes the real lens's field match the perspective camera's: the real chief ray
of the field half-angle along the camera's `fov_axis` (x, y or the diagonal) lands at the film's edge
there, at the lens's primary wavelength (distortion elsewhere is the lens's own). Lengths in the scene
are world units; the lens camera converts with `world_unit_mm` (default 1000: metres).
"""
from __future__ import annotations

import math
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import SolasError, plugin_error
from .scene import lens_file

SWAPPABLE = ("perspective", "thinlens")
FILM_35MM_WIDTH_MM = 36.0  # Mitsuba's `focal_length` is a 35 mm-equivalent


def _value(element: ET.Element, defaults: dict[str, str]) -> str:
    value = element.get("value", "")
    return defaults.get(value[1:], value) if value.startswith("$") else value


def _property(sensor: ET.Element, name: str, defaults: dict[str, str]) -> str | None:
    for child in sensor:
        if child.get("name") == name:
            return _value(child, defaults)
    return None


def _film_size(sensor: ET.Element, defaults: dict[str, str]) -> tuple[int, int]:
    film = sensor.find("film")
    size = {"width": 768, "height": 576}  # Mitsuba's film defaults
    if film is not None:
        for child in film:
            if child.get("name") in size:
                size[child.get("name")] = int(float(_value(child, defaults)))
    return size["width"], size["height"]


def scene_film_size(xml_path: str | Path) -> tuple[int, int]:
    """(width, height) pixels of the film of the first sensor of the scene file `xml_path`."""
    try:
        root = ET.parse(xml_path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise SolasError(f"scene {xml_path} cannot be read as XML: {exc}") from None
    sensor = root.find("sensor")
    defaults = {d.get("name"): d.get("value") for d in root.iter("default")}
    return _film_size(sensor if sensor is not None else ET.Element("sensor"), defaults)


def field_half_angle(sensor: ET.Element, defaults: dict[str, str]) -> tuple[float, str]:
    """(half field in degrees, axis "x" | "y" | "diagonal") of a perspective sensor element."""
    fov, focal = _property(sensor, "fov", defaults), _property(sensor, "focal_length", defaults)
    axis = (_property(sensor, "fov_axis", defaults) or "x").lower()
    width, height = _film_size(sensor, defaults)
    if axis in ("smaller", "larger"):
        axis = "x" if (width <= height) == (axis == "smaller") else "y"
    if axis not in ("x", "y", "diagonal"):
        raise SolasError(f"sensor fov_axis {axis!r} must be one of x, y, diagonal, smaller, larger")
    if fov is not None:
        return 0.5 * float(fov), axis
    if focal is not None:  # 35 mm-equivalent focal length across the film's width
        f = float(focal.lower().removesuffix("mm"))
        return math.degrees(math.atan(0.5 * FILM_35MM_WIDTH_MM / f)), "x"
    raise SolasError("the scene's sensor has neither fov nor focal_length; give --pitch-um")


def default_pitch_um(lens, half_deg: float, axis: str, width: int, height: int) -> float:
    """Pixel pitch (µm) whose film edge along `axis` meets the real chief ray of `half_deg`."""
    from ..optics.pupil import chief_rays

    if not 0.0 < half_deg < 89.0:
        raise SolasError(f"the scene's camera half field {half_deg:g} deg must lie in (0, 89) degrees")
    span = {"x": width, "y": height, "diagonal": math.hypot(width, height)}[axis]
    direction = {"x": (1.0, 0.0), "y": (0.0, 1.0), "diagonal": (width / math.hypot(width, height),
                                                                   height / math.hypot(width, height))}[axis]
    t = math.tan(math.radians(half_deg))
    field = np.degrees(np.arctan(np.array([[t * direction[0], t * direction[1]]])))
    try:
        xy = chief_rays(lens, field, np.array([lens.primary_wavelength])).image_xy[0]
    except SolasError as exc:
        raise SolasError(f"the scene's camera sees ±{half_deg:g} deg along {axis} and lens {lens.name} cannot image "
                         f"that field ({exc}); narrow the camera's fov, or give --pitch-um for a film that the "
                         "lens's field covers") from None
    return 2e3 * float(np.hypot(*xy)) / span


def scene_text(xml_path: str | Path, lens=None, pitch_um: float | None = None, focus_distance: float | None = None,
               response: str | None = None, world_unit_mm: float | None = None,
               lens_folder: str | Path | None = None) -> str:
    """The scene XML at `xml_path` as text, with a `path` integrator if it has none and, given `lens`,
    its first sensor replaced by a `lens_camera` at the same `to_world`, film and sampler, naming a
    file that holds the lens (`render.scene.lens_file`: written into `lens_folder` when the lens was
    changed in memory)."""
    path = Path(xml_path)
    if not path.is_file():
        raise SolasError(f"no such scene file: {path}")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise SolasError(f"scene {path} is not valid XML: {exc}") from None
    if root.find("integrator") is None:
        root.insert(0, ET.Element("integrator", {"type": "path"}))
    if lens is not None:
        _swap_sensor(root, path, lens, pitch_um, focus_distance, response, world_unit_mm, lens_folder)
    return ET.tostring(root, encoding="unicode")


def _swap_sensor(root: ET.Element, path: Path, lens, pitch_um, focus_distance, response, world_unit_mm,
                 lens_folder) -> None:
    defaults = {d.get("name"): d.get("value") for d in root.iter("default")}
    sensors = root.findall("sensor")
    if not sensors:
        raise SolasError(f"scene {path} has no <sensor>; add a perspective camera where the lens should be")
    old = sensors[0]
    kind = old.get("type")
    if kind not in SWAPPABLE:
        raise SolasError(f"the scene's sensor is {kind!r}; --lens replaces a {' or '.join(SWAPPABLE)} camera")
    held = lens_file(lens, lens_folder)
    width, height = _film_size(old, defaults)
    if pitch_um is None:
        pitch_um = default_pitch_um(lens, *field_half_angle(old, defaults), width, height)
    elif not (isinstance(pitch_um, (int, float)) and 0.0 < pitch_um < 1e4):
        raise SolasError(f"pixel pitch {pitch_um!r} um must be a positive number below 1e4")
    new = ET.Element("sensor", {"type": "lens_camera"})
    ET.SubElement(new, "string", {"name": "lens", "value": str(held.resolve())})
    ET.SubElement(new, "float", {"name": "pitch_um", "value": repr(float(pitch_um))})
    for name, value, tag in (("focus_distance", focus_distance, "float"), ("world_unit_mm", world_unit_mm, "float"),
                             ("response", response, "string")):
        if value is not None:
            ET.SubElement(new, tag, {"name": name, "value": str(value)})
    for child in old:
        if child.tag in ("transform", "film", "sampler") or (child.tag == "ref" and child.get("name") is None):
            new.append(child)
    root[list(root).index(old)] = new


def load(xml_path: str | Path, variant: str | None = None, lens=None, params: dict | None = None, **lens_options):
    """The scene of `scene_text` loaded in Mitsuba (plugins registered), relative paths resolved from
    the scene file's folder; `params` fill its <default> values."""
    from .mitsuba import mitsuba

    with tempfile.TemporaryDirectory(prefix="solas-lens-") as folder:  # the lens camera reads its lens while loading
        text = scene_text(xml_path, lens, lens_folder=folder, **lens_options)
        defaults = sorted(d.get("name") for d in ET.fromstring(text).iter("default"))
        unknown = sorted(set(params or {}) - set(defaults))
        if unknown:
            raise SolasError(f"scene {xml_path} has no <default> named {', '.join(unknown)}; "
                             f"its defaults: {', '.join(defaults) or 'none'}")
        mi = mitsuba(variant)
        resolver = mi.file_resolver()
        resolver.prepend(str(Path(xml_path).resolve().parent))
        try:
            return mi.load_string(text, **{k: str(v) for k, v in (params or {}).items()})
        except RuntimeError as exc:
            raise plugin_error(exc, f"cannot load scene {xml_path}") from None
        finally:
            del resolver[0]
