"""The render that is calling a plugin: its scene and integrator.

Mitsuba 3.9 does not forward `set_scene` (nor any other call carrying the scene or the integrator) to
plugins written in Python, so a plugin that needs them — the image's bounding sphere for light
tracing, the lens sensor's check of the integrator — finds them on the Python call stack: the
function that started the render (`mi.render`, or a user's own `integrator.render(scene, …)`) holds
both. The scalar variants render on worker threads, so the stacks of all threads are searched, the
caller's first. In the JIT variants this runs once per traced kernel; the scalar variants call it
per sample, so callers cache what they learn.
"""

from __future__ import annotations

import sys
import threading

import mitsuba as mi

# Mitsuba class names of the integrators, as their plugin names
INTEGRATOR_NAMES = {
    "PathIntegrator": "path",
    "VolumetricPathIntegrator": "volpath",
    "AOVIntegrator": "aov",
    "DirectIntegrator": "direct",
    "ParticleTracerIntegrator": "ptracer",
    "VolpathMisIntegratorImpl": "volpathmis",
    "PRBIntegrator": "prb",
    "DepthIntegrator": "depth",
}


def integrator_name(integrator) -> str:
    """The plugin name of an integrator (`path`, `direct`, …), else its class name."""
    cls = integrator.class_name() if type(integrator).__module__.startswith("mitsuba") else type(integrator).__name__
    return INTEGRATOR_NAMES.get(cls, cls)


def calling_render() -> tuple[object, object]:
    """(scene, integrator) of the innermost render on the call stack (this thread's, else another's);
    either is None if not found. A scene alone stands for its `scene.integrator()`."""
    here = threading.get_ident()
    stacks = [sys._getframe(1)] + [f for ident, f in sys._current_frames().items() if ident != here]
    for frame in stacks:
        found = _render_in(frame)
        if found is not None:
            return found
    return None, None


def _render_in(frame):
    """(scene, integrator) of the innermost frame of this stack that holds either, else None."""
    while frame is not None:
        values = list(frame.f_locals.values())
        scene = next((v for v in values if isinstance(v, mi.Scene)), None)
        integrator = next((v for v in values if isinstance(v, mi.Integrator)), None)
        if integrator is None and scene is not None:
            integrator = scene.integrator()
        if scene is not None or integrator is not None:
            return scene, integrator
        frame = frame.f_back
    return None
