"""Where a batch's items run: local worker processes (`run_local`) or a Dask cluster (`run_dask`).
Both run `work.run_job` on each item (with the one PSF grid of a degrade batch; a render batch has
none), and hand each finished item (done or failed) to `on_done` as it comes.

Local: `workers` spawned processes, each mapping the batch's grid from shared memory (or reading its
file where shared memory lacks the room) and then taking one item at a time over its own pipe, so the batch always knows which item each process holds. A process that
dies (killed, out of memory) loses only that item: it is retried in a fresh process up to
MAX_ATTEMPTS times, then reported failed. Interrupted (Ctrl-C, SIGTERM), the batch sends every
worker SIGTERM at once, then waits for them all (stopped one after another, the waits added up: a
tester's batch took 7.2 s); each turns it into an interruption, so the temporary files of the item
it was writing are removed and no partial output is left, and ends without the interpreter's
teardown. The workers ignore Ctrl-C, which a terminal sends to every process of the job: the batch
alone decides how they stop (a worker's own Ctrl-C during its start printed a traceback).

Dask: the grid is scattered to every worker once; the scheduler retries an item whose worker died
(`distributed.scheduler.allowed-failures`) and then reports it failed (KilledWorker).
"""
from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time
from collections import deque
from collections.abc import Callable
from contextlib import contextmanager
from multiprocessing import resource_tracker
from multiprocessing.connection import wait
from typing import TYPE_CHECKING, Any

from .. import imageio
from ..errors import SolasError
from ..interrupts import raise_outside_imports
from . import work
from .jobs import Job
from .work import run_job

if TYPE_CHECKING:
    from ..psf.depth import DepthGrid
    from ..psf.grid import PSFGrid
    from .jobs import Manifest

DASK_SCHEMES = ("tcp", "tls", "ucx")  # the comm protocols of distributed that take HOST:PORT
MAX_ATTEMPTS = 3
STOP_WAIT_S = 10.0  # how long interrupted workers get to remove their temporary files


def check_dask(dask: str | None) -> None:
    """Nothing, or SolasError unless `dask` (None: local processes) is "local" or a scheduler address
    SCHEME://HOST:PORT (tcp, tls, ...) or HOST:PORT, the port a number from 1 to 65535: checked before
    any work, since the scheduler is only reached when the items start."""
    from urllib.parse import urlsplit

    if dask is None or dask == "local":
        return
    ok = isinstance(dask, str) and not any(c.isspace() for c in dask)
    if ok:
        parts = urlsplit(dask if "://" in dask else f"tcp://{dask}")
        try:
            port = parts.port
        except ValueError:
            port = None
        ok = (parts.scheme in DASK_SCHEMES and bool(parts.hostname) and port is not None and port > 0
              and parts.path in ("", "/") and not parts.query and not parts.fragment)
    if not ok:
        raise SolasError(f"--dask {dask!r} must be a scheduler address, tcp://HOST:PORT of a running `dask "
                         f"scheduler` (or {', '.join(s + '://' for s in DASK_SCHEMES[1:])} HOST:PORT), or local for "
                         "a LocalCluster")


def _interrupt(signum, frame) -> None:
    work.STOPPING = True  # an item failing from here on was interrupted (`work.run_job`)
    raise_outside_imports(KeyboardInterrupt(), frame)


@contextmanager
def _shared_grid(grid: PSFGrid | DepthGrid | None):
    """The block with `grid`'s arrays copied into one block of shared memory, which the local workers map
    (`_mapped_grid`) instead of each reading the grid file (0.7 CPU-s and 315 MB each for a 32×32×3 grid of
    160 px): what they need to map it (its pickle without the arrays, the block's name and each array's place),
    or None without a grid or where shared memory lacks the room (tmpfs over its size kills its writer)."""
    import pickle
    from multiprocessing import shared_memory

    arrays: list = []
    payload = pickle.dumps(grid, protocol=5, buffer_callback=arrays.append) if grid is not None else b""
    views = [a.raw() for a in arrays]
    size = sum(v.nbytes for v in views)
    try:
        room = os.statvfs("/dev/shm")
        free = room.f_bavail * room.f_frsize
    except OSError:  # no /dev/shm
        free = 0
    if grid is None or not views or free < 2 * size:
        yield None
        return
    block = shared_memory.SharedMemory(create=True, size=size)
    try:
        places, at = [], 0
        for v in views:
            block.buf[at : at + v.nbytes] = v
            places.append((at, v.nbytes))
            at += v.nbytes
        yield payload, block.name, places
    finally:
        block.close()
        block.unlink()


def _mapped_grid(shared: tuple[bytes, str, list[tuple[int, int]]]) -> PSFGrid | DepthGrid:
    """The batch's grid on the shared memory `_shared_grid` filled, read-only (the workers share it); the block
    stays mapped while the process lives."""
    import pickle
    from multiprocessing import shared_memory

    payload, name, places = shared
    block = shared_memory.SharedMemory(name=name)
    _MAPPED.append(block)
    view = block.buf.toreadonly()
    return pickle.loads(payload, buffers=[view[at : at + n] for at, n in places])


_MAPPED: list = []  # this worker's shared memory blocks (`_mapped_grid`)


def _serve(conn, grid_path: str | None, settings: dict[str, Any]) -> None:
    """A local worker process: map the batch's grid (settings' "shared_grid") or read it (if any) once, then
    do the items sent until None comes."""
    from ..psf.depth import read_grid

    signal.signal(signal.SIGTERM, _interrupt)  # interrupted, not killed: temporary files are removed
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the batch stops its workers (a Ctrl-C pending is dropped)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # blocked since its start (`_sigint_blocked`)
    imageio.SWEEP_STALE = False  # the batch swept the folder it holds (`run_batch`)
    try:
        shared = settings.get("shared_grid")
        # over field, or field and distance
        grid = _mapped_grid(shared) if shared else read_grid(grid_path) if grid_path is not None else None
        while (job := conn.recv()) is not None:
            conn.send(run_job(job, grid, grid_path, settings))
            if work.STOPPING:  # the item was interrupted (and said so): end now
                break
    except (KeyboardInterrupt, EOFError):
        pass
    sys.stdout.flush()
    sys.stderr.flush()
    # its items' files are written and their results sent: the interpreter's teardown (Dr.Jit's, Mitsuba's)
    # has nothing to save, and took a second under load, which an interrupted batch waited for
    os._exit(0)


@contextmanager
def _sigint_blocked():
    """The block with SIGINT blocked in this thread: a process started in it starts so (the mask passes
    through fork and exec) until `_serve` ignores it; this process still receives its own Ctrl-C
    (through another thread, or when the block ends)."""
    blocked = signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        if not blocked:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


class _Worker:
    def __init__(self, ctx, grid_path: str | None, settings: dict[str, Any]):
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_serve, args=(child, grid_path, settings), daemon=True)
        # a process's first start also starts multiprocessing's resource tracker, which unblocks SIGINT as it
        # ends (its guard of its own start): started first, it cannot undo the block the worker starts in
        resource_tracker.ensure_running()
        with _sigint_blocked():
            self.proc.start()
        child.close()
        self.index: int | None = None  # the item it holds

    def give(self, index: int, job: Job) -> None:
        self.index = index
        try:
            self.conn.send(job)
        except OSError:  # the process has died: the loop sees it end and retries the item
            pass

    def ask_to_stop(self, now: bool) -> None:
        """SIGTERM when `now` (its item ends interrupted), else no more items (it ends when idle)."""
        if self.proc.is_alive():
            if now:
                self.proc.terminate()
            else:
                try:
                    self.conn.send(None)
                except OSError:
                    self.proc.terminate()

    def wait_stopped(self, deadline: float) -> None:
        """Wait for the process to end until `deadline` (`time.monotonic`), then kill it."""
        self.proc.join(max(0.0, deadline - time.monotonic()))
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()

    def last_result(self) -> Job | None:
        """The result of its item if the (stopped) process sent it before it ended."""
        try:
            result = self.conn.recv() if self.conn.poll() else None
        except (EOFError, OSError):
            result = None
        self.conn.close()
        return result if isinstance(result, Job) else None


def _stop_all(pool: list[_Worker], now: bool) -> None:
    """Ask every worker of `pool` to stop, then wait for them all together, STOP_WAIT_S at most."""
    for w in pool:
        w.ask_to_stop(now)
    deadline = time.monotonic() + STOP_WAIT_S
    for w in pool:
        w.wait_stopped(deadline)


def run_local(jobs: list[Job], todo: list[int], grid_path: str | None, settings: dict[str, Any], workers: int,
              on_done: Callable[[int, Job], None]) -> None:
    """Items `todo` (indices into `jobs`) on `workers` local processes."""
    ctx = multiprocessing.get_context("spawn")  # never fork a process that may hold Dr.Jit's threads
    queue = deque(todo)
    pool = [_Worker(ctx, grid_path, settings) for _ in range(min(workers, len(todo)))]
    interrupted = True
    try:
        for w in pool:
            if queue:
                i = queue.popleft()
                w.give(i, jobs[i])
        while any(w.index is not None for w in pool):
            busy = [w for w in pool if w.index is not None]
            wait([w.conn for w in busy] + [w.proc.sentinel for w in busy])
            for n, w in enumerate(pool):
                if w.index is None:
                    continue
                i = w.index
                try:
                    if not w.conn.poll():
                        if w.proc.is_alive():
                            continue
                        raise EOFError
                    result = w.conn.recv()
                except (EOFError, OSError):  # the process died holding item i
                    jobs[i].attempts += 1
                    w.index = None
                    _stop_all([w], now=True)
                    w.conn.close()
                    code = w.proc.exitcode
                    pool[n] = w = _Worker(ctx, grid_path, settings)
                    if jobs[i].attempts < MAX_ATTEMPTS:
                        queue.appendleft(i)
                    else:
                        jobs[i].status = "failed"
                        jobs[i].error = (f"its worker process died {jobs[i].attempts} times "
                                         f"(exit status {code}); killed or out of memory?")
                        on_done(i, jobs[i])
                else:
                    w.index = None
                    on_done(i, result)
                if queue:
                    i = queue.popleft()
                    w.give(i, jobs[i])
        interrupted = False
    finally:
        _stop_all(pool, now=interrupted)
        for w in pool:
            result = w.last_result()
            if w.index is not None and result is None:  # its worker stopped before it ended
                result = jobs[w.index]
                result.status, result.error = "interrupted", "the batch was interrupted"
            if result is not None and w.index is not None:  # finished (or stopped) as the batch was interrupted
                on_done(w.index, result)


def run_dask(jobs: list[Job], todo: list[int], grid: PSFGrid | DepthGrid | None, grid_path: str | None, settings: dict[str, Any],
             address: str, workers: int, on_done: Callable[[int, Job], None]) -> None:
    """Items `todo` on the Dask scheduler at `address`, or on a LocalCluster of `workers` processes
    started for this batch when `address` is "local"."""
    import dask
    from distributed import Client, LocalCluster, as_completed

    cluster = None
    try:
        if address == "local":
            # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which turns off glibc's adaptive
            # mmap threshold: every large temporary is mapped afresh (measured: degrade 0.5 s → 1.1 s)
            with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
        try:
            client = Client(cluster if cluster is not None else address, timeout="20s")
        except OSError as exc:
            raise SolasError(f"cannot reach the Dask scheduler {address!r} ({exc}); give tcp://HOST:PORT "
                             "of a running `dask scheduler`, or local") from None
        with client:
            shared = client.scatter(grid, broadcast=True) if grid is not None else None
            futures = {client.submit(run_job, jobs[i], shared, grid_path, settings, pure=False): i for i in todo}
            for future in as_completed(futures):
                i = futures.pop(future)
                try:
                    result = future.result()
                except Exception as exc:  # the item's worker died too often (KilledWorker) or was lost
                    jobs[i].status, jobs[i].error = "failed", f"{type(exc).__name__}: {exc}"
                    result = jobs[i]
                # released, so that a worker dying later does not make the scheduler redo (rewrite) it
                future.release()
                on_done(i, result)
    finally:
        if cluster is not None:
            cluster.close()



def worker_threads(workers: int, dask: str | None) -> int | None:
    """The threads each of a batch's `workers` runs (`threads.use_share`): its share of this machine's cores where
    they share them (local processes, a Dask LocalCluster); None on a Dask scheduler's (its machines' own)."""
    from ..threads import share

    return share(workers) if dask in (None, "local") else None


def run_batch(manifest: Manifest, todo: list[int], grid: PSFGrid | DepthGrid | None, grid_path: str | None,
              settings: dict[str, Any], workers: int, dask: str | None, progress: str | None) -> None:
    """Items `todo` of `manifest.jobs` on `workers` local processes or the Dask scheduler `dask`, the
    manifest saved as they finish (and at the end, also when interrupted), a progress bar of the unit
    `progress` ("image", "render"; None: no bar). The output folder is held for the whole run
    (`outputs.hold_folder`: a second batch on it is refused, naming this one); the temporary files
    that killed runs or workers left there are removed before and after. Each worker runs its share of the
    cores' threads (`worker_threads`, settings' "threads")."""
    from ..outputs import hold_folder, remove_temporaries
    from ..progress import Progress

    jobs = manifest.jobs
    settings = {**settings, "threads": worker_threads(workers, dask)}
    with hold_folder(manifest.path.parent, f"batch {manifest.header.get('kind')} {manifest.header.get('batch_id')}"):
        remove_temporaries(manifest.path.parent)
        manifest.save()
        bar = Progress(f"batch {manifest.header.get('kind')}", len(jobs), f"{progress}s",
                       initial=len(jobs) - len(todo), enabled=bool(progress))

        def on_done(i: int, job: Job) -> None:
            jobs[i] = job
            manifest.save(force=False)
            if job.status != "interrupted":  # stopped, not done: not progress
                bar.update()

        try:
            if todo and dask is None:
                with _shared_grid(grid) as shared:
                    run_local(jobs, todo, grid_path, {**settings, "shared_grid": shared}, workers, on_done)
            elif todo:
                run_dask(jobs, todo, grid, grid_path, settings, dask, workers, on_done)
        finally:
            bar.close()
            remove_temporaries(manifest.path.parent)  # a worker killed while writing cannot remove its own
            manifest.save()
