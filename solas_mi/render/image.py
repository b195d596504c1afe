"""An input image through the lens geometry: the lens's scene (`scene`) written to a temporary
directory with the image as its object, loaded (`mitsuba`) and rendered (`loop`)."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..imageio import image_channels, read_image, write_exr
from ..optics.camera import Camera, camera_for, film_pitch_um
from ..optics.paraxial import paraxial
from . import response as responses
from .loop import Render, render
from .mitsuba import load_scene, variant_for
from .scene import resolve_rings, write_scene
from .spec import RenderSpec
from .user_scene import unit_f_number

SCENE_PREFIX = "solas-scene-"  # + the process id: $TMPDIR/solas-scene-PID-XXXXXXXX, one per image render


def remove_stale_scenes() -> int:
    """Remove the temporary scene folders that renders killed outright (SIGKILL, out of memory) left in
    $TMPDIR: those of processes that no longer run. The number removed."""
    removed = 0
    for folder in Path(tempfile.gettempdir()).glob(f"{SCENE_PREFIX}*-*"):
        pid = folder.name[len(SCENE_PREFIX) :].split("-", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid() or not folder.is_dir() or folder.is_symlink():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(folder, ignore_errors=True)
            removed += 1
        except OSError:  # alive, another user's
            pass
    return removed


def fisheye_camera(lens, sensor: tuple[int, int], fov_deg: float | None, pitch_um: float | None) -> Camera:
    """The sensor of a lens of polar fields: (rows, columns) pixels of `pitch_um` µm (default: the
    width spans the lens's [image] diameter); the input spans ±fov_deg (default: the lens's field)."""
    rows, cols = sensor
    if pitch_um is None:
        pitch_um = film_pitch_um(lens, cols)
    fov = lens.field_deg if fov_deg is None else float(fov_deg)
    if not (0.0 < pitch_um < 1e4) or not (0.0 < fov < 180.0):
        raise SolasError(f"pixel pitch {pitch_um!r} um must be in (0, 1e4) and fov {fov!r} deg in (0, 180)")
    return Camera(cols, rows, float(pitch_um), paraxial(lens).efl_mm, fov, lens.primary_wavelength, "sensor")


def image_sensor(lens, spec: RenderSpec) -> Camera:
    """The sensor an image is rendered onto (`spec`'s sensor, pitch and field of view)."""
    return (
        camera_for(lens, spec.sensor, spec.fov_deg, spec.pitch_um)
        if lens.field_type.pinhole
        else fisheye_camera(lens, spec.sensor, spec.fov_deg, spec.pitch_um)
    )


def image_camera(lens, camera: Camera, response, model: str | None) -> dict:
    """The camera a render of an image records (`optics.calibration.describe_camera`): `lens` at its file's
    image plane, the sensor `camera` (`image_sensor`) and `model` fitted to the lens's chief-ray mapping over it
    at the `response`'s one wavelength (mono, lines of one), else the lens's primary."""
    from ..optics.calibration import Sensor, describe_camera

    return describe_camera(
        lens,
        Sensor(camera.width, camera.height, camera.pitch_um),
        model,
        wavelength_nm=float(response.single_wavelength or lens.primary_wavelength),
    )


def image_sensor_key(lens, spec: RenderSpec) -> tuple[str, Camera, responses.Response]:
    """An image item's sensor (`image_sensor`) and response, and their name in the manifest's
    `cameras`: lens, size, pitch and the wavelength its camera block is fitted at."""
    camera, response = image_sensor(lens, spec), responses.parse(spec.response, lens.wavelengths_nm)
    wavelength = response.single_wavelength or lens.primary_wavelength
    return f"{lens.name} {camera.width}x{camera.height} {camera.pitch_um:.6g}um {wavelength:g}nm", camera, response


# long: the public API's numpydoc docstring is half of it
def render_image(
    lens,
    image: str | np.ndarray,
    spec: RenderSpec | None = None,
    *,
    progress=None,
    calibration_model: str | None = None,
    camera_block: dict | None = None,
    **settings,
) -> Render:
    """Render an input image through a lens in Mitsuba, the lens as geometry.

    The image's width spans ±``fov_deg`` degrees and, unless ``pitch_um`` is given, so does the
    sensor's (`solas_mi.optics.camera`). For a lens of polar fields (a fisheye) the image is an
    environment image spanning ±``fov_deg`` in its ``mapping`` (`plugins/image_object.py`), the sensor is
    just pixels and the distortion is the lens's own ([rendering through the lens](../details/render.md)).

    Parameters
    ----------
    lens : Lens
        The lens.
    image : str or numpy.ndarray
        An image file (PNG/JPEG: sRGB; EXR: linear), or a linear H×W[×3] array.
    spec : RenderSpec, optional
        The render's settings (`render.spec.RenderSpec`: sensor, pitch, field, response, boundary,
        Fresnel, rings, mapping, spp, variant, seed); default: its defaults.
    progress : callable, optional
        Called as ``progress(done, total)`` with the samples per pixel done.
    calibration_model : str, optional
        The camera model (`optics.calibration.MODELS`) whose fit to the lens over the sensor the metadata
        records as "camera" (`image_camera`), fitted before the render (a model that cannot hold the field is
        refused before any work); default: no camera block.
    camera_block : dict, optional
        The metadata's "camera" already fitted (a batch's, once per sensor), in place of fitting one here.
    **settings
        Fields of `RenderSpec` to change, e.g. ``sensor=(rows, columns)``, ``spp=16``.

    Returns
    -------
    Render
        The image (irradiance in units of the ideal camera's) and its metadata.

    Raises
    ------
    SolasError
        For a focus distance or labels (a scene file's settings), a rectilinear image spanning ±90° or
        more, a response the lens or variant cannot take, or an image that cannot be read.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.render import render_image
    >>> result = render_image(Lens.load("solas-doublet"), "scenes/images/rocket.png", sensor=(24, 32), spp=4)
    >>> result.image.shape, result.channels
    ((24, 32, 3), ('R', 'G', 'B'))
    >>> result.write("rocket.exr")
    'rocket.png'
    """
    spec = (spec or RenderSpec()).replace(**settings)
    if spec.focus_distance is not None:
        raise SolasError(
            "a focus distance sets the lens camera of a scene file; an image lies on the lens's object "
            "plane: render it without one"
        )
    if spec.labels:
        raise SolasError(
            f"labels ({spec.labels}) are traced through the lens camera of a scene file; an image has "
            "no scene to label: render it without them"
        )
    camera = image_sensor(lens, spec)
    if spec.mapping == "rectilinear" and camera.fov_deg >= 90.0:  # tan θ changes sign: the input would mirror
        raise SolasError(
            f"a rectilinear input spans less than ±90 deg and this one would span ±{camera.fov_deg:g} deg; "
            "give --fov-deg below 90 or a mapping that reaches past 90 deg (equidistant, equisolid, "
            "equirectangular)"
        )
    # the user's mistakes, named here rather than inside the scene's plugins
    parsed = responses.parse(spec.response, lens.wavelengths_nm)
    responses.check_lens(parsed, lens)
    variant = variant_for(parsed, spec.variant)
    if not isinstance(image, np.ndarray):
        read_image(image)
    remove_stale_scenes()
    with tempfile.TemporaryDirectory(prefix=f"{SCENE_PREFIX}{os.getpid()}-") as tmp:
        if isinstance(image, np.ndarray):
            path = str(Path(tmp) / "object.exr")
            write_exr(path, image_channels(np.asarray(image, dtype=np.float32)))
            image = path
        xml = write_scene(lens, tmp, str(Path(image).resolve()), camera, spec)
        if camera_block is None and calibration_model is not None:  # after the scene's own checks, before the render
            camera_block = image_camera(lens, camera, parsed, calibration_model)
        scene = load_scene(xml, variant)
        result = render(scene, spec.spp, seed=spec.seed, progress=progress)
    result.meta.update(camera.meta(), f_number=unit_f_number(scene.sensors()[0]))
    result.meta.update(
        {
            "lens": lens.name,
            "lens_hash": lens.hash,
            "boundary": spec.boundary,
            "fresnel": spec.fresnel,
            "mapping": spec.mapping,
            "cap_rings": resolve_rings(lens, spec.rings),
            "render_spec": spec.as_dict(),
            **({"camera": camera_block} if camera_block is not None else {}),
        }
    )
    return result
