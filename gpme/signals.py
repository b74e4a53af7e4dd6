"""SIGINT, SIGTERM and SIGHUP end a command at every moment, compilation included.

Python runs a signal handler between two bytecodes of the main thread.  When that moment
falls inside a callback from C (numba's compiler calls back into Python through ctypes;
``__del__`` methods and weakref callbacks are alike), the exception the handler raises
cannot leave the callback: Python prints "Exception ignored ..." and the work goes on, so
before this module a SIGTERM 20-30 s into a fresh compilation was lost and the run
completed with exit 0.

Worse, the swallowed exception leaves numba's compiler without its object code, and the
run then dies with numba's RuntimeError instead of the signal's status.

Here the handler records the signal and does not raise while the interrupted frame is
inside a callback from C (a frame of llvmlite's bindings, where numba's compiler calls
back): it asks for the exception to be raised :data:`REDELIVER_S` later (SIGALRM, main
thread), and again until the callback has returned.  ``sys.unraisablehook`` is the
fallback for any other place an exception cannot leave (it re-arms the same delivery), and
:func:`gpme.cli.main` reports any error raised after a signal as the interruption.  The command then exits with 130 (SIGINT) or 128 + the
signal number (143 SIGTERM, 129 SIGHUP), and :func:`raise_if_pending` lets a command check
before it publishes a result.
"""
import atexit
import signal
import sys
from pathlib import Path
from typing import List

REDELIVER_S = 0.05       # s, delay before a swallowed interruption is raised again
SIGNAL_NAMES = ("SIGINT", "SIGTERM", "SIGHUP")
# source folders whose frames are called from C through ctypes (an exception raised there
# is swallowed): llvmlite's bindings, which numba's compiler calls back
_CALLBACK_FOLDERS = (("llvmlite", "binding"),)

_pending: List[int] = []          # signal numbers received, first first
_previous_unraisable = sys.unraisablehook


class Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP) received: raised in the main thread like Ctrl-C's
    KeyboardInterrupt, so every ``finally`` and staging-directory cleanup runs; the command
    then exits with 128 + the signal number (143 for SIGTERM)."""

    def __init__(self, signum):
        super().__init__(signum)
        self.signum = signum


def interruption(signum: int) -> KeyboardInterrupt:
    """The exception that stands for signal ``signum`` (KeyboardInterrupt for SIGINT)."""
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


def exit_status(exc: KeyboardInterrupt) -> int:
    """130 for Ctrl-C (SIGINT), 128 + the signal number for a Terminated."""
    return 128 + int(getattr(exc, "signum", signal.SIGINT))


def pending() -> List[int]:
    """The signals received so far (numbers), in order."""
    return list(_pending)


def raise_if_pending() -> None:
    """Raise the first received signal's interruption if one came (a check before a command
    publishes its result: a run must never complete after a signal)."""
    if _pending:
        raise interruption(_pending[0])


def _in_callback(frame) -> bool:
    """True when ``frame`` or a caller is a function called from C (see _CALLBACK_FOLDERS)."""
    while frame is not None:
        parts = Path(frame.f_code.co_filename).parts
        if any(parts[i:i + len(f)] == f for f in _CALLBACK_FOLDERS
               for i in range(len(parts) - len(f) + 1)):
            return True
        frame = frame.f_back
    return False


def _arm() -> None:
    signal.setitimer(signal.ITIMER_REAL, REDELIVER_S)


def _deliver(frame) -> None:
    """Raise the first pending interruption, or re-arm the delivery while inside a
    callback from C."""
    if not _pending:
        return
    if _in_callback(frame):
        _arm()
        return
    raise interruption(_pending[0])


def _handler(signum, frame):
    _pending.append(signum)
    _deliver(frame)


def _redeliver(signum, frame):
    _deliver(frame)


def cancel_delivery() -> None:
    """Stop a pending redelivery (at exit: the default SIGALRM action would kill the
    process after Python restored it)."""
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
    except ValueError:
        pass


def _unraisable(hook_args):
    """A swallowed interruption of ours is raised again soon; anything else goes to the
    previous hook."""
    if isinstance(hook_args.exc_value, KeyboardInterrupt) and _pending:
        _arm()
        return
    _previous_unraisable(hook_args)


def install() -> None:
    """Install the handlers (main thread only; a no-op elsewhere, e.g. a test worker)."""
    try:
        for name in SIGNAL_NAMES:
            sig = getattr(signal, name, None)
            if sig is not None:
                signal.signal(sig, _handler)
        signal.signal(signal.SIGALRM, _redeliver)
    except ValueError:            # not the main thread
        return
    sys.unraisablehook = _unraisable
    atexit.register(cancel_delivery)


def ignore_late_signals() -> None:
    """The command's work is done and written: a signal during the interpreter's shutdown
    would only turn its status into a death by signal."""
    for name in SIGNAL_NAMES:
        sig = getattr(signal, name, None)
        if sig is not None:
            signal.signal(sig, signal.SIG_IGN)
    cancel_delivery()
