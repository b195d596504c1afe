"""The Newton iteration of ray aiming (`optics.newton`) traces only the rays still moving, and a ray's
solution is its own, whatever rays share its batch; NumPy arrays reach Dr.Jit in memory that does not
change its kernels."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics import aiming as A
from solas_mi.optics import pupil as P
from solas_mi.optics import tracer as T

dr = T.dr


def test_only_the_rays_still_moving_are_traced(monkeypatch):
    """The double Gauss lens at 17.6° by 17.6°: its vignetted rim holds a few rays that move for tens of
    steps. Every step traced all 4096 rays of the 64² grid (175 traces a ray); now about 2 of the rays
    the grid aims, counted over all its levels."""
    lens = Lens.load("double-gauss-50mm")
    traced = []
    trace = A.Bundle.trace

    def counting(self, ex, ey, *args, **kwargs):
        traced.append(dr.width(ex))
        return trace(self, ex, ey, *args, **kwargs)

    monkeypatch.setattr(A.Bundle, "trace", counting)
    pf = P.pupil_function(lens, [[17.6, 17.6]], [587.56], 64)
    assert (pf.coverage > 0).sum() > 500
    assert sum(traced) < 8 * 64 * 64


def test_a_ray_is_aimed_alike_alone_and_in_a_batch():
    """The wide-angle lens's corner (33°, 33°), whose pupil has vignetted edges where a ray converges only
    from the right start: its pupil function alone and beside two other fields."""
    lens = Lens.load("wide-angle-22mm")
    w = lens.wavelengths_nm[0]
    alone = P.pupil_function(lens, [[33.0, 33.0]], [w], 64)
    batch = P.pupil_function(lens, [[11.0, 11.0], [33.0, 11.0], [33.0, 33.0]], [w] * 3, 64)
    assert np.array_equal(alone.coverage[0] > 0, batch.coverage[2] > 0)
    assert np.abs(alone.opd_mm[0] - batch.opd_mm[2]).max() < 1e-9
    assert batch.transmission[2] == pytest.approx(alone.transmission[0], rel=1e-9)


def test_numpy_arrays_reach_dr_jit_without_new_kernels():
    """A kernel reading a NumPy array in place is compiled for its address's alignment: the same
    computation over arrays at different offsets was up to one kernel per alignment (20-40 compilations
    of 10-100 ms in each 8x8 PSF grid). Through `tracer.array` the kernel is one."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        kernels = set()
        for offset in range(8):
            raw = np.arange(100_040, dtype=np.float64)
            x = T.array(raw[offset : offset + 100_000])
            dr.kernel_history()
            dr.eval(dr.sqrt(x * x + 0.123456789))
            kernels |= {str(k["hash"]) for k in dr.kernel_history() if str(k["type"]).endswith("JIT")}
        assert len(kernels) == 1
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)


def test_chief_rays_that_the_paraxial_guess_reaches_are_aimed_once(monkeypatch):
    """`chief_aim` aims from the paraxial guess to learn which fields it loses; where it loses none, that
    aim is the chief rays' (the same aim, from the same start, was run a second time)."""
    fields = np.stack([np.zeros(5), np.linspace(0.0, 2.0, 5)], axis=-1)
    doublet = Lens.load("solas-doublet")
    calls = []
    aim = A.aim

    def counting(*args, **kwargs):
        calls.append(args[0].n_fields)
        return aim(*args, **kwargs)

    monkeypatch.setattr(A, "aim", counting)
    monkeypatch.setattr(P, "aim", counting)
    chief = P.chief_rays(doublet, fields, np.full(5, 531.0))
    assert calls == [5]
    tr = P.Bundle(doublet, fields, np.full(5, 531.0), 1).trace(
        T.array(chief.entrance[:, 0]), T.array(chief.entrance[:, 1])
    )
    assert np.abs(np.concatenate(T.to_numpy(tr.stop_x, tr.stop_y))).max() < 1e-9  # through the stop centre
