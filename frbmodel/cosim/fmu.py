"""One FMU instance of a co-simulation and the one place through which every FMI call goes.

:meth:`FmuInstance.call` calls an fmpy ``FMU2Slave`` function, checks the returned status (fmpy raises for
Discard, Error and Fatal) and, with a ``trace`` callable, logs each call with its arguments and status — the
``--trace-fmi`` option of ``frb cosim`` costs nothing when it is off. It also counts the calls and the wall time
spent in them per FMI function (:attr:`FmuInstance.calls`; two clock reads per call, ~0.1 µs against the 3-6 µs
of an FMI call through ctypes and pythonfmu), from which ``benchmarks/cosim.py`` splits a macro step's time.

The FMU's log messages come to :meth:`FmuInstance._on_log` (its own logger callback; fmpy's default one prints
to stdout): they are kept (:attr:`FmuInstance.messages`), passed to ``trace``, and the ones logged during a call
that failed make the :class:`FmiCallFailed` message, so that a stopped co-simulation says why, not only which
status came back. The instance is created with loggingOn = fmi2False (fmi2True with ``trace``): the frbmodel
FMUs (through their loader) log the reason of every status above fmi2OK whatever loggingOn says.

getReal and setReal, the per-step traffic, call the FMU's fmi2GetReal / fmi2SetReal directly with C arrays of the
value references (and a value buffer) made once per list of value references: fmpy's ``getReal`` / ``setReal``
build both arrays at every call (measured in the main job's exchange: 7.3 -> 3.1 us for 15 values read, 11.8 ->
5.0 us for 30 values set).
"""
from __future__ import annotations

import collections
import ctypes
import time
from pathlib import Path

from ..errors import CosimStopped, ParameterError

#: fmi2Status names by value
STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
#: most lists of value references whose C arrays an instance keeps per direction (a master uses a handful)
MAX_PLANS = 256
#: log messages an instance keeps (the newest)
MAX_MESSAGES = 200


class FmiCallFailed(CosimStopped):
    """An FMI function returned Discard, Error or Fatal. ``.fmu`` (instance name), ``.function``, ``.status``
    (fmi2Status value; 2 = Discard, the only one a master may retry after a rollback), ``.reasons`` (the messages
    the FMU logged during the call, without the instance-name prefix).

    Parameters
    ----------
    fmu : str
        Instance name of the FMU.
    function : str
        Name of the FMI function (fmpy ``FMU2Slave`` method, e.g. ``"doStep"``).
    status : int
        The returned fmi2Status value.
    reasons : list of str, optional
        What the FMU logged during the call; the first one is in the message.

    Examples
    --------
    >>> exc = FmiCallFailed("bearing_t", "doStep", 2, ["inner film: eccentricity ratio 1.2 >= 1", "ring ..."])
    >>> print(exc)
    bearing_t: doStep returned status Discard: inner film: eccentricity ratio 1.2 >= 1 (and 1 more message)
    >>> exc.discarded
    True
    >>> print(FmiCallFailed("bearing_t", "doStep", 3))
    bearing_t: doStep returned status Error (the FMU logged no reason)
    """

    def __init__(self, fmu, function, status, reasons=()):
        reasons = list(reasons)
        more = len(reasons) - 1
        why = (f": {reasons[0]}" + (f" (and {more} more message{'s' if more > 1 else ''})" if more > 0 else "")
               if reasons else " (the FMU logged no reason)")
        super().__init__(f"{fmu}: {function} returned status {STATUS[status] if 0 <= status < 6 else status}{why}")
        self.fmu, self.function, self.status, self.reasons = fmu, function, status, reasons

    @property
    def discarded(self):
        """True if the status is Discard (2): the step may be retried after a rollback."""
        return self.status == 2


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
    messages : collections.deque
        ``(status, message)`` of the messages the FMU logged, the newest :data:`MAX_MESSAGES`.
    """

    def __init__(self, name, path, unzip_root, trace=None):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.name = name
        self.trace = trace
        self.calls = {}
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
        self._c_step = self.slave.dll.fmi2DoStep
        self._get_plans, self._set_plans = {}, {}
        self._fast = {"getReal": self._get_real, "setReal": self._set_real, "doStep": self._do_step}
        self.messages = collections.deque(maxlen=MAX_MESSAGES)
        self._logged = 0  # messages logged so far (the reasons of a failed call are the ones logged during it)
        self._callbacks = _callbacks(self)  # (kept: the FMU calls them until it is freed)
        try:
            self.call("instantiate", True, self._callbacks, trace is not None)
        except BaseException:
            _LISTENERS.pop(id(self), None)
            raise

    def _on_log(self, env, instance, status, category, message):
        """The FMU's logger callback (through fmpy's native proxy, which formats the message)."""
        text = message.decode("utf-8", "replace") if message else ""
        self.messages.append((int(status), text))
        self._logged += 1
        if self.trace is not None:
            self.trace(f"{self.name} log [{STATUS[status] if 0 <= status < 6 else status}] {text}")

    def _reasons(self, since):
        """The messages logged after the first ``since`` ones, without the FMU's "<instance>: " prefix."""
        new = list(self.messages)[-(self._logged - since):] if self._logged > since else []
        prefix = f"{self.name}: "
        return [m[len(prefix):] if m.startswith(prefix) else m for _, m in new]

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
        t0, logged = time.perf_counter(), self._logged
        try:
            fast = self._fast.get(function)
            out = fast(*args) if fast is not None else getattr(self.slave, function)(*args)
        except _fmi_call_exception() as exc:
            self._count(function, t0)
            if self.trace is not None:
                self.trace(f"{self.name}.{function}{_brief(args)} -> {STATUS[int(exc.status)]}")
            raise FmiCallFailed(self.name, function, int(exc.status), self._reasons(logged)) from None
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

        for function in ("terminate", "freeInstance"):
            try:
                self.call(function)
            except Exception:  # noqa: BLE001  (a failed FMU may refuse terminate; freeInstance must still run)
                pass
        _LISTENERS.pop(id(self), None)
        sys.path[:] = [p for p in sys.path if not p.startswith(str(self.dir))]


#: {componentEnvironment value: FmuInstance} of the instances alive, for :func:`_dispatch_log`
_LISTENERS = {}
_DISPATCH = []  # the one logger callback object (made at first use, kept for the life of the process)


def _dispatch_log(env, instance, status, category, message):
    """The logger of every FmuInstance: the message goes to the instance whose componentEnvironment it carries.
    fmpy's native proxy, which formats a message with its variadic arguments, keeps one Python logger for the whole
    process (the last one given to it): messages of other fmpy users (no such environment) are printed as fmpy
    prints them."""
    fmu = _LISTENERS.get(env)
    if fmu is not None:
        fmu._on_log(env, instance, status, category, message)
    else:
        from fmpy.fmi1 import printLogMessage

        printLogMessage(env, instance, status, category, message)


def _callbacks(fmu):
    """fmi2CallbackFunctions for ``fmu``: :func:`_dispatch_log` behind fmpy's native formatting proxy as the
    logger, ``id(fmu)`` as componentEnvironment, the C runtime's calloc/free."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
    )

    if not _DISPATCH:
        _DISPATCH.append(fmi2CallbackLoggerTYPE(_dispatch_log))
    cb = fmi2CallbackFunctions()
    cb.logger = _DISPATCH[0]
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    cb.componentEnvironment = id(fmu)
    _LISTENERS[id(fmu)] = fmu
    try:
        from fmpy.logging import addLoggerProxy

        addLoggerProxy(ctypes.byref(cb))  # (sets the proxy's logger to _DISPATCH again, whoever set it last)
    except Exception:  # noqa: BLE001  (no native proxy on this platform: messages arrive unformatted)
        pass
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
