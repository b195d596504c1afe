"""A lens as Mitsuba geometry (the meshes: `render.mesh`): every refracting surface a triangle-mesh cap (sphere or even asphere) with vertex
normals carrying its two glasses (`sellmeier_dielectric`), every clear aperture and the stop an
absorbing annulus, a barrel closing the sides, the `lens_sensor` on the image plane and the input
image as `image_object`. A coated surface's cap is a `coated_dielectric`, the same glasses with its coating.

Coordinates are the lens file's (surface 1's vertex at the origin, +z toward the image, mm). Cap
normals face the object (−z); the glass after the surface is the dielectric's interior.
Meshes are written as binary PLY beside the scene XML, so a scene directory is self-contained.
"""
from __future__ import annotations

import itertools
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..imageio import atomic_path, write_text
from ..optics import lens_checks, thermal, virtual_object
from ..optics.camera import Camera, camera_for
from ..optics.coating import Coating
from ..optics.lens import Lens
from ..outputs import inside, safe_name
from ..psf.registry import METHODS
from . import response as responses
from .mesh import absorber_ring, cap_mesh, circle, joined, mesh_rings, rim_phi, tube_mesh, write_ply
from .spec import RenderSpec, check_rings

FLOAT32_REACH_MM = 2.0 ** 24 * 1e-3  # float32 holds a point this far (mm) from the origin to 1 µm
SPAWN_OFFSET_MM = 1e-4  # a continued ray starts this far (mm) along its own direction (`loop.continue_ray`)
MIN_GAP_MM = 10 * SPAWN_OFFSET_MM  # closest two refracting surfaces of the mesh scene may come


@dataclass(frozen=True)
class Part:
    """One shape of the lens scene: a mesh file name, its two glasses (None: an absorber), the lens's
    temperature and pressure where not 20 °C and 101.325 kPa (`optics.thermal.metadata`) and the surface's
    coating (None: bare glass)."""

    name: str
    mesh: tuple[np.ndarray, np.ndarray, np.ndarray]
    ext_glass: str | None = None
    int_glass: str | None = None
    environment: tuple[tuple[str, float], ...] = ()
    coating: Coating | None = None

    def bsdf(self, fresnel: str) -> dict:
        """The cap's BSDF as `mi.load_dict` takes it, its environment left out: `sellmeier_dielectric`
        between its glasses with `fresnel`, or `coated_dielectric` with its coating's lens-file table as JSON."""
        bsdf = {"type": "sellmeier_dielectric", "ext_glass": self.ext_glass, "int_glass": self.int_glass,
                "fresnel": fresnel}
        if self.coating is not None:
            bsdf.update(type="coated_dielectric", coating=json.dumps(self.coating.table()))
        return bsdf


def check_gaps(lens: Lens) -> None:
    """Refuse a lens whose neighbouring refracting surfaces come closer, anywhere inside their clear
    apertures, than MIN_GAP_MM: a ray continued SPAWN_OFFSET_MM past one surface would skip the next."""
    caps = [k for k, s in enumerate(lens.surfaces)
            if s.glass != (lens.surfaces[k - 1].glass if k else lens.object_glass)]
    for a, b in itertools.pairwise(caps):
        sa, sb = lens.surfaces[a], lens.surfaces[b]
        r = np.linspace(0.0, min(sa.semi_diameter, sb.semi_diameter), 257)
        gap = lens.vertex_z[b] - lens.vertex_z[a] + sb.sag(r) - sa.sag(r)
        if gap.min() < MIN_GAP_MM:
            i = int(np.argmin(gap))
            raise SolasError(f"surfaces {a + 1} and {b + 1} of lens {lens.name} are {gap[i]:.3g} mm apart at r = "
                             f"{r[i]:.3g} mm: the mesh scene continues each ray {SPAWN_OFFSET_MM:g} mm past a surface, "
                             f"so its refracting surfaces must be at least {MIN_GAP_MM:g} mm apart (the tracer's psf, "
                             "psf-grid and the lens_camera take this lens as it is)")


def resolve_rings(lens: Lens, rings: int | None) -> int:
    """`rings` checked, or for None the count `mesh_rings` chooses for `lens`."""
    return mesh_rings(lens) if rings is None else check_rings(rings)


def _trace_instead() -> str:
    """What traces a lens that solid geometry cannot hold: the lens camera, or a PSF method that traces the
    lens itself (every one but those that build it as meshes)."""
    tracers = [name for name, method in METHODS.items() if not method.extra.get("meshes")]
    return (f"the lens camera (a scene file's sensor, `render.user_scene`) or a tracer PSF method "
            f"({', '.join(tracers)})")


def _check_buildable(lens: Lens, image_radius: float) -> None:
    """SolasError where `lens` has no solid geometry: an ideal thin lens, a virtual object, an iris (the
    meshes have a round stop), overlapping surfaces, or a part (a vertex, the image plane out to `image_radius`) farther from surface 1 than
    float32 places to 1 µm (a film 1e7 mm away rendered the wrong colours, one at 1e12 mm black); each
    message names what traces it instead."""
    reach = max(abs(float(lens.image_z)), float(np.abs(lens.vertex_z).max()), image_radius)
    if reach > FLOAT32_REACH_MM:
        raise SolasError(f"lens {lens.name} reaches {reach:g} mm from surface 1 (its image plane at {lens.image_z:g} "
                         f"mm, the film out to {image_radius:g} mm): the mesh scene's float32 geometry holds a point "
                         f"to 1 µm within {FLOAT32_REACH_MM:g} mm only; trace it instead: {_trace_instead()}")
    ideal = next((k for k, s in enumerate(lens.surfaces, start=1) if s.ideal), None)
    if ideal is not None:
        raise SolasError(f"surface {ideal} of lens {lens.name} is an ideal thin lens (focal_length), which has no glass "
                         f"to build as Mitsuba geometry; trace it instead: {_trace_instead()}")
    virtual_object.check_real(lens, "the mesh scene")
    lens_checks.refuse_as_built(lens, "the mesh scene")
    iris = next((k for k, s in enumerate(lens.surfaces, start=1) if s.blades), None)
    if iris is not None:  # the meshes have a round stop: not what the lens states
        raise SolasError(f"lens {lens.name}: surface {iris}'s iris (blades) has no Mitsuba geometry here (a round "
                         f"stop); trace it instead: {_trace_instead()}")
    if lens.overlaps:
        raise SolasError(f"lens {lens.name} cannot be built as Mitsuba geometry: {'; '.join(lens.overlaps)}. Trace it "
                         f"instead: {_trace_instead()}")


def lens_parts(lens: Lens, rings: int | None = None, image_radius: float = 0.0) -> list[Part]:
    """Caps for refracting surfaces, absorbing annuli around every clear aperture (and the stop), and
    a barrel closing the sides from the first aperture to the image plane. A lens of polar fields (a
    fisheye) takes light from 90° and beyond, which reaches its front element from the side and from
    behind its vertex: that element stands proud of the mount, with no annulus and the barrel starting
    at the second surface's rim. `rings` per cap (None: `mesh_rings`). The barrel's radius is twice the
    largest clear aperture plus 10 mm, or more to hold the image plane out to `image_radius` mm (the
    sensor's corners, a PSF's window): a barrel narrower than the image cut off the light that arrives
    there (Cooke triplet at 32°: its light lands 31 mm off axis, outside a 30 mm barrel)."""
    _check_buildable(lens, image_radius)
    rings = resolve_rings(lens, rings)
    check_gaps(lens)
    parts = []
    outer = max(2.0 * max(s.semi_diameter for s in lens.surfaces) + 10.0, 1.05 * image_radius + 1.0)
    phi = rim_phi(rings)
    before = lens.object_glass
    before_name = "AIR" if lens.object_glass.kind == "air" else lens.object_glass.name
    rim_z, ring_z = [], []
    for k, (s, zv) in enumerate(zip(lens.surfaces, lens.vertex_z), start=1):
        zr = zv + float(s.sag(s.semi_diameter))
        rim_z.append(zr)
        rim = circle(s.semi_diameter, zr, phi)
        if s.glass != before:
            cap = cap_mesh(s.radius, zv, s.semi_diameter, rings, s.conic, s.aspheric, s.qbfs, s.norm_radius)
            rim = cap[0][-len(phi):]
            parts.append(Part(f"surface{k}", cap, before_name, s.material, tuple(thermal.metadata(lens).items()),
                              s.coating))
        if not (k == 1 and lens.field_type.sideways):
            parts.append(Part(f"aperture{k}", absorber_ring(rim, s.semi_diameter, outer, zr, phi)))
            ring_z.append(zr)
        before, before_name = s.glass, s.material
    start = rim_z[1] if lens.field_type.sideways and len(rim_z) > 1 else min(rim_z) - 1.0
    levels = sorted({start, lens.image_z, *(z for z in ring_z if z > start)})
    turn = phi + math.pi / len(phi)  # a second, circumscribing layer turned half a segment (`absorber_ring`)
    parts.append(Part("barrel", joined(tube_mesh(outer, levels, phi),
                                       tube_mesh(outer / math.cos(math.pi / len(phi)), levels, turn))))
    return parts


def path_depth(lens: Lens, ghosts: bool) -> int:
    """Interactions a camera path through `lens` needs: one per refracting surface and the escape; with
    sampled Fresnel reflections (`ghosts`), room for a ghost (two reflections and the way back)."""
    refracting = sum(1 for k, s in enumerate(lens.surfaces)
                     if s.glass != (lens.surfaces[k - 1].glass if k else lens.object_glass))
    return 3 * refracting + 2 if ghosts else refracting + 2


def xml_attr(text) -> str:
    """`text` escaped for an XML attribute value in double quotes (a path or name is user data: a quote,
    "<", "&" or a line break in it cannot end the value or add an element)."""
    from xml.sax.saxutils import escape

    return escape(str(text), {'"': "&quot;", "\n": "&#10;", "\r": "&#13;", "\t": "&#9;"})


def _shapes_xml(parts: list[Part], mono: str) -> str:
    """The <shape> elements of `parts`: its BSDF (`Part.bsdf`: `sellmeier_dielectric` between its two glasses,
    `coated_dielectric` for a coated surface; with the mono variants' `wavelength` element `mono`, or ""), or
    the absorber."""
    shapes = []
    for p in parts:
        if p.int_glass is None:
            bsdf = '<ref id="absorber"/>'
        else:
            where = "".join(f'<float name="{key}" value="{value!r}"/>' for key, value in p.environment)
            params = p.bsdf("$fresnel")
            bsdf = (f'<bsdf type="{params.pop("type")}">'
                    + "".join(f'<string name="{key}" value="{xml_attr(value)}"/>' for key, value in params.items())
                    + f'{where}{mono}</bsdf>')
        shapes.append(f'    <shape type="ply" id="{p.name}">\n        <string name="filename" value="meshes/{p.name}.ply"/>\n'
                      f'        {bsdf}\n    </shape>')
    return "\n".join(shapes)


def _defaults_xml(camera: Camera, spec: RenderSpec, image: str, max_depth: int, wavelength_nm: float | None) -> str:
    """The <default> lines at the top of the scene: every number a user may want to change."""
    wavelength_default = "" if wavelength_nm is None else \
        f'\n    <default name="wavelength" value="{wavelength_nm!r}"/>  <!-- nm: the response\'s, for mono variants -->'
    return f"""    <default name="spp" value="{spec.spp}"/>
    <default name="width" value="{camera.width}"/>
    <default name="height" value="{camera.height}"/>
    <default name="pitch_um" value="{camera.pitch_um!r}"/>
    <default name="response" value="{xml_attr(spec.response)}"/>{wavelength_default}
    <default name="spectrum" value="{responses.object_spectrum(spec.response)}"/>  <!-- the image's RGB as a spectrum -->
    <default name="image" value="{xml_attr(image)}"/>
    <default name="fov_deg" value="{camera.fov_deg!r}"/>
    <default name="boundary" value="{spec.boundary}"/>
    <default name="mapping" value="{spec.mapping}"/>
    <default name="fresnel" value="{spec.fresnel}"/>
    <default name="max_depth" value="{max_depth}"/>"""


def scene_xml(lens_file: str, parts: list[Part], camera: Camera, image: str, spec: RenderSpec, max_depth: int,
              wavelength_nm: float | None = None) -> str:
    """Mitsuba 3 scene XML; meshes are referenced as meshes/<part>.ply beside it. Every number a user
    may want to change is a <default> at the top (`spec`'s spp, response, boundary, mapping, fresnel).
    `wavelength_nm`, the response's one wavelength (nm; None: it has more), is the glasses' and the
    object's `wavelength` for the mono variants.
    The integrator is Mitsuba's `path` with `max_depth` interactions (`mi.render`); solas-mi's loop reads only the sensor, the object, the shapes and the
    sampler's count. The sampler is `independent`, the one that takes any count as given: `multijitter`
    has 2.4× less noise in 40-px blocks under `mi.render` but rounds the count (128 → 132) and kills the
    process with a floating-point exception on a count of 0."""
    mono = '' if wavelength_nm is None else '<float name="wavelength" value="$wavelength"/>'
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- solas-mi lens scene: render with `solas-mi render THIS.xml -o out.exr` (lengths in mm, pitch in um), or in
     Python: `mi = solas_mi.mitsuba(); mi.render(mi.load_file("THIS.xml"))` (Mitsuba's path integrator below).
     Pixel values are image irradiance in units of the ideal camera's: an ideal lossless lens returns the image. -->
<scene version="3.0.0">
{_defaults_xml(camera, spec, image, max_depth, wavelength_nm)}

    <integrator type="path">
        <integer name="max_depth" value="$max_depth"/>
    </integrator>

    <sensor type="lens_sensor" id="sensor">
        <string name="lens" value="{xml_attr(lens_file)}"/>
        <float name="pitch_um" value="$pitch_um"/>
        <float name="fov_deg" value="$fov_deg"/>
        <string name="response" value="$response"/>
        <film type="hdrfilm">
            <integer name="width" value="$width"/>
            <integer name="height" value="$height"/>
            <rfilter type="box"/>
        </film>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
    </sensor>

    <emitter type="image_object" id="object">
        <string name="filename" value="$image"/>
        <float name="fov_deg" value="$fov_deg"/>
        <string name="boundary" value="$boundary"/>
        <string name="mapping" value="$mapping"/>
        <string name="spectrum" value="$spectrum"/>{mono and chr(10) + 8 * ' ' + mono}
    </emitter>

    <bsdf type="diffuse" id="absorber">
        <rgb name="reflectance" value="0"/>
    </bsdf>

{_shapes_xml(parts, mono)}
</scene>
"""


_READS_AS: dict[tuple[str, str], Lens] = {}  # (file, SHA-256 of its bytes) → the lens it reads as


def _reads_as(source: Path) -> Lens:
    """The lens that the file `source` reads as, parsed once per content of the file (a render's
    caller has loaded it already; the scene's sensor parses its own copy)."""
    import hashlib

    from ..userfiles import read_bytes

    key = (str(source.resolve()), hashlib.sha256(read_bytes(source, "lens file")).hexdigest())
    if key not in _READS_AS:
        _READS_AS[key] = Lens.load(source)
    return _READS_AS[key]


def lens_file(lens: Lens, folder: str | os.PathLike | None = None) -> Path:
    """A file that holds exactly `lens`, for a scene's sensor to load: its source file when that still
    reads as this very lens (every field equal), else the lens written as TOML into
    `folder` (a lens changed in memory — refocused, edited with `dataclasses.replace` — or built with
    `Lens.from_dict`). Without a folder such a lens is a SolasError, never its source file's lens in its place."""
    source = Path(lens.source) if lens.source else None
    if source is not None and source.is_file() and _reads_as(source) == lens:
        return source
    if folder is None:
        raise SolasError(f"lens {lens.name} differs from its file {lens.source or '(none)'}; save it "
                         "(Lens.save) and load it from there to render it")
    path = inside(folder, f"{safe_name(source.stem if source is not None else 'lens', 'lens')}_{lens.hash}.toml")
    lens.save(path)
    if Lens.load(path).hash != lens.hash:  # the TOML writer keeps every number: a miss is a bug, not noise
        raise SolasError(f"lens {lens.name} did not survive writing to {path}")
    return path


# long: the public API's numpydoc docstring is half of it
def write_scene(lens: Lens, out_dir: str | os.PathLike, image: str, camera: Camera | None = None,
                spec: RenderSpec | None = None, *, name: str = "scene.xml", **settings) -> Path:
    """Write a lens's Mitsuba scene into a folder, self-contained: the XML, the cap meshes and the lens file.

    Render it with ``solas-mi render``, or `render_scene`. A response of one wavelength is also written as
    the glasses' and the object's ``wavelength`` (mono variants).

    Parameters
    ----------
    lens : Lens
        The lens.
    out_dir : str or PathLike
        The folder: the XML, ``meshes/*.ply`` and the lens file (`lens_file`: a copy of its source, or the
        lens as changed in memory).
    image : str
        The input image the scene's ``image_object`` shows (a path the scene reads).
    camera : Camera, optional
        The sensor and field (`optics.camera.Camera`); default: `optics.camera.camera_for(lens)`.
    spec : RenderSpec, optional
        Rings per cap mesh, spp, response, boundary, Fresnel and the image's ``mapping``; default: its
        defaults.
    name : str, default "scene.xml"
        The XML's name.
    **settings
        Fields of `RenderSpec` to change.

    Returns
    -------
    Path
        The XML.

    Raises
    ------
    SolasError
        For a lens whose surfaces come too close for float32 meshes, a bad setting, or a lens that did
        not survive writing.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.render import write_scene
    >>> xml = write_scene(Lens.load("solas-doublet"), "scene", "rocket.png")
    >>> xml.name, sorted(p.name for p in xml.parent.iterdir())
    ('scene.xml', ['meshes', 'scene.xml', 'solas_doublet.toml'])
    """
    import shutil

    spec = (spec or RenderSpec()).replace(**settings)
    camera = camera or camera_for(lens)
    out = Path(out_dir)
    (out / "meshes").mkdir(parents=True, exist_ok=True)
    corner = math.hypot(np.abs(camera.pixel_x_mm()).max(), np.abs(camera.pixel_y_mm()).max()) + camera.pitch_mm
    parts = lens_parts(lens, spec.rings, corner)
    for p in parts:
        write_ply(out / "meshes" / f"{p.name}.ply", *p.mesh)
    held = lens_file(lens, out)
    if held.parent.resolve() != out.resolve():  # the source file, unchanged: copied beside the scene
        copy = out / held.name
        if not copy.exists() or not copy.samefile(held):
            with atomic_path(copy) as tmp:
                shutil.copyfile(held, tmp)
        held = copy
    # deep enough for ghosts whatever `fresnel` is set to later: a path without them ends sooner anyway
    xml = scene_xml(held.name, parts, camera, image, spec, path_depth(lens, ghosts=True),
                    responses.one_wavelength(spec.response, lens.wavelengths_nm))
    path = out / name
    write_text(path, xml)
    return path
