"""Packaging and documentation facts that a user meets first: the licence, dependency ranges that
accept the lock (and no exact pins), a truthful requires-python, the README as a short front door
whose examples the docs run, and a site whose every page exists."""

import fnmatch
import itertools
import re
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
LOCK = {}
for line in (ROOT / "requirements.lock").read_text().splitlines():
    if line and not line.startswith("#"):
        name, _, version = line.partition("==")
        LOCK[name.lower().replace("_", "-")] = version

sys.path.insert(0, str(ROOT / "docs" / "tools"))
import check_pages  # noqa: E402
import check_reference  # noqa: E402
import hooks  # noqa: E402
import run_examples  # noqa: E402


def test_licence_is_the_declared_one():
    text = (ROOT / "LICENSE").read_text()
    assert PYPROJECT["license"] == "BSD-3-Clause"
    assert "BSD 3-Clause License" in text and "the solas-mi developers" in text
    assert "Neither the name of the copyright holder" in text  # the third clause


@pytest.mark.parametrize(
    "requirement",
    PYPROJECT["dependencies"] + [r for extra in PYPROJECT["optional-dependencies"].values() for r in extra],
)
def test_dependencies_are_ranges_that_accept_the_lock(requirement):
    req = Requirement(requirement)
    assert not any(s.operator in ("==", "===") for s in req.specifier), f"{requirement}: pin it in requirements.lock"
    locked = LOCK[req.name.lower()]
    assert req.specifier.contains(locked, prereleases=True), f"{requirement} refuses the locked {locked}"


def test_mitsuba_floor_and_python():
    mitsuba = next(Requirement(r) for r in PYPROJECT["dependencies"] if r.startswith("mitsuba"))
    assert not mitsuba.specifier.contains("3.8.0") and mitsuba.specifier.contains("3.9.0")
    assert SpecifierSet(PYPROJECT["requires-python"]).contains(".".join(map(str, sys.version_info[:3])))
    assert not SpecifierSet(PYPROJECT["requires-python"]).contains("3.10.0")  # the locked numpy has no 3.10 build


def test_docs_tools_are_locked():
    assert {"mkdocs", "mkdocs-material", "mkdocstrings", "mkdocstrings-python", "build"} <= set(LOCK)


def test_every_package_folder_is_in_the_wheel():
    """The wheel's package list is written out in pyproject.toml: a new stage folder left out of it
    imports in the repository and fails once installed (the sensor stage did, caught by the smoke run)."""
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    mapped = {ROOT / path: name for name, path in setuptools.get("package-dir", {}).items()}
    folders = {
        mapped.get(p.parent, ".".join(p.parent.relative_to(ROOT).parts)) for p in ROOT.glob("solas_mi/**/__init__.py")
    } | set(mapped.values())
    assert folders == set(setuptools["packages"]), folders ^ set(setuptools["packages"])


def test_every_data_file_is_in_the_wheel():
    """A data file beside a package's modules (lens data, sensor presets, scenes) ships only where
    pyproject's package-data names it: left out, it loads in the repository and is missing once installed."""
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    folders = {
        ROOT / setuptools.get("package-dir", {}).get(name, name.replace(".", "/")): name
        for name in setuptools["packages"]
    }
    for path in [p for folder in set(folders) for p in folder.rglob("*") if p.is_file()]:
        if path.suffix in (".py", ".pyc") or "__pycache__" in path.parts:
            continue
        owner = max((f for f in folders if f in path.parents), key=lambda f: len(f.parts))
        patterns = setuptools["package-data"].get(folders[owner], [])
        relative = path.relative_to(owner).as_posix()
        assert any(fnmatch.fnmatch(relative, pattern) for pattern in patterns), (
            f"{path.relative_to(ROOT)} is not in {folders[owner]}'s package-data {patterns}"
        )


def test_typed_and_changelog():
    assert (ROOT / "solas_mi" / "py.typed").is_file()
    assert (
        "py.typed"
        in tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["solas_mi"]
    )
    assert "## [Unreleased]" in (ROOT / "CHANGELOG.md").read_text()


def test_readme_is_a_short_front_door():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    assert "## Contents" in text
    first = run_examples.FENCE.search(text).group(2).split("\n")
    assert first[0].startswith("make demo") and first[1].startswith("make test")
    for target in re.findall(r"\]\(((?:docs/|CHANGELOG|LICENSE)[^)#]*)", text):
        assert (ROOT / target).exists(), f"README links to {target}, which does not exist"


def test_every_readme_and_guide_example_is_run_or_says_why_not():
    pages = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]
    found = [ex for page in pages for ex in run_examples.examples(page)]
    assert len(found) >= 15
    skipped = [ex for ex in found if ex.skip]
    assert all(len(ex.skip) > 20 for ex in skipped) and len(skipped) <= 1  # only `make demo` / `make test`
    stated = sum(bool(ex.expect) for ex in found) + sum(run_examples.EXPECT in ex.code for ex in found)
    assert stated >= 6


def test_every_example_of_the_site_is_run_or_says_why_not():
    """Beyond the README and the guide (details, lens files, validation, benchmarks, reference, developer
    guide): each block with commands runs, or carries a skip mark with its reason; none is in a fence
    the runner passes over (a ```text block of commands would be left out silently)."""
    found = [
        ex
        for page in sorted((ROOT / "docs").rglob("*.md"))
        if "guide" not in page.parts
        for ex in run_examples.examples(page)
    ]
    unmarked = [f"{ex.page.name}:{ex.line}" for ex in found if ex.language == "text" and not ex.skip]
    assert not unmarked, f"commands in fences that are not run: {unmarked}"
    assert all(len(ex.skip) >= run_examples.MIN_REASON for ex in found if ex.skip)
    assert sum(not ex.skip for ex in found) >= 9  # reference, plugins, render, sharpness, street


def test_the_runner_leaves_no_command_out_silently(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```text\nsolas-mi lens list\n```\n\n```text\na diagram ─► of words\n```\n")
    assert [ex.language for ex in run_examples.examples(page)] == ["text"]
    assert run_examples.run_page(page, quick=False, keep=False) == 1
    page.write_text("<!-- example: skip it needs the reader's own frames -->\n\n```text\nsolas-mi lens list\n```\n")
    assert run_examples.run_page(page, quick=False, keep=False) == 0
    page.write_text("<!-- example: skip -->\n\n```sh\nsolas-mi lens list\n```\n")
    with pytest.raises(SystemExit, match="needs its reason"):
        run_examples.examples(page)


def test_benchmark_and_validation_tables_come_from_results_files():
    problems, included, recorded = [], [], []
    for page in check_pages.pages(list(check_pages.DEFAULT_PAGES)):
        p, i, r = check_pages.check(page)
        problems, included, recorded = problems + p, included + i, recorded + r
    assert not problems
    # recorded: KrakenOS (a side environment of its own) and the 16-min crossval headline, until it is re-run
    assert len(included) >= 8 and len(recorded) <= 2


def test_the_table_check_can_fail(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        '| a | b |\n|---|---|\n| 1 | 2 |\n\n--8<-- "benchmarks/results/nothing.md"\n\n'
        '--8<-- "README.md"\n\n<!-- table: recorded -->\n\n| c |\n|---|\n\n'
        "<!-- table: recorded by a tool that runs elsewhere -->\n\n| d |\n|---|\n\n```\n| e |\n```\n"
    )
    problems, included, recorded = check_pages.check(page)
    assert [p.split(": ", 1)[1][:24] for p in problems] == [
        "a table typed into the p",
        "includes benchmarks/resu",
        "includes README.md, not ",
        "a recorded table needs i",
    ]
    assert included == [] and len(recorded) == 1


def test_the_benchmark_page_shows_no_raw_log():
    """Every results file the benchmark and validation pages include is tables and text: no library's log
    line (Mitsuba's "2026-11-26 00:16:11 WARN  [HDRFilm] ..." lines ran together into a paragraph there),
    no two lines of text that Markdown would run together."""
    log_line = re.compile(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d +[A-Z]+ +\[")
    for path in sorted((ROOT / "benchmarks" / "results").glob("*.md")):
        lines = path.read_text(encoding="utf-8").splitlines()[check_pages.HEADER_LINES :]
        assert not [line for line in lines if log_line.match(line)], path.name
        assert not [
            b for a, b in itertools.pairwise(lines) if a and b and not (a.startswith("|") and b.startswith("|"))
        ], path.name


def test_the_recorder_keeps_results_and_drops_logs():
    recorded = check_pages.recorder().recorded
    run = (
        "load average before: 1.2\n\x1b[33m2026-11-26 00:16:11 WARN  [HDRFilm] Monochrome mode enabled\x1b[0m\n"
        f"wrote {ROOT}/out/x.exr\n| a | b |\n|---|---|\n| 1 | 2 |\nload average after: 1.0\n"
    )
    assert recorded(run) == (
        "load average before: 1.2\n\nwrote out/x.exr\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\nload average after: 1.0\n"
    )
    assert recorded(recorded(run)) == recorded(run)


def test_the_reference_check_finds_what_a_site_leaves_out(tmp_path):
    """`make docs` runs docs/tools/check_reference.py on the built site; on a site whose reference
    pages are empty it names every command, public function and plugin missing."""
    for page in ("api", "cli", "plugins"):
        (tmp_path / "reference" / page).mkdir(parents=True)
        (tmp_path / "reference" / page / "index.html").write_text("<html></html>")
    assert "solas_mi.psf.grid.psf_grid" in check_reference.missing_api(tmp_path)
    assert "plugins.lens_camera.LensCamera" in check_reference.missing_api(tmp_path)
    assert "solas-mi lens list" in check_reference.missing_commands(tmp_path)
    assert "lens_camera: its documentation rendered" in check_reference.missing_plugins(tmp_path)
    assert check_reference.main([str(tmp_path)]) == 1


def test_example_runner_checks_what_a_page_states(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        '```python\nx = 2\nx + 1  # → 4\n```\n\n```sh\necho hello\n```\n\n<!-- example: expect "bye" -->\n'
        "\n<!-- example: skip not here, for a reason -->\n\n```sh\nexit 3\n```\n"
    )
    assert run_examples.run_page(page, quick=False, keep=False) == 2  # the wrong value and the missing output
    page.write_text(
        '```python\nx = 2\nx + 0.3  # → 2.2\n```\n\n```sh\necho hello bye\n```\n\n<!-- example: expect "bye" -->\n'
    )
    assert run_examples.run_page(page, quick=False, keep=False) == 1  # 2.3 is not 2.2 to the printed digit


def test_the_home_page_leads_to_every_guide_and_in_depth_page():
    """The home page's "I want to…" table names every page of the site's Guide and In depth sections (it had
    no row for the sensor, the image processor or batches)."""
    import yaml

    nav = {
        next(iter(item)): next(iter(item.values())) for item in yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]
    }
    pages = [next(iter(entry.values())) for section in ("Guide", "In depth") for entry in nav[section]]
    home = set(re.findall(r"\]\(([\w/.-]+\.md)\)", (ROOT / "docs" / "index.md").read_text()))
    assert len(pages) >= 10 and [page for page in pages if page not in home] == []


def test_every_list_of_lens_file_formats_in_the_docs_is_whole():
    """A line of the README or the site (as the site shows it: the registries' lists filled in by the docs'
    hooks) that lists lens file extensions lists those the readers are registered for
    (`optics.formats.READERS`, and our TOML), or, about converting or writing, the writers' (two pages
    left CODE V's .seq out)."""
    from solas_mi.optics.formats import READERS, WRITERS

    readable, lists = {".toml", *READERS}, 0
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        for number, line in enumerate(hooks.fill_markers(page.read_text(encoding="utf-8")).splitlines(), start=1):
            named = set(re.findall(r"(\.(?:toml|zmx|seq|dat))\b", line)) & readable
            if len(named) >= 3:
                lists += 1
                whole = set(WRITERS) if re.search(r"convert|writ|save", line) else readable
                assert named == whole, f"{page.relative_to(ROOT)}:{number}: {sorted(named)}, not {sorted(whole)}"
    assert lists >= 4


def test_every_page_of_the_site_exists():
    nav = re.findall(r":\s*([\w/.-]+\.md)\s*$", (ROOT / "mkdocs.yml").read_text(), re.M)
    generated = {"reference/cli.md", "reference/api.md", "reference/registries.md"}  # docs/tools/hooks.py writes them
    assert len(nav) >= 20
    for page in nav:
        assert page in generated or (ROOT / "docs" / page).is_file(), page


def test_the_reference_check_names_each_public_name_missing(tmp_path, monkeypatch):
    """The public API (`hooks.public_api`: every name of solas_mi's and each subpackage's `__all__`) must be
    on the built API page by the path of its definition; a package without `__all__` is named too."""
    (tmp_path / "reference" / "api").mkdir(parents=True)
    (tmp_path / "reference" / "api" / "index.html").write_text('<h4 id="solas_mi.optics.lens.Lens"></h4>')
    missing = check_reference.missing_public(tmp_path)
    assert "solas_mi.psf.psf_grid (solas_mi.psf.grid.psf_grid)" in missing
    assert "solas_mi.convolution.DegradeSpec (solas_mi.convolution.spec.DegradeSpec)" in missing
    assert not [m for m in missing if m.startswith(("solas_mi.Lens ", "solas_mi.optics.Lens "))]
    real = hooks.declared_all
    monkeypatch.setattr(hooks, "declared_all", lambda package: None if package == "solas_mi.isp" else real(package))
    assert "solas_mi.isp: no __all__ (the package's public names)" in check_reference.missing_public(tmp_path)


def test_the_public_api_resolves_through_lazy_exports():
    """`hooks.defining_module` follows a package's imports and lazy exports to the module that defines a name."""
    assert hooks.defining_module("solas_mi", "Lens") == "solas_mi.optics.lens"
    assert hooks.defining_module("solas_mi", "SolasError") == "solas_mi.errors"
    assert hooks.defining_module("solas_mi.psf", "PSFGrid") == "solas_mi.psf.grid_file"
    with pytest.raises(LookupError, match="solas_mi.psf.nothing"):
        hooks.defining_module("solas_mi.psf", "nothing")


def test_the_docstring_examples_run_and_can_fail(tmp_path, monkeypatch):
    """With the docs folder, run_examples runs the docstrings' Examples of the API reference's modules (doctest,
    a fresh folder per module): a wrong stated output fails the module."""
    assert {"solas_mi.optics.lens", "solas_mi.psf.grid"} <= set(run_examples.docstring_modules())
    module = tmp_path / "stated_example.py"
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    monkeypatch.setattr(run_examples, "docstring_modules", lambda: ["stated_example"])
    module.write_text('def double(x):\n    """Twice x.\n\n    >>> double(2)\n    5\n    """\n    return 2 * x\n')
    assert run_examples.run_docstrings(keep=False) == 1
    module.write_text('def double(x):\n    """Twice x.\n\n    >>> double(2)\n    4\n    """\n    return 2 * x\n')
    assert run_examples.run_docstrings(keep=False) == 0
