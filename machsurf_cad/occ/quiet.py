"""Silence OCCT's console chatter (transfer statistics) so CLI output and JSON stay clean."""

from __future__ import annotations

import contextlib
import os
import sys

from OCP.Message import Message, Message_Gravity

_done = False


def _lower_printers() -> None:
    global _done
    if _done:
        return
    printers = Message.DefaultMessenger_s().Printers()
    for i in range(1, printers.Length() + 1):
        printers.Value(i).SetTraceLevel(Message_Gravity.Message_Fail)
    _done = True


@contextlib.contextmanager
def quiet_occt():
    """Context in which OCCT's own prints to stdout are discarded (errors still raise)."""
    _lower_printers()
    sys.stdout.flush()
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        yield
        return
    saved = os.dup(fd)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, fd)
        os.close(saved)
        os.close(devnull)
