"""The figures a benchmark states for comparison run to run (`run_all.py`): one line each on stdout,
`figure: NAME = VALUE UNIT`, kept in the results file as text. A figure in seconds is better lower, one
in a rate (…/s) better higher; `run_all.py` compares each with the same figure of the recorded run and
calls a change for the worse of more than REGRESSION a regression.
"""

from __future__ import annotations

import re

FIGURE = re.compile(r"^figure: (?P<name>[A-Za-z0-9_.-]+) = (?P<value>[0-9.eE+-]+) (?P<unit>\S+)$")
REGRESSION = 0.20  # a figure 20 % worse than the recorded run's
IDLE_LOAD_PER_CORE = 0.5  # a run is on an idle machine when the load average before it and the other
# processes' use during it stay within half the cores (a load of 1 on 2 cores); else its timings are
# marked and never a headline


def figure(name: str, value: float, unit: str) -> None:
    """Print figure `name` (a word: letters, digits, _ . -) of `value` in `unit` ("s", "frames/s", ...)."""
    print(f"figure: {name} = {value:.4g} {unit}", flush=True)


def figures(text: str) -> dict[str, tuple[float, str]]:
    """The figures of a run's output or a results file: name → (value, unit)."""
    return {m["name"]: (float(m["value"]), m["unit"]) for m in map(FIGURE.match, text.splitlines()) if m}


def worse(old: float, new: float, unit: str) -> float:
    """How much worse `new` is than `old` (a fraction; negative: better): times lower, rates higher."""
    return new / old - 1.0 if not unit.endswith("/s") else old / new - 1.0
