"""The sequential ghosts against brute force (`validation.mesh_ghosts`): the same rays through the Cooke
triplet as Mitsuba meshes whose glass samples each reflection with probability R (`fresnel` "sample").
The count of rays that take each path is Poisson about the sequential trace's expectation (its weights
are each ray's chance of that path), and each ray lands where the sequential trace of that ray lands."""

import math

import numpy as np
import pytest

from solas_mi.validation.mesh_ghosts import mesh_ghosts


@pytest.mark.slow
def test_every_ghost_of_the_triplet_matches_the_meshes(triplet, variant_llvm_ad_spectral):
    rows = mesh_ghosts(triplet, (0.0, 10.0), 587.5618, rays=128, passes=8)
    direct = rows.pop(None)
    assert abs(direct["observed"] - direct["expected"]) < 4 * math.sqrt(direct["expected"])
    assert max(direct["shifts_um"]) < 1.0  # float32 meshes against Float64: well under a pixel
    assert len(rows) == 15  # every path of the six reflecting surfaces, and no other two-reflection path
    for path, row in rows.items():
        e, o = row["expected"], row["observed"]
        assert abs(o - e) < 4 * math.sqrt(e) + 1, (path, o, e)  # Poisson, 4 sigma
        if row["shifts_um"]:
            assert np.median(row["shifts_um"]) < 10 and max(row["shifts_um"]) < 100, (path, row["shifts_um"])
    expected, observed = (sum(r[k] for r in rows.values()) for k in ("expected", "observed"))
    assert abs(observed / expected - 1) < 4 / math.sqrt(expected)  # all ghosts together


@pytest.mark.slow
def test_the_coated_triplet_s_ghosts_match_the_coated_meshes(triplet, variant_llvm_ad_spectral):
    """The triplet with the typical AR (`optics.typical_ar`, MgF2 on its six air-glass faces) as meshes of
    `coated_dielectric`: each path's sampled power is Poisson about the sequential engine's expectation,
    which takes the same coatings by their transfer matrices (a ghost's chance 40x below bare glass). Only
    the grid's rays that the trace carries are launched (`traced_rays_only`), for statistics."""
    from solas_mi.optics.typical_ar import with_typical_ar

    rows = mesh_ghosts(with_typical_ar(triplet), (0.0, 10.0), 587.5618, rays=384, passes=40, traced_rays_only=True)
    direct = rows.pop(None)
    assert abs(direct["observed"] - direct["expected"]) < 4 * math.sqrt(direct["expected"])
    assert len(rows) == 15
    for path, row in rows.items():
        e, o = row["expected"], row["observed"]
        assert abs(o - e) < 4 * math.sqrt(e) + 1, (path, o, e)
    expected, observed = (sum(r[k] for r in rows.values()) for k in ("expected", "observed"))
    assert expected > 100  # enough ghost rays that the bound below says something (4 sigma: 40 %)
    assert abs(observed / expected - 1) < 4 / math.sqrt(expected)
