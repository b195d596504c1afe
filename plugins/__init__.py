"""The Mitsuba plugins of solas-mi, written in Python (installed as `solas_mi.plugins`):

| plugin                 | kind    | module                    |
|------------------------|---------|---------------------------|
| `lens_sensor`          | sensor  | `lens_sensor.py`          |
| `sellmeier_dielectric` | BSDF    | `sellmeier_dielectric.py` |
| `coated_dielectric`    | BSDF    | `coated_dielectric.py`    |
| `image_object`         | emitter | `image_object.py`         |
| `lens_camera`          | sensor  | `lens_camera.py`          |

Each module documents its parameters. The modules subclass the types of Mitsuba's current variant,
so they are imported only by `register`, after a variant is set (`solas_mi.render.mitsuba`), in the
order of `PLUGINS` (`coated_dielectric` after the `sellmeier_dielectric` it subclasses). Beside them, for both sensors: `lens_film` (their core: lens, response, film and crop window, pupil and
wavelengths; its base class, too, subclasses the variant's `mi.Sensor`), `pupil_sampling` (rays
toward the exit pupil) and `wavelength_sampling` (a path's wavelength from the camera response);
`tables` (lookup tables and records in every variant) and `scene_probe` (the scene and integrator
of the render calling a plugin, which Mitsuba does not pass to Python plugins).
"""

from __future__ import annotations

import importlib

PLUGINS = ("sellmeier_dielectric", "coated_dielectric", "image_object", "lens_sensor", "lens_camera")
BASES = ("lens_film",)  # modules of base classes of the variant's types, reloaded before the plugins


def register() -> None:
    """(Re)import the plugin modules for Mitsuba's current variant and register them under their names.
    The reload is needed after a variant change: the classes must subclass the new variant's types.
    Each registration keeps its own variant's class, so registering once per variant suffices."""
    for name in BASES:
        importlib.reload(importlib.import_module(f"{__name__}.{name}"))
    for name in PLUGINS:
        module = importlib.import_module(f"{__name__}.{name}")
        importlib.reload(module).register()
