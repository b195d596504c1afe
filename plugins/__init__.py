"""The Mitsuba plugins of solas-mi, written in Python (installed as `solas_mi.plugins`):

| plugin                 | kind    | module                    |
|------------------------|---------|---------------------------|
| `lens_sensor`          | sensor  | `lens_sensor.py`          |
| `sellmeier_dielectric` | BSDF    | `sellmeier_dielectric.py` |
| `image_object`         | emitter | `image_object.py`         |

Each module documents its parameters. The modules subclass the types of Mitsuba's current variant,
so they are imported only by `register`, after a variant is set (`solas_mi.render.mitsuba`).
"""
from __future__ import annotations

import importlib

PLUGINS = ("sellmeier_dielectric", "image_object", "lens_sensor")


def register() -> None:
    """(Re)import the plugin modules for Mitsuba's current variant and register them under their names.
    The reload is needed after a variant change: the classes must subclass the new variant's types."""
    for name in PLUGINS:
        module = importlib.import_module(f"{__name__}.{name}")
        importlib.reload(module).register()
