"""Direct spectral rendering with Mitsuba 3, the lens as geometry: glass caps carrying
`sellmeier_dielectric`, the `lens_sensor` on the image plane, the input image as `image_object`
(the plugins live in `plugins/`, installed as `solas_mi.plugins`).

In the order of the data: `scene` (a lens → meshes + scene XML) → `mitsuba` (the variant, the plugins
registered for it, loading a scene) → `loop` (the path loop: a scene → a `Render`); `image` chains
them for an input image (`render_image`). Beside them: `sampling` (stratified sample patterns) and
`response` (camera spectral responses); `commands`: `scene`, `render`, `render-image`.

    render_image(lens, "photo.png", sensor=(960, 1280), spp=64).write("out.exr")
"""
from ..psf.registry import RAYS, PSFMethod, register_method


def _render_psfs(*args, **kwargs):
    """The PSF method "render" (`psf.registry`): `psf.compute`, imported when it computes (it loads Mitsuba)."""
    from .psf import compute

    return compute(*args, **kwargs)


# this stage adds its PSF method to the registry of the lower stage (which imports nothing from here)
register_method(PSFMethod("render", _render_psfs, (RAYS,), "the entrance-grid rays traced through the Mitsuba "
                                                            "scene's lens meshes, binned per pixel"))
