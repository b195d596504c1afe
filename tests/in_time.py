"""Calls that must return in time: a reader stuck on a FIFO, or reading /dev/zero, never returns."""

import threading

from solas_mi.errors import SolasError

WAIT_S = 60  # a reader that waits on a FIFO never returns; one that refuses it returns in well under a second


def finished(call, *args, **kwargs) -> dict:
    """{"value": what `call` returned} or {"error": what it raised}; the test fails when it has not returned
    within WAIT_S (the call goes on in a daemon thread, which the test run does not wait for)."""
    out = {}

    def run():
        try:
            out["value"] = call(*args, **kwargs)
        except BaseException as exc:  # any: handed to the test
            out["error"] = exc

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(WAIT_S)
    assert out, f"{getattr(call, '__qualname__', call)} did not return within {WAIT_S} s"
    return out


def refused(call, *args, **kwargs) -> str:
    """The message of the SolasError `call` must raise in time."""
    out = finished(call, *args, **kwargs)
    assert isinstance(out.get("error"), SolasError), out
    return str(out["error"])
