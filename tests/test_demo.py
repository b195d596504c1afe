"""`make demo` says what it does: each step is announced before it runs, naming the files it writes, and no
step runs unannounced (the commands are recorded, not run)."""

import fnmatch
import json
import re

from solas_mi import demo

ANNOUNCED = re.compile(r"== demo step (\d+) of (\d+): (.*)\n   writes \(in (.*)\): (.*)")


def patterns(writes: str) -> list[str]:
    """The file patterns an announcement names: "a.exr|png (what it holds), b/*.png" → a.exr, a.png, b/*.png."""
    found = []
    for item in re.split(r"[;,] ", re.sub(r" \([^)]*\)", "", writes)):
        stem, _, more = item.strip().partition("|")
        found += [stem, *(stem.rsplit(".", 1)[0] + "." + ext for ext in more.split("|") if more)]
    return found


def test_each_step_is_announced_before_it_runs_naming_what_it_writes(tmp_path, monkeypatch, capsys):
    import solas_mi.imageio
    import solas_mi.validation.flare_views
    import solas_mi.validation.sheet

    printed, calls = [], []  # what the demo printed; (command, the announcements printed before it)

    def record(argv):
        printed.append(capsys.readouterr().out)
        calls.append((argv, ANNOUNCED.findall("".join(printed))))

    monkeypatch.setattr(demo, "cli", record)
    monkeypatch.setattr(demo, "read_image", lambda *a, **k: None)
    monkeypatch.setattr(demo, "camera_sheet", lambda *a, **k: None)
    monkeypatch.setattr(solas_mi.imageio, "read_exr", lambda *a, **k: ({}, {"labels": {}}))
    monkeypatch.setattr(solas_mi.validation.sheet, "comparison_sheet", lambda *a, **k: None)
    monkeypatch.setattr(solas_mi.validation.flare_views, "flare_sheet", lambda *a, **k: None)
    demo.run(tmp_path)
    printed.append(capsys.readouterr().out)
    announced = ANNOUNCED.findall("".join(printed))
    assert [(int(k), int(n)) for k, n, *_ in announced] == [
        (k, len(demo.steps())) for k in range(1, len(announced) + 1)
    ]
    assert len(announced) == len(demo.steps()) and all(folder == str(tmp_path) for *_, folder, _ in announced)
    commands = {}
    for argv, before in calls:
        assert before, f"solas-mi {' '.join(argv)} runs before any step is announced"
        commands.setdefault(len(before), []).append(argv)
        if "-o" in argv:
            written = str(argv[argv.index("-o") + 1]).removeprefix(str(tmp_path) + "/")
            named = patterns(before[-1][4])
            assert any(fnmatch.fnmatch(written, p) or p.startswith(written + "/") for p in named), (written, named)
    assert set(commands) == set(range(1, len(announced) + 1))  # every step runs a command, after its announcement
    assert any(argv[:2] == ["experiment", "street"] for argv in commands[len(announced)])
    summary = json.loads("".join(printed)[("".join(printed)).rindex("\n{") + 1 :])
    assert set(summary) == {"results"} | {name for _, writes, _ in demo.steps() for name in writes}
