"""machsurf_cad's long calls off FreeCAD's GUI thread (no GUI import: the GUI registers its event pump).

A recompute runs on FreeCAD's GUI thread, so a fit or a drop-cutter of a minute used to freeze the window
(no repaint, Esc not seen). :func:`run` runs one machsurf_cad call in a worker thread instead, and the GUI
thread meanwhile waits in short slices: it moves FreeCAD's progress bar from the progress the call reports,
and lets the GUI handle its events (the pump the workbench registers with :func:`set_pump`). FreeCAD's
progress bar keeps the user's mouse and keys from other widgets while it runs; Esc (seen by the GUI's
pump, :func:`request_cancel`) cancels at once: the recompute returns with the feature's ``Cancelled``
error, and the call stops at its next progress report (waited for 0.2 s; a call that reports later stops
on its own then, its result dropped). The
worker only computes: the document is written by the GUI thread once the result is there. Headless
(FreeCADCmd), with no pump registered, the call runs directly.
"""

import threading

_PUMP = None
_STATE = {"recomputing": 0, "cancel": False}  # a machsurf recompute under way; Esc asked to stop it
SLICE_S = 0.05
"""How long the GUI thread waits for the worker between two rounds of events (s)."""


def set_pump(pump) -> None:
    """The GUI's ``processEvents`` (None: run calls directly)."""
    global _PUMP
    _PUMP = pump


def pump() -> None:
    """Let the GUI handle its events now (between steps of work the GUI thread itself does)."""
    if _PUMP is not None:
        _PUMP()


class recompute:
    """``with worker.recompute():`` around a feature's compute: Esc cancels from then on."""

    def __enter__(self):
        if not _STATE["recomputing"]:
            _STATE["cancel"] = False
        _STATE["recomputing"] += 1
        return self

    def __exit__(self, *exc):
        _STATE["recomputing"] -= 1
        if not _STATE["recomputing"]:
            _STATE["cancel"] = False
        return False


def busy() -> bool:
    """Whether a machsurf recompute is under way (Esc is then machsurf's)."""
    return _STATE["recomputing"] > 0


def request_cancel() -> None:
    """The user asked to stop (the GUI's Esc): the recompute stops at once, its call at its next report."""
    if busy():
        _STATE["cancel"] = True


def cancel_requested() -> bool:
    return bool(_STATE["cancel"])


class _Shared:
    """Progress and cancellation between the worker and the GUI thread (plain values under the GIL)."""

    def __init__(self):
        self.done, self.total, self.message = 0, None, ""
        self.cancel = False
        self.result = None
        self.error = None


def run(fn, args, kwargs, bar, *, cancelled, progress: bool = True):
    """``fn(*args, **kwargs)`` (with ``progress=`` when ``progress``), off the GUI thread while a pump is
    registered; ``bar`` is the feature's progress bar (called on the GUI thread only), ``cancelled`` the
    exception class to raise when the user cancels."""
    if _PUMP is None:
        return fn(*args, **({**kwargs, "progress": bar} if progress else kwargs))
    shared = _Shared()

    def report(done, total=None, message=""):
        if shared.cancel or _STATE["cancel"]:
            raise cancelled("cancelled by the user")
        shared.done, shared.total, shared.message = done, total, message

    def work():
        try:
            shared.result = fn(*args, **({**kwargs, "progress": report} if progress else kwargs))
        except BaseException as exc:  # handed to the GUI thread
            shared.error = exc

    t = threading.Thread(target=work, name="machsurf-recompute", daemon=True)
    seen = None
    try:
        t.start()
        while t.is_alive():
            t.join(SLICE_S)
            now = (shared.done, shared.total, shared.message)
            if now != seen or shared.total is None:  # a busy indicator steps on every slice
                bar(*now)
                seen = now
            _PUMP()
            if _STATE["cancel"]:
                raise cancelled("cancelled by the user")
    except cancelled:
        shared.cancel = True
        t.join(0.2)  # most calls report within that; the others stop at their next report, unseen
        raise
    if shared.error is not None:
        raise shared.error
    return shared.result
