"""The one exception type for user errors."""
import re

_QUOTED = re.compile(r'"([^"]*)"')


MAX_WORD, MAX_MESSAGE = 200, 2000  # characters: a value quoted back from a file is cut, not printed whole
_LONG_WORD = re.compile(r"\S{%d,}" % (MAX_WORD + 1))


class SolasError(ValueError):
    """A user error: the message names the bad value and what is allowed. It holds at most MAX_MESSAGE
    characters, none of its words more than MAX_WORD (the rest cut, "…"): a file's line of a megabyte
    quoted back stays a line a terminal can show."""

    def __init__(self, message: object = "") -> None:
        text = _LONG_WORD.sub(lambda m: m[0][:MAX_WORD] + "…", str(message))
        super().__init__(text if len(text) <= MAX_MESSAGE else text[:MAX_MESSAGE] + "…")


def plugin_error(exc: BaseException, context: str, known: str | None = None) -> SolasError:
    """The user's one-line message out of an error Mitsuba raised around one of our plugins: the
    plugin's SolasError where Mitsuba kept it as the cause (JIT renders wrap it in their own
    RuntimeError) or in its text (the parser embeds a traceback ending in "SolasError: <message>");
    any other error gives the first line of Mitsuba's text. With `known` (the text of the scene's own
    files), a quoted "…" of Mitsuba's text that `known` does not hold is left out: Mitsuba quotes what it
    read from a mesh ("unknown token …"), and a scene may name any file the user can read."""
    cause = exc
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
    if known is not None:
        message = _QUOTED.sub(lambda m: m[0] if m[1] in known else '"…"', message)
    return SolasError(f"{context}: {message}")
