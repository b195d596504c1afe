"""`batch degrade --lens-population`: each frame degraded by its own lens of a population (a tolerance run's
lens files), chosen by seed and frame name; the manifest names it and re-degrading the frame with that lens
gives the same image; a resumed batch redoes only what is missing, identically."""

import json
from pathlib import Path

import numpy as np
import pytest

from solas_mi.batch import population as pop
from solas_mi.convolution.spec import DegradeSpec
from solas_mi.errors import SolasError
from solas_mi.imageio import read_exr
from solas_mi.optics import tolerance as tol
from solas_mi.psf.spec import GridSpec

GRID = {"grid": (2, 2), "size": 32, "pupil_samples": 32}


@pytest.fixture
def population(tmp_path, doublet):
    """Three doublets off the line (radius and despace drawn), as `solas-mi tolerance` writes them."""
    spec = tol.spec_from_dict(
        doublet, {"tolerance": [{"kind": "radius", "surfaces": [1], "fringes": 20.0}, {"kind": "despace", "mm": 0.2}]}
    )
    folder = tmp_path / "population" / tol.LENS_FOLDER
    folder.mkdir(parents=True)
    for i in range(3):
        tol.draw(doublet, spec, 1, i)[0].save(folder / f"sample_{i:05d}.toml")
    return tmp_path / "population"


def _pixels(path) -> np.ndarray:
    channels, _ = read_exr(str(path))
    return np.stack([channels[k] for k in sorted(channels)])


def test_each_frame_is_degraded_by_the_lens_its_manifest_names(batch_inputs, population):
    from solas_mi.batch import GridCache, degrade_batch

    frames = batch_inputs.write(4)
    cache = GridCache(batch_inputs.root / "cache")
    spec = DegradeSpec(grid_spec=GridSpec(**GRID))
    out = batch_inputs.root / "out"
    done = degrade_batch(
        frames,
        out,
        spec,
        lens_population=pop.Population(population, 5, (-40.0, 85.0)),
        cache=cache,
        workers=1,
        progress=False,
    )
    assert not done.failed and done.grid_source == "population"
    manifest = json.loads((out / "batch.json").read_text())
    lenses = pop.load_population(population)
    used = set()
    for item in manifest["items"]:
        record = item["params"]["lens"]
        name = Path(item["output"]).stem
        assert record["index"] == pop.instance(name, 5, 3) and record["file"] == lenses[record["index"]][0]
        assert record["temperature_c"] == pop.temperature(name, 5, [-40.0, 85.0])
        used.add(record["hash"])
        from solas_mi import Lens

        lens = Lens.load(record["file"]).at(record["temperature_c"])
        assert lens.hash == record["hash"]
        again = degrade_batch(
            [item["input"]],
            batch_inputs.root / f"again-{name}",
            spec,
            lens=lens,
            cache=cache,
            workers=1,
            progress=False,
        )
        np.testing.assert_array_equal(_pixels(again.jobs[0].output), _pixels(item["output"]))
        assert Path(again.jobs[0].png).read_bytes() == Path(item["png"]).read_bytes()
    assert len(used) > 1  # the frames were not all one lens
    assert manifest["grids"]["computed"] == len(used)


def test_a_resumed_population_batch_redoes_only_what_is_missing_identically(batch_inputs, population):
    from solas_mi.batch import GridCache, degrade_batch

    frames = batch_inputs.write(3)
    cache = GridCache(batch_inputs.root / "cache")
    spec = DegradeSpec(grid_spec=GridSpec(**GRID))
    out = batch_inputs.root / "out"

    def run(seed: int = 2):
        given = pop.Population(population, seed)
        return degrade_batch(frames, out, spec, lens_population=given, cache=cache, workers=1, progress=False)

    first = run()
    before = {job.output: _pixels(job.output) for job in first.jobs}
    Path(first.jobs[1].output).unlink()
    second = run()
    assert [job.status for job in second.jobs] == ["skipped", "done", "skipped"]
    for job in second.jobs:
        np.testing.assert_array_equal(_pixels(job.output), before[job.output])
    other = run(seed=3)
    assert all(job.status == "done" for job in other.jobs)  # another seed: other lenses, nothing reused


def test_a_frame_gets_its_lens_by_seed_and_name_alone():
    picks = [pop.instance(f"frame{i:03d}", 7, 5) for i in range(200)]
    assert picks == [pop.instance(f"frame{i:03d}", 7, 5) for i in range(200)]
    assert set(picks) == set(range(5))  # every instance is used
    assert picks != [pop.instance(f"frame{i:03d}", 8, 5) for i in range(200)]


def test_population_mistakes_are_refused_by_name(batch_inputs, population, tmp_path):
    from solas_mi.batch.degrade import plan_batch

    frames = batch_inputs.write(1)
    empty = tmp_path / "empty"
    empty.mkdir()
    for kwargs, message in (
        ({"lens_population": empty}, "0 lens files"),
        ({"lens_population": population, "lens": "solas-doublet"}, "one of"),
        ({"lens_population": pop.Population(population, 0, (500.0,))}, "temperature 500.0"),
        ({"lens_population": pop.Population(population, -1)}, "seed -1"),
    ):
        with pytest.raises(SolasError, match=message):
            plan_batch(frames, tmp_path / "out", DegradeSpec(grid_spec=GridSpec(**GRID)), **kwargs)


def test_the_command_takes_a_population(batch_inputs, population, capsys):
    """--lens-population on the command line: the dry run counts the lens instances the frames use; a
    temperature for every lens is refused, pointing to --frame-temperatures-c."""
    from solas_mi.cli import main

    frames = batch_inputs.write(6)
    argv = [
        "batch",
        "degrade",
        *map(str, frames),
        "--lens-population",
        str(population),
        "--seed",
        "5",
        "--grid",
        "2x2",
        "--size",
        "32",
        "-o",
        str(batch_inputs.root / "out"),
        "--cache",
        str(batch_inputs.root / "cache"),
    ]
    assert main([*argv, "--frame-temperatures-c", "-40", "85", "--dry-run"]) == 0
    used = {(pop.instance(f.stem, 5, 3), pop.temperature(f.stem, 5, [-40.0, 85.0])) for f in frames}
    assert f"{len(used)} lens instances of {population.resolve()}" in capsys.readouterr().out
    assert main([*argv, "--temperature-c", "60", "--dry-run"]) == 2
    assert "--frame-temperatures-c" in capsys.readouterr().err
    argv[argv.index("--lens-population") : argv.index("--seed")] = ["--lens", "solas-doublet"]
    assert main([*argv, "--frame-temperatures-c", "60", "--dry-run"]) == 2
    assert "--frame-temperatures-c is for --lens-population" in capsys.readouterr().err


def test_a_render_batch_takes_a_population(batch_inputs, population, tmp_path):
    """`render_batch(lens=Population(...))`: each item's lens is the population's pick for its name (and
    temperature), named in its params; rendering the frame with that lens file alone gives the same image."""
    from solas_mi.batch import render_batch

    frames = batch_inputs.write(3)
    common = {"sensor": "16x12", "spp": 1, "workers": 1, "progress": False}
    done = render_batch(frames, tmp_path / "pop", lens=pop.Population(population, 0, (-20.0, 60.0)), **common)
    assert [job.status for job in done.jobs] == ["done"] * 3
    lenses = pop.load_population(population)
    for job in done.jobs:
        own = pop.pick(Path(job.output).stem, lenses, 0, (-20.0, 60.0))
        assert job.params["lens"] == own["file"] and job.params["temperature_c"] == own["temperature_c"]
        assert job.params["lens_hash"] == own["lens"].hash == pop.item_lens(job.params).hash
    plain = render_batch(frames, tmp_path / "pop0", lens=pop.Population(population), **common)
    job = plain.jobs[0]
    alone = render_batch([job.input], tmp_path / "alone", lens=job.params["lens"], **common)
    np.testing.assert_array_equal(_pixels(alone.jobs[0].output), _pixels(job.output))


def test_a_population_batch_on_dask_equals_the_local_one(batch_inputs, population):
    from solas_mi.batch import GridCache, degrade_batch

    frames = batch_inputs.write(3)
    cache = GridCache(batch_inputs.root / "cache")
    common = {"lens_population": pop.Population(population, 4), "cache": cache, "workers": 2, "progress": False}
    spec = DegradeSpec(grid_spec=GridSpec(**GRID))
    local = degrade_batch(frames, batch_inputs.root / "local", spec, **common)
    dask = degrade_batch(frames, batch_inputs.root / "dask", spec, dask="local", **common)
    assert dask.count("done") == local.count("done") == 3
    for a, b in zip(local.jobs, dask.jobs):
        assert a.params == b.params
        np.testing.assert_array_equal(_pixels(a.output), _pixels(b.output))
