"""How much a lens may hold (`optics.formats`: MAX_SURFACES, MAX_WAVELENGTHS, MAX_FIELDS) and how large a
lens file may be (`userfiles.LIMITS`): refused in every reader (TOML, Zemax .zmx, CODE V .seq, pbrt .dat)
and wherever a `Lens` is built, in seconds, before anything is traced. Before: a .seq of 10 000 surfaces
crashed `lens info` (a segmentation fault: Dr.Jit's kernel assembly recurses once per variable of a
ray's chain through the surfaces and overflowed the stack), 2 000 surfaces or 10⁶ wavelengths ran past
2 minutes, 3 000 nested arrays raised RecursionError, a Zemax FTYP of 10¹² fields a MemoryError."""

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics.formats import MAX_FIELDS, MAX_SURFACES, MAX_WAVELENGTHS
from solas_mi.optics.lens import NORM_RADIUS_MM
from solas_mi.optics.paraxial import paraxial
from solas_mi.userfiles import LIMITS, MAX_NESTING, _size


def _toml(surfaces: int, wavelengths: int = 3) -> str:
    """A stack of thin meniscus elements, the stop first."""
    waves = ", ".join(str(500.0 + i) for i in range(wavelengths))
    rows = [
        f"[[surface]]\nradius = {1000.0 if i % 2 == 0 else -1000.0}\nthickness = 2.0\ndiameter = 10.0\n"
        f'material = "{"N-BK7" if i % 2 == 0 else "AIR"}"\nstop = {"true" if i == 0 else "false"}\n'
        for i in range(surfaces)
    ]
    return f"wavelengths_nm = [{waves}]\n" + "".join(rows)


def _zmx(surfaces: int, fields: int = 2, waves: int = 1, ftyp_count: int | None = None) -> str:
    blocks = "".join(
        f"SURF {i}\n  {'STOP' if i == 1 else ''}\n  CURV {0.001 if i % 2 else -0.001}\n  DISZ 2\n"
        f"  {'GLAS N-BK7' if i % 2 else ''}\n  DIAM 5 1\n"
        for i in range(1, surfaces + 1)
    )
    ys = " ".join(str(float(i)) for i in range(fields))
    return (
        "UNIT MM\nFLOA\n"
        + f"FTYP 0 0 {fields if ftyp_count is None else ftyp_count} 1 0 0 0\n"
        + f"XFLN {' '.join('0' for _ in range(fields))}\nYFLN {ys}\n"
        + "".join(f"WAVM {i + 1} {0.5 + 0.001 * i} 1\n" for i in range(waves))
        + "SURF 0\n  DISZ INFINITY\n"
        + blocks
        + f"SURF {surfaces + 1}\n  DISZ 0\n"
    )


def _seq(surfaces: int, fields: int = 2) -> str:
    rows = "".join(
        f"S {1000.0 if i % 2 == 0 else -1000.0} 2 {'N-BK7_SCHOTT' if i % 2 == 0 else ''}\nCIR 5\n"
        + ("STO\n" if i == 0 else "")
        for i in range(surfaces)
    )
    return (
        f"RDM\nDIM M\nWL 550\nEPD 2\nYAN {' '.join(str(float(i)) for i in range(fields))}\nSO 0 1e10\n"
        + rows
        + "SI 0 0\n"
    )


def _dat(surfaces: int) -> str:
    rows = ["0 2.0 0 5.0"] + [
        f"{1000.0 if i % 2 else -1000.0} 2.0 {1.5 if i % 2 else 0} 10.0" for i in range(1, surfaces)
    ]
    return "# radius thickness n_d aperture\n" + "\n".join(rows) + "\n"


WRITE = {".toml": _toml, ".zmx": _zmx, ".seq": _seq, ".dat": _dat}


def _file(tmp_path, ext: str, text: str):
    path = tmp_path / f"lens{ext}"
    path.write_text(text)
    return path


def test_ten_thousand_surfaces_are_refused_not_a_crash(tmp_path):
    """`lens info` on a .seq of 10 000 surfaces: exit 2 with one line, within a timeout generous for a
    loaded machine (before: compiling for many minutes, then a segmentation fault, exit 139)."""
    path = _file(tmp_path, ".seq", _seq(10_000))
    done = subprocess.run(
        [sys.executable, "-m", "solas_mi", "lens", "info", str(path)], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 2, done.stderr[-500:]
    assert done.stderr.strip().endswith(f"10000 surfaces; a lens may have at most {MAX_SURFACES}")
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("ext", list(WRITE))
def test_every_reader_refuses_one_surface_too_many(tmp_path, ext):
    with pytest.raises(
        SolasError, match=f"lens{ext}: {MAX_SURFACES + 1} surfaces; a lens may have at most {MAX_SURFACES}$"
    ):
        Lens.load(_file(tmp_path, ext, WRITE[ext](MAX_SURFACES + 1)))


def test_a_lens_at_the_bounds_is_a_lens(tmp_path):
    lens = Lens.load(_file(tmp_path, ".toml", _toml(MAX_SURFACES, MAX_WAVELENGTHS)))
    assert len(lens.surfaces) == MAX_SURFACES and len(lens.wavelengths_nm) == MAX_WAVELENGTHS


@pytest.mark.parametrize(
    "ext, text", [(".toml", _toml(3, MAX_WAVELENGTHS + 1)), (".zmx", _zmx(3, waves=MAX_WAVELENGTHS + 1))]
)
def test_wavelengths_are_bounded(tmp_path, ext, text):
    with pytest.raises(
        SolasError, match=f"{MAX_WAVELENGTHS + 1} wavelengths; a lens may have at most {MAX_WAVELENGTHS}"
    ):
        Lens.load(_file(tmp_path, ext, text))


@pytest.mark.parametrize(
    "ext, text, count",
    [
        (".zmx", _zmx(3, fields=MAX_FIELDS + 1), MAX_FIELDS + 1),
        (".zmx", _zmx(3, ftyp_count=10**12), 10**12),
        (".seq", _seq(3, fields=MAX_FIELDS + 1), MAX_FIELDS + 1),
    ],
)
def test_fields_are_bounded(tmp_path, ext, text, count):
    """FTYP's count of fields (10¹²: before, a list of 10¹² zeros, MemoryError) or the fields listed."""
    with pytest.raises(SolasError, match=f"{count} fields; a lens may have at most {MAX_FIELDS}"):
        Lens.load(_file(tmp_path, ext, text))


def test_the_python_api_is_bounded_too(doublet):
    """However a Lens is built: the constructor, `dataclasses.replace`, `from_dict`."""
    many = doublet.surfaces * (MAX_SURFACES // len(doublet.surfaces) + 1)
    message = f"{len(many)} surfaces; a lens may have at most {MAX_SURFACES}"
    with pytest.raises(SolasError, match=message):
        dataclasses.replace(doublet, surfaces=many)
    with pytest.raises(SolasError, match=message):
        Lens("big", many)
    with pytest.raises(SolasError, match=f"{MAX_WAVELENGTHS + 1} wavelengths"):
        dataclasses.replace(doublet, wavelengths_nm=tuple(500.0 + i for i in range(MAX_WAVELENGTHS + 1)))
    with pytest.raises(SolasError, match=message):
        Lens.from_dict({"surface": [{"radius": 0.0, "thickness": 1.0, "diameter": 1.0}] * len(many)})


def test_nesting_and_size_of_a_lens_file(tmp_path):
    """3 000 nested arrays (before: RecursionError) and a file over the bound (sparse: no disk used)."""
    deep = _file(tmp_path, ".toml", "x = " + "[" * 3000 + "]" * 3000 + "\n")
    with pytest.raises(SolasError, match=f"nests tables and arrays more than {MAX_NESTING} levels deep"):
        Lens.load(deep)
    big = tmp_path / "big.zmx"
    with open(big, "wb") as f:
        f.truncate(LIMITS["lens file"] + 1)
    with pytest.raises(SolasError, match=f"is larger than {_size(LIMITS['lens file'])}, the most a lens file may hold"):
        Lens.load(big)


@pytest.mark.parametrize("rho", [0.0, 1e300, -1.0])
def test_a_normalisation_radius_that_breaks_arithmetic_is_refused(doublet_spec, rho):
    """norm_radius 0 divided by zero in the paraxial curvature (ZeroDivisionError), 1e300 overflowed
    its square (OverflowError), with or without Qbfs terms."""
    doublet_spec["surface"][0]["norm_radius"] = rho
    lo, hi = NORM_RADIUS_MM
    with pytest.raises(
        SolasError,
        match=re.escape(f"norm_radius, the radius where the Qbfs terms' u = 1, from {lo:g} to {hi:g} mm; got {rho!r}"),
    ):
        paraxial(Lens.from_dict(doublet_spec))


def test_the_docs_state_the_limits():
    """The lens-file page and the conventions page state the bounds `formats` and `userfiles` hold."""
    docs = Path(__file__).resolve().parents[2] / "docs"
    lenses, conventions = (" ".join((docs / name).read_text().split()) for name in ("lens-files.md", "conventions.md"))
    assert (
        f"A lens holds at most {MAX_SURFACES} surfaces and {MAX_WAVELENGTHS} wavelengths, and a Zemax or CODE V "
        f"file at most {MAX_FIELDS} fields"
    ) in lenses
    assert f"at most {_size(LIMITS['lens file'])}, a TOML one UTF-8 nested at most {MAX_NESTING} levels" in lenses
    assert (
        f"A lens holds at most {MAX_SURFACES} surfaces and {MAX_WAVELENGTHS} wavelengths, a .zmx or .seq at most "
        f"{MAX_FIELDS} fields"
    ) in conventions
