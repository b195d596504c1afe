"""How benchmarks/run_all.py records a run: how busy the machine was (a busy run is marked and sets no
README headline), and each figure compared with the recorded run's (a regression beyond 20 % between
runs on an idle machine is named)."""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "tools"))
import check_pages  # noqa: E402

run_all = check_pages.recorder()  # benchmarks/run_all.py, loaded as the docs check loads it


def results(figures: str, busy: bool = False) -> str:
    """A results file as run_all writes it, holding `figures` (figure lines)."""
    machine = run_all.Machine()
    machine.load, machine.cores, machine.others = (3.0 if busy else 0.2), 2, 0.1
    return (
        f"<!-- written by benchmarks/run_all.py; do not edit -->\n`python benchmarks/bench_x.py`, 2026-11-29, "
        f"x86_64 with 2 cores, {machine.describe()}:\n\n{figures}\n"
    )


def test_a_run_on_a_busy_machine_is_marked():
    machine = run_all.Machine()
    machine.cores, machine.others = 2, 0.0
    machine.load = 0.9
    assert machine.idle and run_all.BUSY not in machine.describe()
    machine.load = 1.1  # above half the cores: a load of 1 on 2 cores
    assert not machine.idle and run_all.BUSY in machine.describe()
    machine.load, machine.others = 0.2, 1.5  # other processes busy during the run
    assert not machine.idle


def test_a_regression_between_idle_runs_is_named():
    recorded = results("figure: grid_s = 0.40 s\n\nfigure: frames = 2.0 frames/s")
    lines, regressions = run_all.compare(recorded, "figure: grid_s = 0.50 s\nfigure: frames = 1.9 frames/s\n", True)
    assert len(lines) == 2 and len(regressions) == 1 and "grid_s" in regressions[0] and "25 % worse" in regressions[0]
    lines, regressions = run_all.compare(recorded, "figure: grid_s = 0.46 s\n", True)  # within 20 %
    assert regressions == [] and "15 % worse" in lines[0]
    lines, regressions = run_all.compare(recorded, "figure: frames = 1.5 frames/s\n", True)  # a rate: higher is better
    assert len(regressions) == 1 and "33 % worse" in regressions[0]
    lines, regressions = run_all.compare(recorded, "figure: grid_s = 0.20 s\n", True)  # faster: said so
    assert regressions == [] and "50 % better" in lines[0]


def test_a_busy_run_is_compared_but_not_judged():
    worse = "figure: grid_s = 0.90 s\n"
    for recorded, idle in (
        (results("figure: grid_s = 0.40 s", busy=True), True),
        (results("figure: grid_s = 0.40 s"), False),
    ):
        lines, regressions = run_all.compare(recorded, worse, idle)
        assert regressions == [] and "not judged" in lines[0]


def test_headlines_come_from_their_benchmark(tmp_path, monkeypatch):
    readme = tmp_path / "README.md"
    readme.write_text(
        "| grid | <!-- headline bench_a grid_s -->old<!-- /headline --> | "
        "<!-- headline bench_b grid_s -->other<!-- /headline --> |\n"
    )
    monkeypatch.setattr(run_all, "README", readme)
    assert run_all.headlines("bench_a", {"grid_s": (0.4321, "s"), "x": (1.0, "s")}) == [
        "README headline grid_s: 0.43 s"
    ]
    assert readme.read_text() == (
        "| grid | <!-- headline bench_a grid_s -->0.43 s<!-- /headline --> | "
        "<!-- headline bench_b grid_s -->other<!-- /headline --> |\n"
    )
