"""Files a scene names — the lens file, a camera-response table — found as Mitsuba finds a scene's
files: through its file resolver (the scene's folder first), else as given (a shipped lens name, a
path relative to the working folder)."""

from __future__ import annotations

from pathlib import Path

import mitsuba as mi

from solas_mi.errors import SolasError
from solas_mi.optics.formats import lens_path
from solas_mi.optics.lens import Lens
from solas_mi.render import response as responses


def resolved(name: str) -> str:
    """`name` as a path the file resolver finds, or `name` itself when it finds no file."""
    path = str(mi.file_resolver().resolve(name))
    return path if Path(path).is_file() else name


def load_lens(props: mi.Properties) -> Lens:
    """The lens of a sensor's `lens` property (default: the shipped doublet). A lens file the scene names
    may be any file the user can read (a shared scene can name one), so a refusal of its text names the
    file and the command that gives the reason, not what it holds: the lens readers quote a faulty line,
    as they should for a file the user gives them. A missing or unreadable file, or another extension, is
    refused naming only the file (`formats.lens_path`)."""
    path = lens_path(resolved(str(props.get("lens", "solas-doublet"))))
    try:
        return Lens.load(path)
    except SolasError:
        raise SolasError(
            f"lens file {str(path)!r}, which the scene names, is not a lens solas-mi can use; "
            f"`solas-mi lens info {path}` says why"
        ) from None


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
