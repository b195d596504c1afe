"""What a batch does once and what each worker runs: the workers share the machine's cores, each running its
share of them (`runner.worker_threads`) in its convolution pool and in OpenBLAS, not every core each (two
workers on 2 cores ran up to 8 busy threads), to the same pixels; a given grid file is hashed once per batch."""

import numpy as np
import pytest

from solas_mi import blas, threads
from solas_mi.batch import degrade, degrade_batch, runner
from solas_mi.batch.work import run_job
from solas_mi.convolution import kernels
from solas_mi.imageio import read_exr
from solas_mi.psf.depth import read_grid


@pytest.fixture
def own_threads(monkeypatch):
    """This process's share of the cores and OpenBLAS's threads as they were, after the test."""
    monkeypatch.setattr(threads, "_SHARE", None)
    api = blas._openblas_threads()
    before = api[0]() if api is not None else None
    yield api
    if api is not None:
        api[1](before)


def test_each_of_two_workers_on_two_cores_runs_one_thread(batch_inputs, monkeypatch, own_threads):
    batch_inputs.write(2)
    monkeypatch.setattr(threads, "cores", lambda: 2)
    pools, seen = [], {}
    real_pool = kernels.ThreadPoolExecutor
    monkeypatch.setattr(kernels, "ThreadPoolExecutor", lambda n: pools.append(n) or real_pool(n))

    def in_process(jobs, todo, grid_path, settings, workers, on_done):  # `run_local`, here: what a worker runs
        seen.update(settings)
        for i in todo:
            on_done(i, run_job(jobs[i], read_grid(grid_path), grid_path, settings))
        seen["blas"] = own_threads[0]() if own_threads is not None else 1

    monkeypatch.setattr(runner, "run_local", in_process)
    root = batch_inputs.root
    two = degrade_batch([batch_inputs.images], root / "two", psf_grid=batch_inputs.grid, workers=2, progress=False)
    assert seen["threads"] == 1 and kernels.workers() == 1 and seen["blas"] == 1
    assert pools == []  # one thread: the convolution runs without a pool
    monkeypatch.setattr(threads, "_SHARE", None)
    one = degrade_batch([batch_inputs.images], root / "one", psf_grid=batch_inputs.grid, workers=1, progress=False)
    assert seen["threads"] == 2 and pools and set(pools) == {2}
    for a, b in zip(two.jobs, one.jobs):
        assert a.status == b.status == "done"
        assert all(np.array_equal(x, y) for x, y in zip(read_exr(a.output)[0].values(), read_exr(b.output)[0].values()))


def test_the_share_of_the_cores():
    assert (
        threads.share(1) == threads.cores()
        and threads.share(threads.cores()) == 1
        and threads.share(10 * threads.cores()) == 1
    )
    assert runner.worker_threads(1, None) == runner.worker_threads(1, "local") == threads.cores()
    assert runner.worker_threads(1, "tcp://scheduler:8786") is None  # its machines' own cores


def test_a_given_grid_is_hashed_once_per_batch(batch_inputs, monkeypatch):
    """The batch's identity and its manifest's grid_hash both name the given grid's hash: one read of the whole
    file for both (it was read twice: 0.2 CPU-s each for a 32×32×3 grid of 160 px, 315 MB)."""
    batch_inputs.write(1)
    hashed = []
    real_hash = degrade.file_hash
    monkeypatch.setattr(degrade, "file_hash", lambda path, *a: hashed.append(str(path)) or real_hash(path, *a))
    result = degrade_batch(
        [batch_inputs.images], batch_inputs.root / "out", psf_grid=batch_inputs.grid, workers=1, progress=False
    )
    assert result.count("done") == 1 and hashed.count(str(batch_inputs.grid)) == 1
    header = result.manifest.read_text()
    assert real_hash(batch_inputs.grid) in header


def test_the_workers_map_the_grid_the_batch_read_not_its_file(batch_inputs, monkeypatch):
    """The local workers take the batch's grid from shared memory, read-only, instead of each reading the grid
    file again (0.7 CPU-s and 315 MB per worker for a 32×32×3 grid of 160 px): with the file gone once the
    batch has read it, the workers still degrade every frame, to the pixels of a batch that kept it."""
    batch_inputs.write(3)
    root = batch_inputs.root
    kept = degrade_batch([batch_inputs.images], root / "kept", psf_grid=batch_inputs.grid, workers=2, progress=False)
    real_run = runner.run_local

    def file_gone(jobs, todo, grid_path, settings, workers, on_done):
        (root / "grid.exr").rename(root / "moved.exr")
        assert settings["shared_grid"] is not None
        real_run(jobs, todo, grid_path, settings, workers, on_done)

    monkeypatch.setattr(runner, "run_local", file_gone)
    mapped = degrade_batch(
        [batch_inputs.images], root / "mapped", psf_grid=batch_inputs.grid, workers=2, progress=False
    )
    assert [job.status for job in mapped.jobs] == ["done"] * 3, mapped.failed[:1] and mapped.failed[0].error
    for a, b in zip(kept.jobs, mapped.jobs):
        assert all(np.array_equal(x, y) for x, y in zip(read_exr(a.output)[0].values(), read_exr(b.output)[0].values()))


def test_the_shared_grid_is_read_only_and_removed_after_the_batch(batch_inputs):
    import os

    grid = read_grid(str(batch_inputs.grid))
    with runner._shared_grid(grid) as shared:
        mapped = runner._mapped_grid(shared)
        assert np.array_equal(mapped.data, grid.data) and not mapped.data.flags.writeable
        name = shared[1]
        assert os.path.exists(f"/dev/shm/{name}")
    assert not os.path.exists(f"/dev/shm/{name}")
    del mapped  # its arrays release the block, which this process (no worker) then closes
    runner._MAPPED.pop().close()
