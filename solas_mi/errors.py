"""The one exception type for user errors."""


class SolasError(ValueError):
    """A user error: the message names the bad value and what is allowed."""


def plugin_error(exc: BaseException, context: str) -> SolasError:
    """The user's one-line message out of an error Mitsuba raised around one of our plugins: Mitsuba
    wraps a plugin's SolasError in its parser error, with a Python traceback ending in
    "SolasError: <message>"; any other error gives the first line of Mitsuba's text."""
    text = str(exc)
    marker = "SolasError: "
    message = text.rsplit(marker, 1)[1] if marker in text else text
    return SolasError(f"{context}: {message.strip().splitlines()[0] if message.strip() else type(exc).__name__}")
