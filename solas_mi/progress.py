"""Progress of the long jobs (renders, PSF grids, degrades, batches, experiments, cross-validation), the
one policy for all of them: a live tqdm bar when the stream is a terminal; anywhere else (a log file,
a pipe, a CI log) a few plain lines, one when each quarter of the work is passed, so that a log holds
about four lines, not one line of hundreds of carriage-return updates, and in a long job one at least
every `QUIET_S` seconds, written by a thread of its own: also while the job reports nothing (a PSF
grid reports after each batch of PSFs, which can take minutes; piped, a long grid's first line came
after 14 minutes). Both estimate the time left from the rate measured so far.

    with Progress("psf-grid", total, "PSF") as bar:
        psf_grid(lens, spec, progress=bar)     # the library's `progress(done, total)` callbacks
"""

from __future__ import annotations

import sys
import threading
import time

QUARTERS = 4  # plain lines: one as each quarter of the work is passed
QUIET_S = 60.0  # and at least one per this many seconds


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min"


def _count(value: float) -> str:
    return f"{value:.4g}" if value != int(value) else f"{int(value)}"


class Progress:
    """`done` of `total` `unit`s of the job `desc`, told by calling it as `progress(done, total)` (the
    callback the library's long functions take; `total` may change the announced total) or by
    `update(n)`; `close()`, or the end of its with block, ends it. `enabled=False`: silent."""

    def __init__(
        self, desc: str, total: float | None, unit: str, *, initial: float = 0, stream=None, enabled: bool = True
    ):
        self.stream = sys.stderr if stream is None else stream
        self.desc, self.total, self.unit, self.done = desc, total, unit, initial
        self.enabled = enabled
        self._bar = None
        self._start = self._said_at = time.monotonic()
        self._quarter = self._quarter_of(initial)
        self._saying = threading.Lock()  # one line at a time, from the job or from the quiet thread
        self._closed = threading.Event()
        if enabled and _is_terminal(self.stream):
            from tqdm import tqdm

            self._bar = tqdm(total=total, initial=initial, unit=unit, desc=desc, file=self.stream, dynamic_ncols=True)
        elif enabled:
            threading.Thread(target=self._when_quiet, name=f"progress of {desc}", daemon=True).start()

    def _quarter_of(self, done: float) -> int:
        return int(QUARTERS * done / self.total) if self.total else 0

    def __call__(self, done: float, total: float | None = None) -> None:
        if total is not None and total != self.total:
            self.total = total
            if self._bar is not None:
                self._bar.total = total
        self.update(done - self.done)

    def update(self, n: float = 1) -> None:
        self.done += n
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.update(n)
            return
        quarter = self._quarter_of(self.done)
        if quarter > self._quarter:
            self._quarter = quarter
            self.line()

    def _when_quiet(self) -> None:
        """The plain line whenever QUIET_S seconds pass without one, until the job ends."""
        while not self._closed.wait(max(0.0, self._said_at + QUIET_S - time.monotonic())):
            if time.monotonic() - self._said_at >= QUIET_S:
                try:
                    self.line()
                except (OSError, ValueError):  # the stream closed under it: say nothing more
                    return

    def line(self) -> None:
        """The plain line: `desc: done/total unit (percent, seconds[, the time left at the rate so far])`."""
        with self._saying:
            self._said_at = now = time.monotonic()
            seconds = now - self._start
            of = f"/{_count(self.total)}" if self.total else ""
            percent = f"{100.0 * self.done / self.total:.0f} %, " if self.total else ""
            left = ""
            if self.total and 0 < self.done < self.total:
                left = f", about {_duration(seconds * (self.total - self.done) / self.done)} left at this rate"
            print(
                f"{self.desc}: {_count(self.done)}{of} {self.unit} ({percent}{seconds:.1f} s{left})",
                file=self.stream,
                flush=True,
            )

    def close(self) -> None:
        self._closed.set()
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
