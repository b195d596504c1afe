"""The one exception type for user errors."""

import re

_QUOTED = re.compile(r'"([^"]*)("?)')  # a quote in Mitsuba's text, closed or running on to the end
_VALUE = re.compile(r"""=\s*(?:"([^"]*)"|'([^']*)')""")  # an XML attribute's value
_TAG = re.compile(r"<\s*([A-Za-z_][\w.-]*)")  # an XML element's name
_CLOSES = " :;,.!?)]"  # what follows a closing quote in Mitsuba's messages (not a word of what it read)


MAX_WORD, MAX_MESSAGE = 200, 2000  # characters: a value quoted back from a file is cut, not printed whole
_LONG_WORD = re.compile(rf"\S{{{MAX_WORD + 1},}}")


class SolasError(ValueError):
    """A user error: one line that names the bad value and what is allowed.

    Every mistake of a caller (a value, a file, a setting) raises it; the command line prints it and
    exits with status 2. A `ValueError`, so code that catches those catches it too.

    Parameters
    ----------
    message : object, default ""
        The message. It is kept to at most `MAX_MESSAGE` characters, none of its words more than
        `MAX_WORD` (the rest cut, "…"): a file's line of a megabyte quoted back stays a line a
        terminal can show.

    Examples
    --------
    >>> from solas_mi import Lens, SolasError
    >>> try:
    ...     Lens.load("no-such-lens")
    ... except SolasError as error:
    ...     print(str(error).split(";")[0])
    unknown lens 'no-such-lens'
    """

    def __init__(self, message: object = "") -> None:
        text = _LONG_WORD.sub(lambda m: m[0][:MAX_WORD] + "…", str(message))
        super().__init__(text if len(text) <= MAX_MESSAGE else text[:MAX_MESSAGE] + "…")


def plugin_error(exc: BaseException, context: str, known: str | None = None) -> SolasError:
    """The user's one-line message out of an error Mitsuba raised around one of our plugins: the
    plugin's SolasError where Mitsuba kept it as the cause (JIT renders wrap it in their own
    RuntimeError) or in its text (the parser embeds a traceback ending in "SolasError: <message>");
    any other error gives the first line of Mitsuba's text. With `known` (the text of the scene's own
    files), Mitsuba's text ends at its first quote of something the scene does not name
    (`_scene_quotes_only`): Mitsuba quotes what it read from a mesh or spectrum file ("unknown token …"),
    and a scene may name any file the user can read."""
    cause: BaseException | None = exc
    while cause is not None:
        if isinstance(cause, SolasError):
            return SolasError(f"{context}: {cause}")
        cause = cause.__cause__ or cause.__context__
    text = str(exc)
    marker = "SolasError: "
    lines = [line.strip() for line in (text.rsplit(marker, 1)[1] if marker in text else text).strip().splitlines()]
    if not lines:
        return SolasError(f"{context}: {type(exc).__name__}")
    # a first line that announces a list ("Found unused parameters:") takes the list along
    message = lines[0] + (" " + "; ".join(line.lstrip("- ") for line in lines[1:]) if lines[0].endswith(":") else "")
    if known is not None and marker not in text:  # Mitsuba's own text (our plugins' messages quote no file)
        message = _scene_quotes_only(message, known)
    return SolasError(f"{context}: {message}")


def _words(text: str) -> set[str]:
    """What a scene's text names: its attribute values (ids, plugin types, property names, values, file
    names and each part of their paths) and its element names."""
    words = {m[1] for m in _TAG.finditer(text)}
    for m in _VALUE.finditer(text):
        value = m[1] if m[1] is not None else m[2]
        words.update([value, *re.split(r"[/\\]", value)])
    return words - {""}


def _scene_quotes_only(message: str, known: str) -> str:
    """Mitsuba's `message` up to its first quote of something the scene's text `known` does not name
    (`_words`; a path counts by its last part, a "file@N" by its file): that quote is shown as "…" and the rest left out. Mitsuba
    quotes what it read from a file without escaping it: a token cut at a NUL byte leaves its quote
    open, and a quote inside the token closes it early, so nothing after such a quote can be told apart
    from the file's text. A quote counts as closed only where a delimiter follows it (`_CLOSES`)."""
    words = _words(known)
    for m in _QUOTED.finditer(message):
        after = message[m.end() : m.end() + 1]
        closed = m[2] == '"' and (not after or after in _CLOSES)
        name = re.sub(r"@\d+$", "", re.split(r"[/\\]", m[1])[-1])  # "mesh.serialized@2": a file's shape 2
        if not (closed and (m[1] in words or name in words)):
            return message[: m.start()] + '"…"'
    return message
