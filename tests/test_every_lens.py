"""Each stage on lenses with and without symmetry (`every_lens`: two shipped lenses on one axis and the Cooke
triplet as built): the Dr.Jit tracer against the NumPy tracer in local frames, a PSF grid degrading an image,
and the stages that take only a lens on one axis refusing the lens as built by name."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.convolution.methods import degrade
from solas_mi.optics import ghost_paths, local_trace, tracer_local
from solas_mi.optics.exit_pupil import reversed_lens
from solas_mi.optics.lens_checks import as_built
from solas_mi.psf.grid import psf_grid
from solas_mi.render.scene import lens_parts
from solas_mi.render.user_scene import default_pitch_um


def test_the_drjit_tracer_lands_rays_where_the_numpy_tracer_in_local_frames_does(every_lens):
    """9×9 rays over half of surface 1's aperture at three fields in two dimensions: the same rays pass, their
    image points (on the image plane, in its own frame) and optical paths within 1e-9 mm."""
    lens, top = every_lens, every_lens.field_deg
    span = np.linspace(-0.5, 0.5, 9) * lens.surfaces[0].semi_diameter
    px, py = (a.ravel() for a in np.meshgrid(span, span))
    reach = 2.0 * max(s.semi_diameter for s in lens.surfaces) + 10.0
    points, directions = [], []
    for fx, fy in ((0.0, 0.0), (0.5 * top, 0.3 * top), (-0.4 * top, -0.7 * top)):
        d = np.array([np.tan(np.radians(fx)), np.tan(np.radians(fy)), 1.0])
        d /= np.linalg.norm(d)
        points.append(np.stack([px, py, np.zeros_like(px)], 1) - reach * d)
        directions.append(np.broadcast_to(d, (len(px), 3)))
    bundle = local_trace.bundle(np.concatenate(points), np.concatenate(directions))
    ours = tracer_local.trace_bundle(lens, bundle, lens.primary_wavelength)
    theirs = local_trace.trace(lens, bundle, lens.primary_wavelength)
    assert ours.ok.sum() > 100 and np.array_equal(ours.ok, theirs.ok)
    for name in ("image_x", "image_y", "opl"):
        assert np.abs(getattr(ours, name) - getattr(theirs, name))[ours.ok].max() < 1e-9, name


def test_a_psf_grid_of_unit_sums_keeps_a_uniform_image_uniform(every_lens):
    """A 2×2 geometric grid over the whole field (every node of the lens as built traced, none mirrored), its PSFs
    of unit sum: a uniform image stays uniform through the spatially variant convolution within 5 % (the PSFs
    resampled to the image's pixels and shifted by distortion, and by the tilted sensor's keystone in the lens as
    built; measured 0.7 % on the doublet, 3.3 % on the triplet as built), and the grid of a lens as built names
    the path that computed it."""
    lens = every_lens
    grid = psf_grid(
        lens, grid=(2, 2), wavelengths_nm=[lens.primary_wavelength], method="geometric", size=32, rays=48, pitch_um=2.0
    )
    assert np.isfinite(grid.data).all() and np.allclose(grid.data.sum(axis=(-2, -1)), 1.0, atol=1e-6)
    out = degrade(np.full((24, 32, 3), 0.25, dtype=np.float32), grid)
    assert np.abs(out / 0.25 - 1.0).max() < 0.05
    assert ("psf.as_built" in grid.meta.get("path", "")) == as_built(lens)


@pytest.mark.parametrize(
    "stage, refuse",
    [
        ("the lens camera", lambda lens: default_pitch_um(lens, 0.5 * lens.field_deg, "x", 64, 48)),
        ("the mesh scene", lens_parts),
        ("the ghost tracer", ghost_paths.paths),
        ("reversing a lens", reversed_lens),
    ],
)
def test_a_stage_on_one_axis_refuses_the_lens_as_built_by_name(every_lens, stage, refuse):
    """The lens camera, the mesh scene, the ghost tracer and the exit pupil's reversed lens take a lens on one axis
    and name the surface of a lens as built that they do not take."""
    if not as_built(every_lens):
        refuse(every_lens)
        return
    with pytest.raises(SolasError, match=rf"lens {every_lens.name}: surface 3 .*decentred or tilted.*, which {stage}"):
        refuse(every_lens)
