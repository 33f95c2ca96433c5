"""Ctrl-C and SIGTERM during long runs, delivered between samples instead of inside compiled callbacks.

An exception raised inside an integrator's right-hand-side callback (scipy's LSODA, numba) can be swallowed or
turned into an unrelated error. :class:`deferred_signals` records SIGINT / SIGTERM while a run is in progress; the
run calls :meth:`~deferred_signals.check` between samples, which raises ``KeyboardInterrupt`` (SIGINT) or
:class:`Terminated` (SIGTERM) there, so the recorder can close its files as ``"interrupted"``. A second Ctrl-C
interrupts at once.
"""
from __future__ import annotations

import signal
import threading


class Terminated(KeyboardInterrupt):
    """SIGTERM, as an exception (exit code 143 in the CLI)."""


class deferred_signals:
    """Context manager: record SIGINT/SIGTERM, raise them at :meth:`check`. Outside the main thread (where
    handlers cannot be installed) it does nothing and :meth:`check` never raises.

    >>> with deferred_signals() as sig:
    ...     sig.check()   # nothing pending
    """

    def __init__(self):
        self.pending = None
        self._old = {}

    def _handler(self, signum, frame):
        if self.pending is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt  # second Ctrl-C: at once
        self.pending = signum

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handler)
        return self

    def check(self):
        """Raise the recorded signal as an exception (KeyboardInterrupt or :class:`Terminated`)."""
        if self.pending is not None:
            signum, self.pending = self.pending, None
            raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()

    def __exit__(self, *exc):
        for s, h in self._old.items():
            signal.signal(s, h)
        self._old = {}
        return False
