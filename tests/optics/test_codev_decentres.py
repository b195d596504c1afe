"""CODE V decentres and tilts read into coordinate breaks (`optics.codev_placement`): each surface's frame
of a hand-written .seq is where CODE V's rules, written out here in the global frame, put it — a basic
decentre, DAR, REV returning a basic decentre, BEN, and a tilted image — α and β by the left-hand rule and
γ by the right-hand rule, in lens units."""

from __future__ import annotations

import math

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics.placement import frames

MOVE = {"XDE": 0.4, "YDE": -0.3, "ZDE": 0.2, "ADE": 3.0, "BDE": -2.0, "CDE": 25.0}
GAPS = (4.0, 2.0, 30.0, 5.0)  # S1 … S4 thicknesses (S4 to the image)


def _seq(moves: dict[str, str], dim: str = "M") -> str:
    """Four surfaces and the image in lens units (`dim`), each followed by its decentre commands from `moves`
    (by row name and number)."""
    u = {"M": 1.0, "C": 10.0}[dim]
    rows = [
        f"STO {40 / u!r} {GAPS[0] / u!r} 1.6:40 ; CIR {8 / u!r}",
        f"S {-60 / u!r} {GAPS[1] / u!r} ; CIR {8 / u!r}",
        f"S {80 / u!r} {GAPS[2] / u!r} 1.7:30 ; CIR {8 / u!r}",
        f"S {-90 / u!r} {GAPS[3] / u!r} ; CIR {8 / u!r}",
        "SI 0 0",
    ]
    body = "\n".join(f"{row}\n{moves.get(row.split()[0] + str(k), '')}" for k, row in enumerate(rows, start=1))
    return f"RDM\nDIM {dim}\nWL 550\nEPD {10 / u!r}\nYAN 0 2\nSO 0 1e10\n{body}\n"


def _decentre(scale: float = 1.0) -> str:
    """MOVE's commands, the decentres in lens units of `scale` mm."""
    return "\n".join(f"{k} {v / scale if k.endswith('DE') and k[0] in 'XYZ' else v!r}" for k, v in MOVE.items())


def _turn(axis: int, degrees: float) -> np.ndarray:
    """The right-hand rotation (columns: the new axes) about coordinate `axis` by `degrees`."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[j, j] = c, c
    m[i, j], m[j, i] = (-s, s) if axis != 1 else (s, -s)
    return m


def _codev_move() -> tuple[np.ndarray, np.ndarray]:
    """CODE V's move: decentre (XDE, YDE, ZDE), then α about x and β about y by the left-hand rule, γ about z
    by the right-hand rule, each about the axes the one before left."""
    d = np.array([MOVE["XDE"], MOVE["YDE"], MOVE["ZDE"]])
    return d, _turn(0, -MOVE["ADE"]) @ _turn(1, -MOVE["BDE"]) @ _turn(2, MOVE["CDE"])


def _expected(kind: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """The vertices and axes of S1 … S4 and the image by CODE V's rules for a decentre of `kind` on S2
    (REV: a basic decentre on S2 returned by REV on S3)."""
    d, r = _codev_move()
    z = np.array([0.0, 0.0, 1.0])
    s1 = (np.zeros(3), np.eye(3))
    nominal2 = s1[0] + GAPS[0] * z
    s2 = (nominal2 + d, r)
    if kind == "DAR":
        after2 = (nominal2, np.eye(3))
    elif kind == "BEN":
        after2 = (s2[0], r @ r)
    else:
        after2 = s2
    s3 = (after2[0] + GAPS[1] * after2[1][:, 2], after2[1])
    after3 = (s3[0] - s3[1] @ r.T @ d, s3[1] @ r.T) if kind == "REV" else s3  # the move undone
    s4 = (after3[0] + GAPS[2] * after3[1][:, 2], after3[1])
    image = (s4[0] + GAPS[3] * s4[1][:, 2], s4[1])
    return [s1, s2, s3, s4, image]


@pytest.mark.parametrize("kind", ["basic", "DAR", "BEN", "REV"])
@pytest.mark.parametrize("dim", ["M", "C"])
def test_each_surface_lies_where_code_v_puts_it(tmp_path, kind, dim):
    scale = {"M": 1.0, "C": 10.0}[dim]
    moves = {"S2": _decentre(scale) + ("\nDAR" if kind == "DAR" else "\nBEN" if kind == "BEN" else "")}
    if kind == "REV":
        moves["S3"] = _decentre(scale) + "\nREV"
    path = tmp_path / "decentred.seq"
    path.write_text(_seq(moves, dim))
    got = frames(Lens.load(path).surfaces, Lens.load(path).image_placement)
    for (o, a), (eo, ea) in zip(got, _expected(kind)):
        assert np.abs(o - eo).max() < 1e-12 and np.abs(a - ea).max() < 1e-12


def test_a_tilted_image_and_what_is_refused(tmp_path):
    """ADE on SI tilts the sensor: by the left-hand rule a positive α turns its normal (+z) toward +y."""
    path = tmp_path / "tilted.seq"
    path.write_text(_seq({"SI5": "ADE 0.5"}))
    lens = Lens.load(path)
    normal = frames(lens.surfaces, lens.image_placement)[-1][1][:, 2]
    assert np.abs(normal - [0.0, math.sin(math.radians(0.5)), math.cos(math.radians(0.5))]).max() < 1e-15
    assert all(s.placement is None for s in lens.surfaces)
    for moves, match in (
        ({"STO1": "ZDE 0.1"}, "ZDE on surface 1 is not supported"),
        ({"S2": "XDE"}, "XDE needs a value"),
    ):
        path.write_text(_seq(moves))
        with pytest.raises(SolasError, match=match):
            Lens.load(path)
