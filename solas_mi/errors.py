"""The one exception type for user errors."""


class SolasError(ValueError):
    """A user error: the message names the bad value and what is allowed."""


def plugin_error(exc: BaseException, context: str) -> SolasError:
    """The user's one-line message out of an error Mitsuba raised around one of our plugins: the
    plugin's SolasError where Mitsuba kept it as the cause (JIT renders wrap it in their own
    RuntimeError) or in its text (the parser embeds a traceback ending in "SolasError: <message>");
    any other error gives the first line of Mitsuba's text."""
    cause = exc
    while cause is not None:
        if isinstance(cause, SolasError):
            return SolasError(f"{context}: {cause}")
        cause = cause.__cause__ or cause.__context__
    text = str(exc)
    marker = "SolasError: "
    message = text.rsplit(marker, 1)[1] if marker in text else text
    return SolasError(f"{context}: {message.strip().splitlines()[0] if message.strip() else type(exc).__name__}")
