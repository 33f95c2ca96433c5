"""One FMU instance of a co-simulation and the one place through which every FMI call goes.

:meth:`FmuInstance.call` calls an fmpy ``FMU2Slave`` function, checks the returned status (fmpy raises for
Discard, Error and Fatal) and, with a ``trace`` callable, logs each call with its arguments and status — the
``--trace-fmi`` option of ``frb cosim`` costs nothing when it is off. It also counts the calls and the wall time
spent in them per FMI function (:attr:`FmuInstance.calls`; two clock reads per call, ~0.1 µs against the 3-6 µs
of an FMI call through ctypes and pythonfmu), from which ``benchmarks/cosim.py`` splits a macro step's time.

The FMU's log messages come to the instance's own logger callback (:meth:`FmuInstance._on_log`; fmpy's default
one prints them to stdout): those with a status above fmi2OK logged during a call that failed make the
:class:`FmiCallFailed` message, so that a stopped co-simulation says why, not only which status came back; all
go to ``trace``. The instance is created with loggingOn = fmi2True (pythonfmu's own binary drops every message
otherwise). The callback is a plain ctypes function, not behind fmpy's formatting proxy, which holds one Python
logger for the whole process (the last one given to it: any later fmpy user would take the messages away): the
frbmodel FMUs' loader passes each message as a format string without arguments ('%' doubled, undone here); an
FMU that passes printf arguments shows its format string.

getReal and setReal, the per-step traffic, call the FMU's fmi2GetReal / fmi2SetReal directly with C arrays of the
value references (and a value buffer) made once per list of value references: fmpy's ``getReal`` / ``setReal``
build both arrays at every call (measured in the main job's exchange: 7.3 -> 3.1 us for 15 values read, 11.8 ->
5.0 us for 30 values set).
"""
from __future__ import annotations

import ctypes
import sys
import tempfile
import time
from pathlib import Path

from ..core.errors import CosimStopped, ParameterError
from .loader import STATUS_MARKER, model_identifier

#: fmi2Status names by value
STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
#: most lists of value references whose C arrays an instance keeps per direction (a master uses a handful)
MAX_PLANS = 256


class FmiCallFailed(CosimStopped):
    """An FMI function returned Discard, Error or Fatal (or fmi2Instantiate returned NULL). ``.fmu`` (instance name),
    ``.function``, ``.status`` (fmi2Status value; 2 = Discard, the only one a master may retry after a rollback),
    ``.reason`` (the first message above fmi2OK the FMU logged during the call, without the instance-name prefix;
    empty if none) and ``.n_reasons`` (how many it logged).

    Parameters
    ----------
    fmu : str
        Instance name of the FMU.
    function : str
        Name of the FMI function (fmpy ``FMU2Slave`` method, e.g. ``"doStep"``).
    status : int
        The returned fmi2Status value.
    reasons : tuple (str, int), optional
        The first reason logged during the call and the number of reasons.

    Examples
    --------
    >>> exc = FmiCallFailed("bearing_t", "doStep", 2, ("inner film: eccentricity ratio 1.2 >= 1", 2))
    >>> print(exc)
    bearing_t: doStep returned status Discard: inner film: eccentricity ratio 1.2 >= 1 (and 1 more message)
    >>> exc.discarded
    True
    >>> print(FmiCallFailed("bearing_t", "doStep", 3))
    bearing_t: doStep returned status Error (the FMU logged no reason)
    """

    def __init__(self, fmu, function, status, reasons=("", 0)):
        reason, n = reasons
        more = n - 1
        why = (f": {reason}" + (f" (and {more} more message{'s' if more > 1 else ''})" if more > 0 else "")
               if n else " (the FMU logged no reason)")
        what = "returned NULL" if function == "instantiate" else \
            f"returned status {STATUS[status] if 0 <= status < 6 else status}"
        super().__init__(f"{fmu}: {function} {what}{why}")
        self.fmu, self.function, self.status, self.reason, self.n_reasons = fmu, function, status, reason, n

    @property
    def discarded(self):
        """True if the status is Discard (2): the step may be retried after a rollback."""
        return self.status == 2


class ExtractionFolder:
    """A temporary folder the FMUs of one master are extracted into. :meth:`cleanup` deletes it and takes off
    ``sys.path`` whatever under it was added since it was made (the instances take their own resources folders off
    when they are freed; anything else left there would point at deleted files)."""

    def __init__(self, prefix):
        self._tmp = tempfile.TemporaryDirectory(prefix=prefix)
        self.name = self._tmp.name
        self._sys_path = list(sys.path)

    def cleanup(self):
        sys.path[:] = [p for p in sys.path if p in self._sys_path or not p.startswith(self.name)]
        self._tmp.cleanup()



class FmuHost:
    """Base of the masters: the FMU instances of an SSP's components (``self.ssp``), extracted into one
    :class:`ExtractionFolder`; a context manager (``setup()`` on entry, :meth:`close` on exit)."""

    fmus: dict
    _tmp: ExtractionFolder | None = None

    def _instantiate(self, prefix):
        """Extract and instantiate every component's FMU (one at a time: :meth:`close` frees those made before a
        failure)."""
        self._tmp = ExtractionFolder(prefix)
        self.fmus = {}
        for name, path in self.ssp.components.items():
            self.fmus[name] = FmuInstance(name, path, self._tmp.name, self.trace)

    def _freed(self, fmu):
        """Called for each instance after it is freed (a master collects its call statistics here)."""

    def close(self):
        """Terminate and free every FMU instance, delete the extracted files and close the SSP."""
        for fmu in self.fmus.values():
            fmu.free()
            self._freed(fmu)
        self.fmus = {}
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None
        self.ssp.close()

    def __enter__(self):
        return self.setup()

    def __exit__(self, *exc):
        self.close()
        return False


class FmuInstance:
    """An instantiated FMU of the system.

    Parameters
    ----------
    name : str
        Instance name (the SSP component name).
    path : path
        The ``.fmu`` archive.
    unzip_root : path
        Folder under which the FMU is extracted (``<unzip_root>/<name>``).
    trace : callable, optional
        ``trace(text)`` receives one line per FMI call, ``"<instance>.<function>(<args>) -> <status>"``, and one per
        message the FMU logs, ``"<instance> log [<status>] <message>"`` (the instance is then created with
        loggingOn = fmi2True, so that messages with status OK come too).

    Attributes
    ----------
    calls : dict
        ``{function: [number of calls, wall time inside them [s]]}`` of every :meth:`call` so far (failed ones
        included).
    """

    def __init__(self, name, path, unzip_root, trace=None):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.name = name
        self.trace = trace
        self.calls = {}

        model_identifier(path)  # a broken archive is named here (fmpy would raise a zipfile.BadZipFile)
        self.md = read_model_description(str(path))
        self.model_identifier = self.md.coSimulation.modelIdentifier
        self.dir = extract(str(path), unzipdir=str(Path(unzip_root) / name))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir, modelIdentifier=self.model_identifier,
                               instanceName=name)
        self.can_state = bool(self.md.coSimulation.canGetAndSetFMUstate)
        # the C functions as fmpy configured them (argument and return types), and the prepared arrays per list of
        # value references: {tuple of value references: (C array of them, count, C value buffer)}
        self._c_get, self._c_set = self.slave.dll.fmi2GetReal, self.slave.dll.fmi2SetReal
        self._c_step, self._c_get_state = self.slave.dll.fmi2DoStep, self.slave.dll.fmi2GetFMUstate
        self._get_plans, self._set_plans = {}, {}
        self._fast = {"getReal": self._get_real, "setReal": self._set_real, "doStep": self._do_step,
                      "getFMUstate": self._get_state}
        # FMUs with the frbmodel loader reuse a state handle given back to fmi2GetFMUstate (FMI 2.0; pythonfmu alone
        # would leak the old state): save_state then keeps one handle, and no freeFMUstate per saved state

        self.reuses_state = self.can_state and (Path(self.dir) / STATUS_MARKER).is_file()
        self._state = None
        # reasons (messages above fmi2OK): how many so far, the first one of the current call and the count at its
        # start (set by call(): the reasons of a failed call are the ones logged during it)
        self._n_reasons, self._first_reason, self._reasons_before = 0, "", 0
        self._callbacks = _callbacks(self._on_log)  # (kept: the FMU calls them until it is freed)
        try:
            self.call("instantiate", True, self._callbacks, True)
        except FmiCallFailed:
            raise
        except Exception as exc:  # noqa: BLE001  (fmpy: "Failed to instantiate model", the FMU returned NULL)
            raise FmiCallFailed(self.name, "instantiate", 4, self._call_reasons()) from exc

    def _on_log(self, env, instance, status, category, message):
        """The FMU's logger callback: count a reason (and keep the first of the call), pass it to ``trace``."""
        text = message.decode("utf-8", "replace").replace("%%", "%") if message else ""
        prefix = f"{self.name}: "
        text = text[len(prefix):] if text.startswith(prefix) else text
        if 0 < status < 5:  # Warning, Discard, Error, Fatal (not Pending)
            if self._n_reasons == self._reasons_before:
                self._first_reason = text
            self._n_reasons += 1
        if self.trace is not None:
            self.trace(f"{self.name} log [{STATUS[status] if 0 <= status < 6 else status}] {text}")

    def _call_reasons(self):
        """(first reason, number of reasons) logged since the current call started."""
        n = self._n_reasons - self._reasons_before
        return (self._first_reason, n) if n else ("", 0)

    def call(self, function, *args):
        """``slave.<function>(*args)`` with status check (and trace).

        Parameters
        ----------
        function : str
            fmpy ``FMU2Slave`` method name (``"doStep"``, ``"getReal"``, ...).
        *args
            Its arguments.

        Returns
        -------
        object
            What the fmpy method returns (None for most setters).

        Raises
        ------
        FmiCallFailed
            If the function returned Discard, Error or Fatal.
        """
        t0 = time.perf_counter()
        self._reasons_before = self._n_reasons
        try:
            fast = self._fast.get(function)
            out = fast(*args) if fast is not None else getattr(self.slave, function)(*args)
        except _fmi_call_exception() as exc:
            self._count(function, t0)
            if self.trace is not None:
                self.trace(f"{self.name}.{function}{_brief(args)} -> {STATUS[int(exc.status)]}")
            raise FmiCallFailed(self.name, function, int(exc.status), self._call_reasons()) from None
        stat = self.calls.get(function)  # (inline: this runs ~20 times per macro step)
        if stat is None:
            stat = self.calls[function] = [0, 0.0]
        stat[0] += 1
        stat[1] += time.perf_counter() - t0
        if self.trace is not None:
            self.trace(f"{self.name}.{function}{_brief(args)} -> OK" + ("" if out is None else f" {_brief(out)}"))
        return out

    def _get_real(self, vr):
        """fmpy's ``getReal(vr)`` (a list of floats; raises its FMICallException above Warning) without making
        the C arrays again for a list of value references seen before."""
        plan = self._get_plans.get(tuple(vr))
        if plan is None:
            if len(self._get_plans) >= MAX_PLANS:
                self._get_plans.clear()
            plan = self._get_plans[tuple(vr)] = _plan(vr)
        refs, n, buf = plan
        status = self._c_get(self.slave.component, refs, n, buf)
        if status > 1:
            raise _fmi_call_exception()(function="fmi2GetReal", status=status)
        return buf[:]

    def _set_real(self, vr, values):
        """fmpy's ``setReal(vr, values)`` without making the array of value references again."""
        plan = self._set_plans.get(tuple(vr))
        if plan is None:
            if len(self._set_plans) >= MAX_PLANS:
                self._set_plans.clear()
            plan = self._set_plans[tuple(vr)] = _plan(vr)
        refs, n, buf = plan
        buf[:] = values
        status = self._c_set(self.slave.component, refs, n, buf)
        if status > 1:
            raise _fmi_call_exception()(function="fmi2SetReal", status=status)

    def _do_step(self, t, h, no_set_prior=True):
        """fmpy's ``doStep(t, h, flag)`` as one C call (fmpy's wrapper adds ~1 µs of Python per call)."""
        status = self._c_step(self.slave.component, t, h, 1 if no_set_prior else 0)
        if status > 1:
            raise _fmi_call_exception()(function="fmi2DoStep", status=status)

    def _get_state(self, state=None):
        """fmpy's ``getFMUstate()`` (a new state), or with ``state`` fmi2GetFMUstate into that handle (reused)."""
        if state is None:
            return self.slave.getFMUstate()
        status = self._c_get_state(self.slave.component, ctypes.byref(state))
        if status > 1:
            raise _fmi_call_exception()(function="fmi2GetFMUstate", status=status)
        return state

    def save_state(self):
        """The FMU's state now (fmi2GetFMUstate): into the instance's one handle where the FMU reuses handles
        (:attr:`reuses_state`), else a new one. Give it to :meth:`drop_state` when no longer needed.

        Returns
        -------
        fmi2FMUstate
        """
        if not self.reuses_state:
            return self.call("getFMUstate")
        if self._state is None:
            self._state = self.call("getFMUstate")
        else:
            self.call("getFMUstate", self._state)
        return self._state

    def drop_state(self, state):
        """Free a state of :meth:`save_state` (the reused handle is kept until :meth:`free`)."""
        if state is not self._state:
            self.call("freeFMUstate", state)

    def _count(self, function, t0):
        stat = self.calls.get(function)
        if stat is None:
            stat = self.calls[function] = [0, 0.0]
        stat[0] += 1
        stat[1] += time.perf_counter() - t0

    def vr(self, names):
        """Value references of the variables ``names``.

        Parameters
        ----------
        names : list of str
            Variable names as in the modelDescription.xml.

        Returns
        -------
        list of int

        Raises
        ------
        ParameterError
            Naming the first variable the FMU does not have.
        """
        try:
            return [self.vars[n].valueReference for n in names]
        except KeyError as exc:
            raise ParameterError(f"FMU {self.name!r} ({self.model_identifier}) has no variable "
                                 f"{exc.args[0]!r}") from None

    def has(self, name):
        """True if the FMU has a variable ``name``.

        Parameters
        ----------
        name : str
            Variable name as in the modelDescription.xml.

        Returns
        -------
        bool
        """
        return name in self.vars

    def set_parameters(self, params):
        """Set parameters of the instance.

        Parameters
        ----------
        params : dict
            ``{name: (type, value)}`` with type ``"Real"``, ``"Integer"``, ``"Boolean"`` or ``"String"`` (as in an
            .ssv file).

        Raises
        ------
        ParameterError
            For an unknown type or variable name.
        FmiCallFailed
            If the FMU refuses a value.
        """
        setter = {"Real": "setReal", "Integer": "setInteger", "Boolean": "setBoolean", "String": "setString"}
        for name, (typ, val) in params.items():
            if typ not in setter:
                raise ParameterError(f"{self.name}.{name}: parameter type {typ!r} is unknown; valid: {sorted(setter)}")
            self.call(setter[typ], self.vr([name]), [val])

    def free(self):
        """Terminate and free the instance (ignoring the refusal of an instance that already failed) and take the
        FMU's resources folder off ``sys.path``, where pythonfmu's slave put it: it holds a copy of frbmodel, which
        processes spawned later from this one (Dask workers) would import, without a numba cache."""
        import sys

        if self._state is not None:
            try:
                self.call("freeFMUstate", self._state)
            except Exception:  # noqa: BLE001  (a failed FMU may refuse it; freeInstance must still run)
                pass
            self._state = None
        for function in ("terminate", "freeInstance"):
            try:
                self.call(function)
            except Exception:  # noqa: BLE001  (a failed FMU may refuse terminate; freeInstance must still run)
                pass
        sys.path[:] = [p for p in sys.path if not p.startswith(str(self.dir))]


def _callbacks(on_log):
    """fmi2CallbackFunctions with ``on_log(env, instance, status, category, message)`` as the logger (a ctypes
    callback, see the module description) and the C runtime's calloc/free."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
    )

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(on_log)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return cb


def _plan(vr):
    """(C array of the value references ``vr``, their count, a C buffer of as many fmi2Real)."""
    n = len(vr)
    return (ctypes.c_uint * n)(*vr), n, (ctypes.c_double * n)()


def _fmi_call_exception():
    """fmpy's exception class for a failed FMI call (imported when first needed: fmpy is optional)."""
    from fmpy.fmi1 import FMICallException

    return FMICallException


def _brief(x, limit=120):
    text = repr(x)
    return text if len(text) <= limit else text[:limit] + "...]"
