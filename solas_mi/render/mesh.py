"""The lens's surfaces as triangle meshes for the Mitsuba scene (`render.scene`): caps (sphere or even
asphere) with vertex normals, absorbing annuli and the barrel, closed where they meet (shared rings,
no T-junctions, absorbers of two crossing layers), written as binary PLY; and how finely to mesh a
lens: the blur its caps add (`mesh_blur_um`) and the ring count that keeps it under a share of the
Airy radius (`mesh_rings`). Lengths in mm.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..imageio import atomic_path
from ..optics.lens import Lens
from ..optics.sag import sag as asphere_sag
from ..optics.sag import sag_slope
from .spec import AUTO_MIN_RINGS, MAX_RINGS


def cap_mesh(
    radius: float,
    vertex_z: float,
    semi_diameter: float,
    rings: int,
    conic: float = 0.0,
    aspheric: tuple[float, ...] = (),
    qbfs: tuple[float, ...] = (),
    norm_radius: float = 1.0,
):
    """A spherical cap (flat disk if radius is 0), or the asphere of `conic`, `aspheric` and Forbes
    `qbfs` terms over `norm_radius` (the lens file's sag, `optics.sag.sag`): vertices (n, 3), unit normals (n, 3) facing −z,
    faces (m, 3) wound so that their geometric normals face −z too. `rings` rings of 4·rings
    segments (`rim_phi`); ring radii are uniform in r. Its last 4·rings vertices are the rim."""
    segments = 4 * rings
    r = semi_diameter * np.arange(1, rings + 1) / rings
    phi = rim_phi(rings)
    rr, pp = np.meshgrid(r, phi, indexing="ij")
    x = np.concatenate([[0.0], (rr * np.cos(pp)).ravel()])
    y = np.concatenate([[0.0], (rr * np.sin(pp)).ravel()])
    if conic != 0.0 or any(aspheric) or any(qbfs):
        c, rho2 = (1.0 / radius if radius else 0.0), x * x + y * y
        z = vertex_z + asphere_sag(rho2, c, conic, aspheric, qbfs=qbfs, norm_radius=norm_radius)
        slope = 2.0 * sag_slope(rho2, c, conic, aspheric, qbfs=qbfs, norm_radius=norm_radius)
        normals = np.stack([slope * x, slope * y, -np.ones_like(x)], axis=-1)
        normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    elif radius == 0.0:
        z = np.full_like(x, vertex_z)
        normals = np.tile([0.0, 0.0, -1.0], (len(x), 1))
    else:
        c = 1.0 / radius
        rho2 = x * x + y * y
        sag = c * rho2 / (1.0 + np.sqrt(1.0 - c * c * rho2))
        z = vertex_z + sag
        normals = np.stack([x, y, z - (vertex_z + radius)], axis=-1) / radius
    faces = []
    ring = lambda i, j: 1 + i * segments + (j % segments)  # noqa: E731
    j = np.arange(segments)
    faces.append(np.stack([np.zeros(segments, int), ring(0, j), ring(0, j + 1)], axis=-1))
    for i in range(rings - 1):
        a, b, c2, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
        faces += [np.stack([a, c2, d], axis=-1), np.stack([a, d, b], axis=-1)]
    vertices = np.stack([x, y, z], axis=-1)
    return vertices, normals, _wind(vertices, normals, np.concatenate(faces))


MESH_BLUR_OF_AIRY = 0.25  # automatic ring counts keep the caps' added RMS blur below this share of the Airy radius
_REFERENCE_RINGS = 16  # the ring count the blur model evaluates the meshes at (the blur goes as 1/rings²)


def _cap_errors(s, zv: float, rings: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Where a ray meets surface `s`'s cap mesh of `rings` rings, against the surface itself, at a
    centroid and three edge-side points of every triangle: the radius r (mm), the mesh's depth error δz
    (mm), the angle (rad) between the shading normal (vertex normals interpolated, as Mitsuba does) and
    the surface's normal there, and the triangle's area (mm², the weight)."""
    v, n, f = cap_mesh(s.radius, zv, s.semi_diameter, rings, s.conic, s.aspheric, s.qbfs, s.norm_radius)
    out = []
    for lam in ((1 / 3, 1 / 3, 1 / 3), (0.5, 0.25, 0.25), (0.25, 0.5, 0.25), (0.25, 0.25, 0.5)):
        p = sum(w * v[f[:, i]] for i, w in enumerate(lam))
        m = sum(w * n[f[:, i]] for i, w in enumerate(lam))
        m /= np.linalg.norm(m, axis=-1, keepdims=True)
        rho2 = p[:, 0] ** 2 + p[:, 1] ** 2
        slope = 2.0 * sag_slope(rho2, **s.shape)
        true = np.stack([slope * p[:, 0], slope * p[:, 1], -np.ones_like(rho2)], axis=-1)
        true /= np.linalg.norm(true, axis=-1, keepdims=True)
        dz = p[:, 2] - zv - asphere_sag(rho2, **s.shape)
        out.append((np.sqrt(rho2), dz, np.linalg.norm(np.cross(m, true), axis=-1)))
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=-1)
    r, dz, dn = (np.concatenate([o[i] for o in out]) for i in range(3))
    return r, dz, dn, np.tile(area, 4)


def _surface_blur_mm2(
    s, zv: float, n1: float, n2: float, beam: float, slope_per_mm: float, lever_shift: float, lever_tilt: float
) -> float:
    """Mean squared image offset (mm²) that surface `s`'s cap mesh (at vertex z `zv`, between indices
    n1 and n2) adds to the rays of an on-axis bundle of radius `beam` there, whose slope before it is
    `slope_per_mm` per mm of height; `lever_shift` and `lever_tilt` are the paraxial transfers of a
    sideways shift and of a tilt from the surface's vertex plane to the image (`mesh_blur_um`)."""
    r, dz, dn, w = _cap_errors(s, zv, _REFERENCE_RINGS)
    w = np.where(r <= beam, w, 0.0)
    normal = np.arctan(2.0 * r * sag_slope(r * r, **s.shape))  # its tilt, radially
    before = np.arctan(slope_per_mm * r)
    i = before + normal
    sin_out = n1 * np.sin(i) / n2
    passes = np.abs(sin_out) < 1.0  # past the critical angle no ray goes on
    i_out = np.arcsin(np.clip(sin_out, -1.0, 1.0))
    after = i_out - normal
    tilt = np.where(passes, 1.0 - n1 * np.cos(i) / (n2 * np.cos(i_out)), 0.0) * dn  # ray tilt per normal error
    shift = np.where(passes, np.tan(after) - np.tan(before), 0.0) * dz  # sideways, from the depth error
    sag = s.sag(r)  # the ray leaves the cap at the sag, not the vertex plane
    e = lever_shift * shift + (lever_tilt - sag * lever_shift) * tilt / np.cos(after) ** 2
    return float(np.sum(w * e * e) / np.sum(w))


def mesh_blur_um(lens: Lens, rings: int) -> float:
    """The RMS blur (µm) the cap meshes of `rings` rings add to an on-axis point image, to first order:
    at each refracting surface a ray meets the flat triangle δz off the surface, which shifts it sideways
    by δz·(tan u' − tan u) (its slope change there), and refracts on the interpolated normal, δθ off the
    surface's, which tilts it by δθ·(1 − n·cos i / (n'·cos i')); the paraxial transfer from the surface to
    the image plane turns shift and tilt into image offsets. The bundle's slopes are paraxial, its
    incidence and refraction angles real; surfaces add in quadrature, each averaged over the bundle's
    footprint on its cap (the object taken at infinity).
    Both errors go as the triangles' size squared, so the blur as 1/rings²: it is evaluated at 16 rings
    and scaled."""
    from ..optics.paraxial import ynu_trace

    wl = lens.primary_wavelength
    n, z, last = lens.indices(wl), lens.vertex_z, len(lens.surfaces) - 1
    ya, ua = ynu_trace(lens, wl, 1.0, 0.0)  # the on-axis bundle: its slope per unit height at each surface
    u_before = np.concatenate([[0.0], ua[:-1]])
    beam = np.abs(ya) * lens.surfaces[lens.stop_index].semi_diameter / abs(ya[lens.stop_index])  # its radius

    def to_image(k: int, y: float, u: float) -> float:
        if k < last:
            yk, uk = ynu_trace(lens, wl, y + u * (z[k + 1] - z[k]), u, start=k + 1)
            y, u = yk[last], uk[last]
        return y + u * (lens.image_z - z[last])

    total = sum(
        _surface_blur_mm2(
            s,
            float(z[k]),
            n[k],
            n[k + 1],
            beam[k],
            u_before[k] / ya[k] if ya[k] else 0.0,
            to_image(k, 1.0, 0.0),
            to_image(k, 0.0, 1.0),
        )
        for k, s in enumerate(lens.surfaces)
        if n[k + 1] != n[k]
    )
    return 1e3 * math.sqrt(total) * (_REFERENCE_RINGS / rings) ** 2


def mesh_rings(lens: Lens) -> int:
    """The ring count that keeps `mesh_blur_um` below MESH_BLUR_OF_AIRY of the Airy radius 1.22·λ·N
    (the lens's shortest wavelength, its working f-number): at least AUTO_MIN_RINGS (the count before it
    was chosen), at most MAX_RINGS. A lens without a paraxial image (afocal) keeps AUTO_MIN_RINGS."""
    from ..errors import SolasError
    from ..optics.paraxial import paraxial

    try:
        airy_um = 1.22 * min(lens.wavelengths_nm) * 1e-3 * paraxial(lens).working_f_number
        blur = mesh_blur_um(lens, _REFERENCE_RINGS)
    except SolasError:
        return AUTO_MIN_RINGS
    need = _REFERENCE_RINGS * math.sqrt(blur / (MESH_BLUR_OF_AIRY * airy_um)) if airy_um > 0 else math.inf
    return int(min(MAX_RINGS, max(AUTO_MIN_RINGS, math.ceil(need)))) if math.isfinite(need) else AUTO_MIN_RINGS


def rim_phi(rings: int) -> np.ndarray:
    """Azimuths of the 4·rings rim vertices of a cap (and of the annuli and barrel that meet it), so
    that no spoke lies on an axis or a diagonal, where a regular grid of rays would run along the shared
    edges: half a segment off them for an even count, a quarter for an odd one (whose diagonals fall
    on a spoke half a segment off)."""
    segments = 4 * rings
    return 2.0 * math.pi * (np.arange(segments) + (0.5 if rings % 2 == 0 else 0.25)) / segments


def circle(radius: float, z: float, phi: np.ndarray) -> np.ndarray:
    """Vertices (n, 3) on the circle of `radius` at z, at azimuths `phi`: every mesh computes a shared
    ring here, so two meshes meeting on it hold bit-identical vertices."""
    return np.stack([radius * np.cos(phi), radius * np.sin(phi), np.full(len(phi), z)], axis=-1)


def annulus_mesh(inner: np.ndarray, outer: np.ndarray):
    """A ring between the closed polygons `inner` and `outer` ((n, 3) each, vertex j of one facing
    vertex j of the other), normals −z. Given the cap's own rim vertices and the barrel's ring, it
    shares their edges: no ray passes between the meshes."""
    n = len(inner)
    j = np.arange(n)
    k = (j + 1) % n
    faces = np.concatenate([np.stack([j, n + j, n + k], -1), np.stack([j, n + k, k], -1)])
    vertices = np.concatenate([inner, outer])
    normals = np.tile([0.0, 0.0, -1.0], (len(vertices), 1))
    return vertices, normals, _wind(vertices, normals, faces)


def tube_mesh(radius: float, z_levels, phi: np.ndarray):
    """An open cylinder of `radius` through the sorted `z_levels` (mm), a vertex ring at each (where the
    annuli meet it, so none ends on an edge's middle), normals facing the axis."""
    n = len(phi)
    vertices = np.concatenate([circle(radius, z, phi) for z in z_levels])
    normals = -vertices * np.array([1.0, 1.0, 0.0]) / radius
    j = np.arange(n)
    k = (j + 1) % n
    faces = np.concatenate(
        [
            np.concatenate([np.stack([a + j, a + n + j, a + n + k], -1), np.stack([a + j, a + n + k, a + k], -1)])
            for a in range(0, n * (len(z_levels) - 1), n)
        ]
    )
    return vertices, normals, _wind(vertices, normals, faces)


def joined(*meshes):
    """One mesh of several (vertices, normals, faces) meshes."""
    offsets = np.cumsum([0] + [len(m[0]) for m in meshes[:-1]])
    return (
        np.concatenate([m[0] for m in meshes]),
        np.concatenate([m[1] for m in meshes]),
        np.concatenate([m[2] + o for m, o in zip(meshes, offsets)]).astype(np.int32),
    )


def absorber_ring(rim: np.ndarray, radius: float, outer: float, z: float, phi: np.ndarray):
    """The absorbing annulus of an aperture of `radius` at z out to the barrel's `outer` radius, two
    layers: one between `rim` (the cap's own rim vertices, or the stop's circle) and the barrel's ring,
    sharing their edges; and one turned half a segment, from the polygon circumscribing the aperture's
    circle, so it covers no glass. Mitsuba's CPU ray tracer (Embree, not in its robust mode) lets about one
    ray in a million through a shared edge; the two layers' edges cross instead of coinciding, so a ray
    let through one layer's edge meets the other's face."""
    turn = phi + math.pi / len(phi)
    return joined(
        annulus_mesh(rim, circle(outer, z, phi)),
        annulus_mesh(circle(radius / math.cos(math.pi / len(phi)), z, turn), circle(outer, z, turn)),
    )


def _wind(vertices: np.ndarray, normals: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Faces reordered where needed so each geometric normal agrees with its vertex normals."""
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    geo = np.cross(v1 - v0, v2 - v0)
    flip = np.einsum("ij,ij->i", geo, normals[faces].sum(axis=1)) < 0
    out = faces.copy()
    out[flip] = out[flip][:, ::-1]
    return out.astype(np.int32)


def write_ply(path: str | os.PathLike, vertices: np.ndarray, normals: np.ndarray, faces: np.ndarray) -> None:
    """Binary little-endian PLY with vertex normals (what Mitsuba's `ply` shape reads)."""
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    vert = np.concatenate([vertices, normals], axis=1).astype("<f4")
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"], face["i"] = 3, faces
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vert.tobytes())
        f.write(face.tobytes())
