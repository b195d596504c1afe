"""A population of lenses through a degrade batch (`batch degrade --lens-population DIR`): each frame is
degraded by its own lens instance, one of the lens files in DIR (or DIR/lenses, where `solas-mi tolerance`
writes its drawn lenses), chosen by the batch's seed and the frame's name as the sensor's noise is
(`instance`: the same frame gets the same lens whatever the order, the workers or a resumed run), and
optionally at one of a list of temperatures chosen the same way (`temperature`, `Lens.at`). Each instance's
PSF grid is computed once through the batch's `GridCache` (by the lens's hash, at that temperature) and read
by the items that use it; the manifest records, per item, the lens file, its hash, the temperature and the
grid (`Job.params["lens"]`, `Job.params["psf_grid"]`)."""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import SolasError
from ..optics.tolerance import LENS_FOLDER
from .jobs import Job

MAX_INSTANCES = 100_000
_READ: dict[str, Any] = {}  # this process's last grid read (`item_grid`): a worker's items share it in turn


@dataclass(frozen=True)
class Population:
    """A lens population for a degrade batch: the folder of lens files, the seed that picks each frame's lens
    (and temperature) with its name, and the frames' temperatures (°C; (): each lens as its file states)."""

    folder: str | os.PathLike
    seed: int = 0
    temperatures_c: tuple[float, ...] = ()


def load_population(folder: str | os.PathLike) -> list[tuple[str, Any]]:
    """(path, Lens) of each lens file in `folder` (or its `LENS_FOLDER`), sorted by file name; SolasError
    for a folder without lens files or a lens file that does not read (named)."""
    from ..optics.formats import READERS
    from ..optics.lens import Lens

    root = Path(folder)
    if not root.is_dir():
        raise SolasError(
            f"lens population {str(folder)!r} must be a folder of lens files (e.g. a `solas-mi "
            "tolerance` output folder)"
        )
    if (root / LENS_FOLDER).is_dir():
        root = root / LENS_FOLDER
    files = sorted(p for p in root.iterdir() if p.is_file() and p.suffix.lower() in READERS)
    if not files or len(files) > MAX_INSTANCES:
        raise SolasError(
            f"lens population {str(root)!r} holds {len(files)} lens files ({', '.join(READERS)}); "
            f"give a folder of 1 to {MAX_INSTANCES}"
        )
    return [(str(p.resolve()), Lens.load(p)) for p in files]


def _pick(what: str, seed: int, name: str, count: int) -> int:
    """An index below `count` from the SHA-256 of (what, seed, name)."""
    digest = hashlib.sha256(f"{what}:{seed}:{name}".encode()).digest()
    return int.from_bytes(digest[:8], "big") % count


def instance(name: str, seed: int, count: int) -> int:
    """The population's lens (index among `count`) that frame `name` (its output's stem) is degraded by."""
    return _pick("lens", seed, name, count)


def temperature(name: str, seed: int, temperatures_c) -> float | None:
    """The temperature (°C) of frame `name` among `temperatures_c` (None where none are given)."""
    return float(temperatures_c[_pick("temperature", seed, name, len(temperatures_c))]) if temperatures_c else None


def check_temperatures(temperatures_c) -> tuple[float, ...]:
    """The frames' temperatures, each checked (`thermal.check_environment`); () where none are given."""
    from ..optics.thermal import STANDARD_KPA, check_environment

    return tuple(check_environment(t, STANDARD_KPA)[0] for t in temperatures_c or ())


def pick(name: str, lenses, seed: int, temperatures_c) -> dict:
    """The lens of the frame (item) `name`: {"file", "index", "hash", "temperature_c"} (`instance`,
    `temperature`; the hash of the lens at that temperature), and that lens ("lens", not for the manifest)."""
    index = instance(name, seed, len(lenses))
    path, lens = lenses[index]
    t = temperature(name, seed, temperatures_c)
    there = lens if t is None else lens.at(t)
    return {"file": path, "index": index, "hash": there.hash, "temperature_c": t, "lens": there}


def assign(jobs: list[Job], lenses, seed: int, temperatures_c, cache, grid_spec) -> None:
    """Each item's lens instance and temperature (`pick`: `lens` in its params) and the grid it takes from
    `cache` (`psf_grid`)."""
    for job in jobs:
        record = pick(Path(job.output).stem, lenses, seed, temperatures_c)
        job.params["psf_grid"] = str(cache.path(record.pop("lens"), grid_spec))
        job.params["lens"] = record


def key(population, seed: int, temperatures_c) -> str:
    """What of the population makes the outputs: its lenses' hashes, the seed and the temperatures."""
    content = [[lens.hash for _, lens in population], seed, list(temperatures_c or ())]
    return hashlib.sha256(repr(content).encode()).hexdigest()[:16]


def instance_lens(job: Job, population):
    """The lens of an item (`assign`), at its temperature."""
    record = job.params["lens"]
    lens = population[record["index"]][1]
    return lens if record["temperature_c"] is None else lens.at(record["temperature_c"])


def grids(jobs: list[Job], todo: list[int], population, grid_spec, cache, progress=None) -> dict[str, int]:
    """The grid of each item of `todo` (`assign`) from `cache`, or computed there once per lens instance and
    temperature; {"computed": n, "cache hits": m}."""
    done: set[str] = set()
    count = {"computed": 0, "cache hits": 0}
    for i in todo:
        if jobs[i].params["psf_grid"] not in done:
            path, hit, _ = cache.get(instance_lens(jobs[i], population), grid_spec, progress=progress)
            done.add(str(path))
            count["cache hits" if hit else "computed"] += 1
    return count


def cameras(jobs: list[Job], todo: list[int], population, sizes, frame, model) -> dict[str, dict]:
    """Each grid's camera blocks (`convolution.camera.frame_cameras`, by frame size), fitted once per grid."""
    from ..convolution.camera import frame_cameras
    from ..psf.depth import read_grid

    out: dict[str, dict] = {}
    for i in todo:
        path = jobs[i].params["psf_grid"]
        if path not in out:
            out[path] = frame_cameras(read_grid(path), sizes, frame, model, instance_lens(jobs[i], population))
    return out


def item_lens(params: dict):
    """A render item's lens: its file (`params["lens"]`), at the temperature a population picked for it."""
    from ..optics.lens import Lens

    lens = Lens.load(params["lens"])
    return lens if params.get("temperature_c") is None else lens.at(params["temperature_c"])


def item_grid(path: str):
    """The grid at `path`, read once while this process's items use it in turn."""
    from ..psf.depth import read_grid

    if path not in _READ:
        _READ.clear()
        _READ[path] = read_grid(path)
    return _READ[path]


def checked(population, psf_grid, lens, scale_lens) -> tuple[Population, list] | None:
    """(`population`, its (path, Lens)) checked against the batch's other sources (one of a grid file, a
    lens or a population; --scale-lens scales one lens); None without a population."""
    if sum(x is not None for x in (psf_grid, lens, population)) != 1:
        raise SolasError("give one of a PSF grid file, a lens to compute one from, or a lens population")
    if population is None:
        return None
    if scale_lens is not None:
        raise SolasError("--scale-lens scales one lens: give --lens, not --lens-population")
    return loaded(population)


def loaded(population) -> tuple[Population, list]:
    """`population` (a `Population`, or its folder) checked, and its lenses ((path, Lens), `load_population`)."""
    if not isinstance(population, Population):
        population = Population(population)
    seed = population.seed
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise SolasError(f"seed {seed!r} must be a whole number >= 0")
    given = Population(population.folder, seed, check_temperatures(population.temperatures_c))
    return given, load_population(population.folder)


__all__ = [
    "Population",
    "assign",
    "grids",
    "instance",
    "item_grid",
    "item_lens",
    "load_population",
    "loaded",
    "pick",
    "temperature",
]


def degrade_settings(p, header: dict, n: int, dask, force: bool, progress: bool) -> dict:
    """A lens population's part of `degrade_batch` (`p` its `BatchPlan`): every item's grid (`grids`) and camera
    blocks, the manifest's header told of the population; the settings each item is degraded with."""
    from ..imageio import image_size
    from ..progress import Progress

    assert p.population is not None and p.cache is not None
    given, lenses = p.population
    with Progress("psf-grid", None, "PSFs", enabled=progress) as bar:
        counts = grids(p.jobs, p.todo, lenses, p.grid_spec, p.cache, progress=bar)
    sizes = [image_size(p.jobs[i].input)[1::-1] for i in p.todo]
    blocks = cameras(p.jobs, p.todo, lenses, [s for s in sizes if s[0]], p.spec.frame, p.spec.calibration_model)
    header.update(
        {
            "grid_source": "population",
            "grid_spec": p.grid_spec.canonical(),
            "grids": counts,
            "lens_population": {
                "folder": str(Path(given.folder).resolve()),
                "lenses": len(lenses),
                "seed": given.seed,
                "temperatures_c": list(given.temperatures_c),
            },
            "runner": {"dask": dask} if dask is not None else {"workers": n},
        }
    )
    p.manifest.header.update(header)
    return {
        "spec": p.spec,
        "camera": p.spec.camera,
        "force": force,
        "population_cameras": blocks,
        "batch": {"id": p.key, "manifest": str(p.manifest.path)},
    }
