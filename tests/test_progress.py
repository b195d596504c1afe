"""Progress of long jobs (solas_mi.progress): a live bar on a terminal, a few plain lines in a log, and
counts that are what they say (a PSF grid counts its PSFs, mirrored ones included)."""

import io
import re
import subprocess
import sys

from solas_mi.progress import QUARTERS, Progress
from solas_mi.resources import resource_dir

PHOTO = resource_dir("scenes") / "images" / "rocket.png"


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_a_line_per_quarter_however_many_updates():
    log = io.StringIO()
    with Progress("render", 192, "spp", stream=log) as bar:
        for done in range(1, 193):
            bar(done, 192)
    lines = log.getvalue().splitlines()
    assert len(lines) == QUARTERS and "\r" not in log.getvalue()
    assert lines[-1].startswith("render: 192/192 spp (100 %")


def test_fractions_and_a_total_told_later():
    log = io.StringIO()
    bar = Progress("psf-grid", None, "PSFs", stream=log)
    for k in range(1, 11):
        bar(k * 4.8, 48)
    bar.close()
    assert log.getvalue().splitlines()[-1].startswith("psf-grid: 48/48 PSFs (100 %")


def test_a_terminal_gets_a_live_bar_and_disabled_is_silent():
    tty, log = Terminal(), io.StringIO()
    with (
        Progress("batch", 10, "images", stream=tty) as live,
        Progress("x", 10, "images", stream=log, enabled=False) as quiet,
    ):
        for _ in range(10):
            live.update()
            quiet.update()
    assert "\r" in tty.getvalue() and "10/10" in tty.getvalue()
    assert log.getvalue() == "" and quiet.done == 10


def _stderr_lines(tmp_path, *args) -> list[str]:
    """The command's stderr as written to a file (not a terminal), split on newlines and carriage returns."""
    log = tmp_path / "log.txt"
    with open(log, "w") as f:
        subprocess.run(
            [sys.executable, "-m", "solas_mi", *map(str, args)],
            cwd=tmp_path,
            stdout=subprocess.DEVNULL,
            stderr=f,
            check=True,
            timeout=300,
        )
    return re.split(r"[\r\n]+", log.read_text().strip())


def test_psf_grid_in_a_log_counts_every_psf(tmp_path):
    # 4×4 nodes at 3 wavelengths: 48 PSFs, of which the mirror symmetry computes only a few
    lines = _stderr_lines(
        tmp_path,
        "psf-grid",
        "solas-doublet",
        "--grid",
        "4x4",
        "--size",
        "32",
        "--pitch-um",
        "2",
        "--wavelengths-nm",
        "486,588,656",
        "-o",
        "g.exr",
    )
    progress = [line for line in lines if line.startswith("psf-grid:")]
    assert 1 <= len(progress) <= QUARTERS, lines
    assert re.match(r"psf-grid: 48/48 PSFs \(100 %", progress[-1]), progress


def test_render_in_a_log_writes_a_few_lines(tmp_path):
    # 160×120 px at 640 spp: six passes of the loop (2^21 samples each), each one a progress update
    lines = _stderr_lines(
        tmp_path, "render-image", "solas-doublet", PHOTO, "--sensor", "160x120", "--spp", "640", "-o", "r.exr"
    )
    progress = [line for line in lines if line.startswith("render:")]
    assert 1 <= len(progress) <= QUARTERS, lines
    assert progress[-1].startswith("render: 640/640 spp (100 %"), progress


def test_a_log_line_tells_the_time_left_at_the_rate_measured(monkeypatch):
    from solas_mi import progress

    clock = [100.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    log = io.StringIO()
    with Progress("render", 192, "spp", stream=log) as bar:
        clock[0] += 30.0  # the first quarter in 30 s: three more at that rate
        bar(48, 192)
        clock[0] += 120.0
        bar(192, 192)
    first, last = log.getvalue().splitlines()
    assert first == f"render: 48/192 spp (25 %, 30.0 s, about {30.0 * 144 / 48:.0f} s left at this rate)"
    assert last == "render: 192/192 spp (100 %, 150.0 s)"


def test_a_long_render_is_announced_without_a_duration_the_machine_may_not_keep(capsys, monkeypatch):
    """The announcement's figure came from a fixed rate of idle cores ("about 2 min" for a render that took
    far longer on a busy machine); the progress lines give the time left at the rate measured instead."""
    from solas_mi.render.commands import check_render

    monkeypatch.setattr("os.cpu_count", lambda: 2)
    check_render(1280, 960, 192, force=False)
    err = capsys.readouterr().err
    assert "1280x960 at 192 spp" in err and "time left at the rate it measures" in err
    assert not re.search(r"\d (min|s)\b", err), err


def test_a_pipe_hears_from_a_job_that_reports_nothing_for_long():
    """Progress piped (not a terminal): a line at least every QUIET_S seconds also while the job does
    not report (a grid's batch of PSFs can take minutes; a long grid's first piped line came after 14
    minutes). Here QUIET_S is 0.5 s and the job waits for its stdin: lines come while it waits."""
    import select
    import time

    code = (
        "import sys\n"
        "import solas_mi.progress as progress\n"
        "progress.QUIET_S = 0.5\n"
        "with progress.Progress('psf-grid', 10, 'PSFs') as bar:\n"
        "    sys.stdin.readline()  # the job at work, reporting nothing\n"
        "    bar(10)\n"
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        start = time.monotonic()
        heard = [p.stderr.readline() for _ in range(2) if select.select([p.stderr], [], [], 20)[0]]
        waited = time.monotonic() - start
        assert p.poll() is None, "the job ended before it was told to"
        _, rest = p.communicate("go\n", timeout=60)
    finally:
        p.kill()
    assert len(heard) == 2 and all(re.match(r"psf-grid: 0/10 PSFs \(0 %, \d+\.\d s\)$", h) for h in heard), heard
    assert waited < 30, f"{waited:.1f} s for two lines at QUIET_S = 0.5 s"
    assert rest.splitlines()[-1].startswith("psf-grid: 10/10 PSFs (100 %"), rest
