"""Every long step answers a signal within about a second: renders run in passes of bounded time
(`render.loop.STEPS_PER_PASS`, `render.stock.SAMPLES_PER_PASS`, the render PSF's ray chunks) and a
signal is answered between them; an interruption that a library reports as its own error (a scene's
plugin interrupted while Mitsuba loads it) is still an interruption, not an error."""

import importlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from strict_json import strict_loads

from solas_mi import cli
from solas_mi.batch import runner, work
from solas_mi.cli import main
from solas_mi.errors import SolasError, plugin_error
from solas_mi.resources import resource_dir

PHOTO = resource_dir("scenes") / "images" / "rocket.png"
STOP_S = 2.0  # a signal answered within about a second (a pass), with room for a loaded machine
# a batch: its worker ends its pass, then the batch; 0.5-0.6 s on the shared 2-core machine at load 10
# (1.3-2.2 s while each worker's interpreter tore down Dr.Jit and Mitsuba first, 2.34 s seen by a tester)
BATCH_STOP_S = 6.0


def solas(*args, cwd) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "solas_mi", *map(str, args)],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, TMPDIR=str(cwd)),
    )


def stop(p: subprocess.Popen, sig) -> tuple[float, str]:
    """Seconds from `sig` to the process's end, and its stderr."""
    start = time.monotonic()
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    return time.monotonic() - start, err


def test_an_interruption_reported_by_a_library_is_an_interruption(tmp_path, monkeypatch, capsys):
    """SIGTERM arriving while Mitsuba builds a scene's plugin: Mitsuba turns the exception into its own
    error, which would read as a scene that cannot load (exit 2); it is the interruption (exit 143)."""
    from solas_mi.render import user_scene

    def loading(*args, **kwargs):
        try:
            os.kill(os.getpid(), signal.SIGTERM)  # raised in the plugin's constructor, as Mitsuba calls it
            time.sleep(5)
        except BaseException as exc:  # Mitsuba's parser: any exception of a plugin becomes a RuntimeError
            raise plugin_error(RuntimeError(f"failed to instantiate: {type(exc).__name__}"), "cannot load scene")  # noqa: B904 -- as Mitsuba, which chains nothing
        raise SolasError("not interrupted")

    monkeypatch.setattr(user_scene, "load", loading)
    scene = resource_dir("scenes") / "solas_doublet" / "scene.xml"
    assert main(["render", str(scene), "--spp", "4", "-o", str(tmp_path / "r.exr")]) == 143
    err = capsys.readouterr().err
    assert "terminated; no output was left half-written" in err and "cannot load" not in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_batch_render_stops_within_a_pass(tmp_path):
    """SIGTERM 8 s into the second of two items (a short one, then a long one): the batch ends within
    BATCH_STOP_S, the long item is recorded interrupted, the short one done, and nothing half-written is left.
    The lens's paths take 14 interactions: one pass of the former 2^21 samples took 3-25 s."""
    image = tmp_path / "f.png"
    image.write_bytes(PHOTO.read_bytes())
    out = tmp_path / "out"
    p = solas(
        "batch",
        "render",
        image,
        "--lens",
        "wide-angle-22mm",
        "--sensor",
        "160x120",
        "--spp",
        "16,256",
        "-o",
        out,
        "--workers",
        "1",
        "--quiet",
        cwd=tmp_path,
    )
    deadline = time.monotonic() + 300
    while not (out / "f_spp16.exr").exists() and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(8.0)  # past the second item's scene load and first compile, into its passes
    assert p.poll() is None, "the batch ended before it could be interrupted"
    seconds, err = stop(p, signal.SIGTERM)
    assert p.returncode == 143, err
    assert seconds < BATCH_STOP_S, f"{seconds:.2f} s from SIGTERM to the end"
    items = {Path(i["output"]).name: i["status"] for i in strict_loads((out / "batch.json").read_text())["items"]}
    assert items == {"f_spp16.exr": "done", "f_spp256.exr": "interrupted"}, items
    assert sorted(f.name for f in out.iterdir()) == ["batch.json", "f_spp16.exr", "f_spp16.png"]
    assert not [f for f in tmp_path.iterdir() if f.name.startswith("solas-")]  # no scene folder left


@pytest.mark.slow
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_render_psf_stops_within_a_chunk(tmp_path, sig, code):
    """The render PSF traces 9 M rays at each of three wavelengths (one wavefront each before: 10-40 s); a
    signal while it traces ends it within STOP_S."""
    p = solas(
        "psf",
        "solas-doublet",
        "--psf-method",
        "render",
        "--rays",
        "3000",
        "--field-deg",
        "0,1",
        "--wavelengths-nm",
        "486,550,656",
        "--size",
        "64",
        "-o",
        "p.exr",
        cwd=tmp_path,
    )
    time.sleep(12.0)  # past the start (imports, the lens's chief rays, the entrance grid) into the tracing
    assert p.poll() is None, "the PSF was finished before it could be interrupted"
    seconds, err = stop(p, sig)
    assert p.returncode == code and "no output was left half-written" in err, err
    assert seconds < STOP_S, f"{seconds:.2f} s from the signal to the end"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_render_image_stops_within_a_pass(tmp_path):
    """A signal one second after the first progress report (the first pass done: the scene loaded and
    its kernel compiled) ends the render within STOP_S. The lens's paths take 14 interactions: a pass
    of the former 2^21 samples took 3-25 s (10.5 s from Ctrl-C to the end, measured)."""
    p = solas(
        "render-image",
        "wide-angle-22mm",
        PHOTO,
        "--fov-deg",
        "30",
        "--sensor",
        "160x120",
        "--spp",
        "1024",
        "-o",
        "r.exr",
        cwd=tmp_path,
    )
    assert p.stderr.read(1), "no progress report"
    time.sleep(1.0)
    assert p.poll() is None, "the render was finished before it could be interrupted"
    seconds, err = stop(p, signal.SIGINT)
    assert p.returncode == 130 and "no output was left half-written" in err, err
    assert seconds < STOP_S, f"{seconds:.2f} s from the signal to the end"
    assert list(tmp_path.iterdir()) == []


def _module_that_signals(folder: Path, name: str, sig) -> None:
    """A module whose body sends `sig` to its own process half-way and then goes on (`done` set last)."""
    (folder / f"{name}.py").write_text(
        "import os, signal\n"
        f"os.kill(os.getpid(), signal.{sig.name})\n"
        "later = [i * i for i in range(1000)]  # the handler runs by here\n"
        "done = True\n"
    )


@pytest.mark.parametrize(
    "handler, sig, exception",
    [
        (cli._stop, signal.SIGINT, KeyboardInterrupt),
        (cli._stop, signal.SIGTERM, cli.Terminated),
        (runner._interrupt, signal.SIGTERM, KeyboardInterrupt),  # a batch's worker process
    ],
)
def test_a_signal_during_an_import_is_raised_once_the_import_is_whole(tmp_path, monkeypatch, handler, sig, exception):
    """A signal arriving while a module is imported: the import finishes (the module whole, in
    `sys.modules`) and the interruption is raised in the frame that imported it, before its next step.
    Raised inside the import, it left a module half-made; Dr.Jit's extension turned it into an
    ImportError (exit 1, see the next test)."""
    name = f"signalling_{handler.__name__.strip('_')}_{sig.name.lower()}"
    _module_that_signals(tmp_path, name, sig)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(work, "STOPPING", False)
    trace = sys.gettrace()
    previous = signal.signal(sig, handler)
    steps = []
    try:
        with pytest.raises(exception):  # noqa: PT012 -- the step after the import must not run
            importlib.import_module(name)
            steps.append("after the import")
    finally:
        signal.signal(sig, previous)
        module = sys.modules.pop(name, None)
    assert module is not None and module.done and steps == []
    assert sys.gettrace() is trace


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_drjit_loads_is_an_interruption(tmp_path, sig, code):
    """The signal delivered exactly while Dr.Jit's extension initialises (its C++ imports drjit.llvm):
    exit 130 / 143 and nothing written; it was an ImportError, then a NameError in Dr.Jit (exit 1), the
    race that testers hit by timing (Ctrl-C a few seconds into `psf-grid` on a loaded machine)."""
    code_text = (
        "import os, signal, sys\n"
        "class SignalOnLookup:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'drjit.llvm':\n"
        f"            os.kill(os.getpid(), signal.{sig.name})\n"
        "        return None\n"
        "sys.meta_path.insert(0, SignalOnLookup())\n"
        "from solas_mi.cli import main\n"
        "sys.exit(main(['psf-grid', 'solas-doublet', '--grid', '4x4', '--size', '32', '-o', 'g.exr']))\n"
    )
    p = subprocess.run([sys.executable, "-c", code_text], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert p.returncode == code and "Traceback" not in p.stderr, p.stderr
    assert "no output was left half-written" in p.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_the_commands_load_is_an_interruption(tmp_path, sig, code):
    """Ctrl-C or SIGTERM in the first second, while the command line imports every stage's commands
    (NumPy among them): exit 130 / 143 with one line. Our handlers came only after that: a
    KeyboardInterrupt traceback of 20 lines (SIGINT), a silent kill (SIGTERM)."""
    code_text = (
        "import os, signal, sys\n"
        "class SignalOnLookup:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'numpy':\n"
        f"            os.kill(os.getpid(), signal.{sig.name})\n"
        "        return None\n"
        "sys.meta_path.insert(0, SignalOnLookup())\n"
        "from solas_mi.cli import main\n"
        "sys.exit(main(['sensors']))\n"
    )
    p = subprocess.run([sys.executable, "-c", code_text], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert p.returncode == code and "Traceback" not in p.stderr, p.stderr
    assert p.stderr.strip().splitlines() == [
        f"solas-mi: {'interrupted' if code == 130 else 'terminated'}; no output was left half-written"
    ], p.stderr


def _ends_late(ready, seconds: float) -> None:
    """A process that needs `seconds` to end once told (SIGTERM), as a worker ends its pass."""
    signal.signal(signal.SIGTERM, lambda *_: (time.sleep(seconds), os._exit(0)))
    ready.set()
    time.sleep(120)


def test_interrupted_workers_are_stopped_together(tmp_path):
    """The batch tells all its workers to stop, then waits for them: its stop takes one worker's time
    to end, not the sum (one after another, a tester's batch took 7.2 s to obey SIGTERM)."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    count, seconds = 3, 1.5
    pool = []
    for _ in range(count):
        ready = ctx.Event()
        worker = object.__new__(runner._Worker)  # a worker's process and pipe, without `_serve`
        worker.proc = ctx.Process(target=_ends_late, args=(ready, seconds), daemon=True)
        worker.proc.start()
        worker.conn, worker.index = None, None
        assert ready.wait(120)
        pool.append(worker)
    start = time.monotonic()
    runner._stop_all(pool, now=True)
    took = time.monotonic() - start
    assert all(w.proc.exitcode == 0 for w in pool)  # each ended by itself, none killed
    assert took < (count - 1) * seconds, f"{took:.2f} s to stop {count} workers that take {seconds} s each"


def test_the_first_worker_of_a_process_leaves_ctrl_c_to_the_batch(tmp_path):
    """The first worker a process starts also starts multiprocessing's resource tracker, which unblocked
    SIGINT as it ended (its own guard): that worker started with Ctrl-C live, and a Ctrl-C during its
    start killed it (exit -SIGINT, the next test alone failed so). In a fresh interpreter, as a batch's."""
    script = tmp_path / "first_worker.py"
    script.write_text(
        "import multiprocessing, os, signal, time\n"
        "from solas_mi.batch import runner\n"
        "if __name__ == '__main__':\n"
        "    worker = runner._Worker(multiprocessing.get_context('spawn'), None, {})\n"
        "    for _ in range(20):  # while it starts and while it waits for items\n"
        "        os.kill(worker.proc.pid, signal.SIGINT)\n"
        "        time.sleep(0.1)\n"
        "    alive = worker.proc.is_alive()\n"
        "    runner._stop_all([worker], now=False)\n"
        "    print(alive, worker.proc.exitcode)\n"
    )
    p = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert p.stdout.split() == ["True", "0"] and "Traceback" not in p.stderr, (p.stdout, p.stderr[-500:])


def test_workers_leave_ctrl_c_to_the_batch(capfd):
    """A terminal's Ctrl-C reaches every process of the job, the workers too: a worker neither dies
    nor prints a traceback (one starting up printed one), and ends when the batch tells it to."""
    import multiprocessing

    worker = runner._Worker(multiprocessing.get_context("spawn"), None, {})
    for _ in range(20):  # while it starts and while it waits for items
        os.kill(worker.proc.pid, signal.SIGINT)
        time.sleep(0.1)
    assert worker.proc.is_alive()
    runner._stop_all([worker], now=False)
    assert worker.proc.exitcode == 0
    assert "Traceback" not in capfd.readouterr().err
