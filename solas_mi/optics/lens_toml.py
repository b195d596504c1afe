"""Our TOML lens file written from a `Lens` (the reader is `Lens.from_dict`): every key the reader
knows, numbers written in full (Python's shortest exact form), so reading the text back gives the
same lens. Lengths in mm, wavelengths in nm, field in degrees."""

from __future__ import annotations

import json
import math

from . import thermal


def _value(v) -> str:
    """A TOML value: booleans, numbers in their exact shortest form, strings and lists."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v))
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):  # an inline table; its keys are bare words (a coating's)
        return "{" + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + "}"
    return text(v)


def text(v) -> str:
    """`v` as one quoted, escaped string (a TOML basic string, also JSON): no line break, quote or
    control character of the value can end it or add a line or a key (DEL, which JSON leaves raw and
    TOML forbids, escaped too)."""
    return json.dumps(str(v), ensure_ascii=False).replace("\x7f", "\\u007f")


def _material(g) -> list[str]:
    """The keys of a lens file's own material `g` (a `glass.Glass`) in its [materials.NAME] table."""
    a, b = g.coefficients
    if g.kind == "table":
        return [f"wavelengths_nm = {_value(a)}", f"index = {_value(b)}"]
    if g.kind == "model":  # a one-entry table: one index, no dispersion
        return ["wavelengths_nm = [587.5618]", f"index = {_value(a)}"]
    keys = {"sellmeier": ("B", "C"), "polynomial": ("K", "P"), "conrady": ("conrady",)}[g.kind]
    heat = (
        ([f"thermal = {_value(g.thermal)}", f"reference_c = {_value(g.reference_c)}"] if g.thermal else [])
        + ([f"cte = {_value(g.cte)}"] if g.cte is not None else [])
        + ([f"melt = {_value(g.melt)}"] if g.melt else [])
    )
    return [f"{k} = {_value(v)}" for k, v in zip(keys, (a, b))] + [f"range_nm = {_value(g.range_nm)}"] + heat


def dumps(lens) -> str:
    """The TOML text of `lens` (a `solas_mi.optics.lens.Lens`)."""
    lines = [
        f"# {text(lens.name)}: lens file written by solas-mi (lengths in mm, wavelengths in nm)",
        f"name = {_value(lens.name)}",
    ]
    if lens.description:
        lines.append(f"description = {_value(lens.description)}")
    lines += [f"wavelengths_nm = {_value(lens.wavelengths_nm)}", f"field_deg = {_value(lens.field_deg)}"]
    if lens.catalogues:
        lines.append(f"catalogues = {_value(lens.catalogues)}")
    if (lens.temperature_c, lens.pressure_kpa) != (thermal.STANDARD_C, thermal.STANDARD_KPA):
        lines += [f"temperature_c = {_value(lens.temperature_c)}", f"pressure_kpa = {_value(lens.pressure_kpa)}"]
    for g in lens.materials:
        lines += ["", f"[materials.{text(g.name)}]", *_material(g)]
    lines += [
        "",
        "[object]",
        f"distance = {_value('infinity') if math.isinf(lens.object_distance) else _value(lens.object_distance)}",
    ]
    if lens.object_glass.kind != "air":
        lines.append(f"material = {_value(lens.object_glass.name)}")
    for s in lens.surfaces:
        lines += ["", "[[surface]]", f"label = {_value(s.label)}"]
        shape = {"kind": s.form.kind, **s.form.table()} if s.form else {"radius": s.radius}
        lines += [f"{key} = {_value(value)}" for key, value in shape.items()]
        if s.conic:
            lines.append(f"conic = {_value(s.conic)}")
        if any(s.aspheric):
            lines.append(f"aspheric = {_value(s.aspheric)}")
        if s.ideal:
            lines.append(f"focal_length = {_value(s.focal_length)}")
        if any(s.qbfs):
            lines += [f"qbfs = {_value(s.qbfs)}", f"norm_radius = {_value(s.norm_radius)}"]
        lines += [
            f"thickness = {_value(s.thickness)}",
            f"diameter = {_value(s.diameter)}",
            f"material = {_value(s.material)}",
        ]
        if s.stop:
            lines.append("stop = true")
        if s.coating:
            lines.append(f"coating = {_value(s.coating.table())}")
        if s.blades:
            lines += [f"blades = {s.blades}", f"blade_rotation = {_value(s.blade_rotation)}"]
        if s.blade_curvature:
            lines.append(f"blade_curvature = {_value(s.blade_curvature)}")
        if s.mount is not None:
            lines.append(f"mount = {_value(s.mount)}")
        if s.placement:  # the order flag an integer
            lines += [f"{k} = {v if k == 'tilt_order' else _value(v)}" for k, v in s.placement.table().items()]
    image = {"diameter": lens.image_diameter} if lens.image_diameter else {}
    image.update(lens.image_placement.table() if lens.image_placement else {})
    if image:
        lines += ["", "[image]"] + [f"{k} = {v if k == 'tilt_order' else _value(v)}" for k, v in image.items()]
    return "\n".join(lines) + "\n"
