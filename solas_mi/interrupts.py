"""Signals (Ctrl-C, SIGTERM) raised as exceptions where the program is, but never inside an import.

An exception raised while a module is being imported breaks more than that import: an extension
module whose initialisation imports Python modules (Dr.Jit's, Mitsuba's, OpenEXR's) turns it into its
own ImportError or swallows it, so a Ctrl-C while Dr.Jit loads ended in a NameError (exit 1), one
while OpenEXR loads was lost, and such a module cannot be imported again in that process. Every
import here is lazy (light modules stay light), so an interruption can come during one at any moment.
`raise_outside_imports` lets an import in progress finish and raises the interruption in the frame
that started it, at its next instruction (the time of one import: a second or two for Mitsuba).
"""

from __future__ import annotations

import sys
from types import FrameType

IMPORT_MACHINERY = ("<frozen importlib._bootstrap>", "<frozen importlib._bootstrap_external>")


def importer(frame: FrameType | None) -> FrameType | None:
    """The frame that started the import in progress at `frame` (the caller of the outermost frame of
    the import machinery), or None when no import is in progress."""
    found = None
    while frame is not None:
        if frame.f_code.co_filename in IMPORT_MACHINERY:
            found = frame.f_back
        frame = frame.f_back
    return found


def _untraced(frame, event, arg) -> None:
    """The global trace function while an interruption waits: it traces no new frame."""
    return None


def raise_outside_imports(exception: BaseException, frame: FrameType | None) -> None:
    """Raise `exception` (a signal handler's, `frame` the frame the signal interrupted) now, or, when
    an import is in progress there, as soon as the import returns to the frame that started it."""
    caller = importer(frame)
    if caller is None:
        raise exception
    previous = sys.gettrace()
    if previous is _untraced:  # an interruption already waits for this import: it will be raised
        return

    def at_caller(frame, event, arg):
        frame.f_trace = None
        sys.settrace(previous)
        raise exception

    caller.f_trace_opcodes = True  # an event at the caller's next instruction, not only at its next line
    caller.f_trace = at_caller
    sys.settrace(_untraced)  # tracing on, so that the caller's own trace function runs
