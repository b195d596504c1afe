"""Direct spectral rendering with Mitsuba 3, the lens as geometry: glass caps carrying
`sellmeier_dielectric`, the `lens_sensor` on the image plane, the input image as `image_object`
(the plugins live in `plugins/`, installed as `solas_mi.plugins`).

`spec` holds a render's settings as one value (`RenderSpec`: sensor, pitch, spp, response, field,
boundary, Fresnel, rings, mapping, variant, seed, focus), which the commands build from its flags and
`render_image`, `write_scene` and the render batch take.

In the order of the data: `scene` (a lens → meshes + scene XML) → `mitsuba` (the variant, the plugins
registered for it, loading a scene) → `loop` (the path loop: a scene → a `Render`); `image` chains
them for an input image (`render_image`). Beside them: `sampling` (stratified sample patterns) and
`response` (camera spectral responses); `commands`: `scene`, `render`, `render-image`.

    render_image(lens, "photo.png", sensor=(960, 1280), spp=64).write("out.exr")
    render_image(lens, "photo.png", RenderSpec(sensor=(960, 1280), response="lines", rings=64))
"""

from ..lazy import lazy_exports
from ..psf.registry import METHODS, RAYS

__all__ = ["Render", "RenderSpec", "render_image", "render_scene", "write_scene"]
__getattr__ = lazy_exports(
    __name__,
    {
        "Render": ".loop",
        "RenderSpec": ".spec",
        "render_image": ".image",
        "render_scene": ".stock",
        "write_scene": ".scene",
    },
)


# this stage adds its PSF method to the registry of the lower stage (which imports nothing from here)
@METHODS.register(
    "render",
    options=(RAYS,),
    meshes=True,
    summary="the entrance-grid rays traced through the Mitsuba scene's lens meshes, binned per pixel",
)
def _render_psfs(*args, **kwargs):
    """The PSF method "render" (`psf.registry`): `psf.compute`, imported when it computes (it loads Mitsuba)."""
    from .psf import compute

    return compute(*args, **kwargs)
