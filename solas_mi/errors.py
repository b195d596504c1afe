"""The one exception type for user errors."""


class SolasError(ValueError):
    """A user error: the message names the bad value and what is allowed."""
