"""The ``machsurf`` entry point: Ctrl-C and SIGTERM handled before anything heavy is imported.

The console script and ``python -m machsurf_cad`` call :func:`main`, which installs the handlers and
only then imports the command line (:mod:`machsurf_cad.cli`), so an interrupt at any moment - while
numpy, scipy or the kernel are still loading - ends with exit 130 (Ctrl-C) or 143 (SIGTERM) and one
line, never a traceback.
"""

from __future__ import annotations

import signal
import sys
import threading


class Terminated(BaseException):
    """SIGTERM, raised like Ctrl-C so staged outputs are removed on the way out."""


def _on_sigterm(signum, frame):
    raise Terminated()


def _signal_in(exc: BaseException | None) -> str | None:
    """ "interrupted" or "terminated" when ``exc`` is, or was raised from, Ctrl-C or SIGTERM (an extension
    module interrupted while it loads raises ImportError from the KeyboardInterrupt)."""
    seen = 0
    while exc is not None and seen < 20:
        if isinstance(exc, KeyboardInterrupt):
            return "interrupted"
        if isinstance(exc, Terminated):
            return "terminated"
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def main(argv=None) -> int:
    """Run ``machsurf`` with ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    main_thread = threading.current_thread() is threading.main_thread()
    previous = previous_int = None
    try:
        if main_thread:
            previous = signal.signal(signal.SIGTERM, _on_sigterm)
            previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)  # even when started ignored
        from .cli import run

        return run(argv)
    except BaseException as exc:
        signalled = _signal_in(exc)
        if signalled is None:
            raise
        print(f"machsurf: {signalled} (nothing written)", file=sys.stderr)
        return 130 if signalled == "interrupted" else 143
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
        if previous_int is not None:
            signal.signal(signal.SIGINT, previous_int)


def entry() -> None:
    """The console script and ``python -m machsurf_cad``: :func:`main`, then exit with its code.

    After Ctrl-C or SIGTERM the process ends at once with 130 or 143 (stdio flushed): an interrupt that
    landed inside an extension's start-up code can leave CPython's "unhandled interrupt" flag set, and the
    interpreter's finalisation would then turn the exit into a kill by SIGINT.
    """
    code = main()
    if code in (130, 143):
        import os

        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    entry()
