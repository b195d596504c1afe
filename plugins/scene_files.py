"""Files a scene names — the lens file, a camera-response table — found as Mitsuba finds a scene's
files: through its file resolver (the scene's folder first), else as given (a shipped lens name, a
path relative to the working folder)."""
from __future__ import annotations

from pathlib import Path

import mitsuba as mi

from solas_mi.optics.lens import Lens
from solas_mi.render import response as responses


def resolved(name: str) -> str:
    """`name` as a path the file resolver finds, or `name` itself when it finds no file."""
    path = str(mi.file_resolver().resolve(name))
    return path if Path(path).is_file() else name


def load_lens(props: mi.Properties) -> Lens:
    """The lens of a sensor's `lens` property (default: the shipped doublet)."""
    return Lens.load(resolved(str(props.get("lens", "solas-doublet"))))


def load_response(props: mi.Properties, lens: Lens, default: str) -> responses.Response:
    """The camera response of a sensor's `response` property, checked against `lens`; a table's file
    is resolved like the scene's other files."""
    text = str(props.get("response", default))
    kind, sep, arg = text.partition(":")
    if kind.strip().lower() == "table" and arg:
        text = f"{kind}{sep}{resolved(arg)}"
    response = responses.parse(text, lens.wavelengths_nm)
    responses.check_lens(response, lens)
    return response
