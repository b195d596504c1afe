"""Every list of names is a registry (`solas_mi.registry`): adding a demosaicing method, a tone curve, a
label layer or a lens reader is one registration, which the command line's choices and help, the
messages and the docs' lists then show; and no list of a registry's names is typed anywhere else."""

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "tools"))
import hooks  # noqa: E402

# The names the package ships, the one place outside the registries where tests spell them all: a
# registration lost in a refactoring shows here (every other test takes the names from the registries).
SHIPPED = {
    "solas_mi.psf.registry.METHODS": ("fraunhofer", "geometric", "render"),
    "solas_mi.convolution.methods.METHODS": ("interp", "patch"),
    "solas_mi.isp.demosaic.METHODS": ("bilinear", "Malvar2004", "Menon2007"),
    "solas_mi.isp.white.METHODS": ("daylight", "grey-world", "grey-card", "given", "none"),
    "solas_mi.isp.tone.CURVES": ("srgb", "gamma", "none", "reinhard"),
    "solas_mi.labelkinds.KINDS": ("depth", "normal", "instance", "semantic", "mask", "flow", "boxes"),
    "solas_mi.render.labels.LABELS": ("depth", "normal", "instance"),
    "solas_mi.optics.formats.READERS": (".toml", ".zmx", ".seq", ".dat"),
    "solas_mi.optics.formats.WRITERS": (".toml", ".zmx", ".dat"),
    "solas_mi.optics.coating.KINDS": ("none", "quarter_wave", "ideal", "stack"),
    "solas_mi.optics.shapes.KINDS": ("plane", "conic", "asphere", "qbfs", "ideal", "toroid", "cylinder", "biconic"),
    "solas_mi.optics.calibration.models.MODELS": (
        "opencv-pinhole",
        "opencv-fisheye",
        "ocamcalib",
        "woodscape",
        "double-sphere",
        "unified",
    ),
    "solas_mi.analysis.registry.ANALYSES": (
        "mtf",
        "mtf-field",
        "mtf50-field",
        "through-focus",
        "field-curvature",
        "distortion",
        "lateral-colour",
        "relative-illumination",
        "ray-fan",
        "opd-fan",
        "wavefront",
        "spot-diagram",
        "encircled-energy",
    ),
    "solas_mi.sensor.chain.STAGES": ("photons", "shutter", "defects", "readout", "merge", "compander"),
}

# One of each registered in a fresh process, then looked for in the parser, the messages and the docs.
ADD_ONE_OF_EACH = r"""
import json, shutil, sys
from pathlib import Path
import numpy as np
sys.path.insert(0, "docs/tools")
from solas_mi.isp import demosaic, tone
from solas_mi.optics.formats import READERS, read_toml_lens
from solas_mi.render.labels import LABELS

demosaic.METHODS.register("Dummy2026", lambda mosaic, bayer: np.zeros((*mosaic.shape, 3)), summary="a dummy demosaicer")
tone.CURVES.register("dummy-curve", lambda x: 1.0 - x, summary="a dummy tone curve")
LABELS.register("dummy-label", lambda hit: ({}, {}), layers=("dummy.V",), summary="a dummy label")
READERS.register(".dummy", read_toml_lens, summary="a dummy lens reader: our TOML under another name")

import hooks
from solas_mi.cli import build_parser, iter_commands
from solas_mi.errors import SolasError
from solas_mi.isp.commands import stage_choices
from solas_mi.isp.pipeline import ISP
from solas_mi.optics.formats import lens_path
from solas_mi.optics.lens import Lens
from solas_mi.render.labels import parse_labels

def message(call, *args):
    try:
        call(*args)
    except SolasError as exc:
        return str(exc)

helps = {" ".join(path): " ".join(p.format_help().split()) for path, p in iter_commands(build_parser())}
lens = Path(sys.argv[1]) / "lens.dummy"
shutil.copy(lens_path("solas-doublet"), lens)
print(json.dumps({
    "helps": {k: helps[k] for k in ("camera", "render", "lens info", "batch degrade")},
    "errors": [message(demosaic.check_method, "AHD"), message(tone.check_curve, "log", 2.2),
               message(parse_labels, "colour"), message(lens_path, "a.txt")],
    "used": [float(demosaic.demosaic(np.ones((4, 4)), "RGGB", "Dummy2026").sum()),
             float(tone.encode(np.array([0.25]), "dummy-curve")[0]), list(parse_labels("dummy-label,depth")),
             Lens.load(lens).surfaces == Lens.load("solas-doublet").surfaces,
             ISP(demosaic="Dummy2026", tone="dummy-curve").tone],
    "docs": [hooks.registries_reference(),
             hooks.fill_markers("{{ names solas_mi.isp.demosaic.METHODS }} / {{ table solas_mi.isp.tone.CURVES }}")],
    "choices": stage_choices(),
}))
"""


def test_adding_one_of_each_is_one_registration(tmp_path):
    """A dummy demosaicing method, tone curve, label layer and lens reader, each registered by one call and
    nothing else: the command line's help and choices, every message that lists what is allowed and the
    docs' generated lists name them, and Python takes them."""
    run = subprocess.run(
        [sys.executable, "-c", ADD_ONE_OF_EACH, str(tmp_path)], capture_output=True, text=True, cwd=ROOT
    )
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    new = ("Dummy2026", "dummy-curve", "dummy-label", ".dummy")
    assert all(name in got["helps"]["camera"] and name in got["choices"] for name in new[:2])
    assert "dummy-label" in got["helps"]["render"] and ".dummy" in got["helps"]["lens info"]
    assert ".dummy" in got["helps"]["batch degrade"]
    assert [name in error for name, error in zip(new, got["errors"])] == [True] * 4
    assert got["errors"][0] == "demosaicing method 'AHD' must be one of bilinear, Malvar2004, Menon2007, Dummy2026"
    assert got["used"] == [0.0, 0.75, ["depth", "dummy-label"], True, "dummy-curve"]
    assert all(name in got["docs"][0] for name in new) and "`dummy.V`" in got["docs"][0]
    assert got["docs"][1].startswith("bilinear, Malvar2004, Menon2007, Dummy2026 / | tone curve |")
    assert "| `dummy-curve` | a dummy tone curve |" in got["docs"][1]


def test_the_shipped_registries_hold_these_names():
    registries = hooks.registries()
    assert {name: tuple(registry) for name, registry in registries.items()} == SHIPPED


# A list: names of one registry joined by list punctuation ("a, b", "a/b", "a | b", "a or b", "`a`, `b`"),
# at least three of them (all of a registry of two): a run of two of a larger registry is an example.
GAP = re.compile(r"""[\s`'"]*(\(default\)[\s`'"]*)?(,\s*(or|and)\b|,|/|\||;|\bor\b|\band\b)[\s`'"]*""")
# Test modules that spell names on purpose: each checks, for some names, a message or a result of its own.
ALLOWED = {
    "tests/test_registries.py": "the shipped names, pinned (SHIPPED)",
    "tests/convolution/test_degrade.py": "pins the wording of the convolution method's message",
    "tests/isp/test_isp_stages.py": "pins the wording of the demosaicing and tone messages",
    "tests/isp/test_isp_chart.py": "each demosaicing method against the colour chart",
    "tests/optics/test_bad_input.py": "pins the wording of the lens-extension messages",
    "tests/optics/test_formats.py": "each writer's round trip; the writers' message",
    "tests/psf/test_caustic.py": "each PSF method at a totally reflected chief ray",
    "tests/psf/test_grid_spec.py": "pins the wording of the convolution method's message",
    "tests/render/test_labels.py": "every label through a lens, checked layer by layer; the labels' message",
    "tests/render/test_scene_file_safety.py": "each lens reader's own refusal, named by a scene",
    "tests/sensor/test_odd_files.py": "the white-balance message; each demosaicing method on the smallest tile",
}


def _lists(text: str, registries: dict) -> list[str]:
    """The lists of names of `registries` in `text` (`GAP`)."""
    found = []
    for name, registry in registries.items():
        names = sorted(registry, key=len, reverse=True)
        pattern = re.compile("|".join(rf"(?<![\w.-]){re.escape(n)}(?![\w-])" for n in names))
        run, need = [], min(len(names), 3)
        for hit in [*pattern.finditer(text), None]:
            if hit is not None and run and GAP.fullmatch(text[run[-1].end() : hit.start()]):
                run.append(hit)
                continue
            if len({h[0] for h in run}) >= need:
                found.append(f"{name.rpartition('.')[2]}: {', '.join(h[0] for h in run)}")
            run = [hit]
    return found


def _python_lists(source: str, registries: dict) -> list[tuple[int, str]]:
    """(line, list) of each string literal holding a list, and each tuple, list or set literal of names."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            found += [(node.lineno, hit) for hit in _lists(node.value, registries)]
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            values = {e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)}
            for name, registry in registries.items():
                if len(values & set(registry)) >= min(len(registry), 3):
                    found.append((node.lineno, f"{name.rpartition('.')[2]}: {sorted(values & set(registry))}"))
    return found


def test_no_list_of_names_is_typed_outside_the_registries():
    """The names of a registry listed anywhere else (a message, a help text, a docstring, a docs page, a
    tuple of names) drift when an entry is added: messages and help texts join the registry's names, the
    docs use `{{ names ... }}` / `{{ table ... }}` (`docs/tools/hooks.py`)."""
    registries = {k: r for k, r in hooks.registries().items() if len(r) >= 2}
    found = []
    for folder in ("solas_mi", "plugins", "benchmarks", "tests", "docs"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            where = path.relative_to(ROOT).as_posix()
            if where not in ALLOWED:
                found += [f"{where}:{line}: {hit}" for line, hit in _python_lists(path.read_text(), registries)]
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        if path.name != "changelog.md":  # what was, in its own words
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
                found += [f"{path.relative_to(ROOT)}:{number}: {hit}" for hit in _lists(line, registries)]
    assert not found, "names typed as a list outside their registry:\n" + "\n".join(found)


def test_the_list_finder_finds_lists_and_leaves_examples():
    registries = {k: hooks.registries()[k] for k in ("solas_mi.isp.demosaic.METHODS", "solas_mi.render.labels.LABELS")}
    assert _lists("`bilinear`, `Malvar2004` (default) or `Menon2007`", registries) == [
        "METHODS: bilinear, Malvar2004, Menon2007"
    ]
    assert _lists("--labels depth,normal,instance", registries) == ["LABELS: depth, normal, instance"]
    assert _lists("--labels depth,instance; Menon2007 costs four times Malvar2004", registries) == []
    assert _python_lists("X = ('bilinear', 'Malvar2004', 'Menon2007')\nY = {'depth': 1}\n", registries) == [
        (1, "METHODS: ['Malvar2004', 'Menon2007', 'bilinear']")
    ]
