"""Helpers shared by the frbmodel FMU slaves (bundled into each FMU next to the slave script): variable
registration with units, the FMI 2.0 state machine and status protocol (:class:`FrbSlaveMixin`)."""
import math
import re
from pathlib import Path

import numpy as np
from pythonfmu import Boolean, Fmi2Causality, Fmi2Initial, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

#: modes of the FMI 2.0 co-simulation state machine (FMI 2.0 section 4.2.4) tracked by the slaves
INSTANTIATED, INITIALIZATION, STEP, TERMINATED, ERROR = ("the instantiated state", "initialization mode",
                                                         "step mode", "the terminated state", "the error state")
#: marker file in the FMU's resources: the FMU binary (the frbmodel loader) returns for each FMI call the worst of
#: pythonfmu's status and the statuses of the messages the slave logged during the call
STATUS_FROM_LOG = "frb_status_from_log"
#: most lists of value references whose index arrays a slave keeps (a master uses a handful; more are forgotten)
MAX_PLANS = 256
#: an input the slave's settings leave unused (the oil supply without the parameter oil) must stay at its start
#: value, to this relative tolerance: a host's interpolation or a text file's digits give 363.1499999999999 K for
#: a constant 363.15 K (the FMU Compliance Checker did), and 1e-9 of a supply value changes nothing physical
UNUSED_INPUT_RTOL = 1e-9
#: build options in the FMU's resources (written by frbmodel.cosim.build): {"linearization": bool}
BUILD_OPTIONS = "frb_build.json"


class FrbSlaveMixin:
    """FMI 2.0 co-simulation behaviour shared by the frbmodel slaves.

    - Variables: ``_param`` / ``_input`` / ``_output`` register each variable with its unit (every Real has one:
      :meth:`to_xml` writes it and the UnitDefinitions) and, for parameters, its valid range or values.
    - State machine (FMI 2.0 section 4.2.4): instantiated -> initialization mode -> step mode -> terminated, and
      an error state after a failed initialization. Each call outside the states the standard's table allows it in
      is refused (fmi2Error) and changes nothing: fmi2GetReal/Integer/Boolean/String in the instantiated state
      (before fmi2EnterInitializationMode, and after fmi2Reset, which gives pythonfmu a new slave), fmi2Terminate
      outside step mode. Parameters are ``fixed``: setting one after fmi2ExitInitializationMode is refused
      (fmi2Error, the value stays). Inputs may be set until terminate. fmi2GetFMUstate is allowed in every state;
      a state taken before initialization brings the instance back to the instantiated state.
    - doStep: refused (fmi2Error) outside step mode or with a step size that is not finite and > 0; discarded
      (fmi2Discard, nothing of the step is kept) when the inputs are not finite or the component fails, e.g. a
      film reaching its wall; the next doStep with valid inputs continues from the unchanged state.
    - Outputs that cannot be evaluated read NaN with an fmi2Discard message, never a silent NaN.
    - Per-step traffic without a Python loop per variable: Real inputs live in one array (:attr:`_input_values`, set by
      index arrays prepared once per list of value references); Real outputs registered with ``block`` are read
      from arrays the slave computes once per change of inputs or state (``_output(..., block=(fn, index))``),
      again by prepared index arrays. Any other request, a failing block or a non-finite value takes the guarded
      per-variable path, which reports.

    Statuses: every FMI entry point returns normally and logs each refusal with the status the call must return
    (:meth:`_refuse`: fmi2Error, :meth:`_discard`: fmi2Discard). pythonfmu's own binary returns fmi2Discard for
    ``do_step() -> False`` and fmi2Fatal for an exception (after which it has released the Python object), nothing
    else; the frbmodel loader in front of it returns the worst of that and the statuses logged during the call.
    Without the loader's :data:`STATUS_FROM_LOG` marker, a failed initialization raises as before (fmi2Fatal), the
    only way pythonfmu's binary can refuse it.
    """

    def _init_state(self):
        """Common slave state: parameter values, input array, FMI mode, change counter, the component, variable
        tables. First of all, the bundled frbmodel is put first on sys.path (its stable copy) unless it is imported
        already (:func:`import_bundled_package_from_stable_copy`)."""
        if self.resources:
            import_bundled_package_from_stable_copy("frbmodel", self.resources)
        self._values = {}  # parameter name -> value
        self._input_values = np.zeros(0)  # Real input values, in the order of registration
        self._input_pos = {}  # input name -> position in self._input_values
        self._input_low, self._input_high = np.zeros(0), np.zeros(0)  # declared range (min/max) of each Real input
        self._violation = (None, None)  # (input values' bytes, bad input names) of the last range check
        self._mode = INSTANTIATED
        self._failure = ""  # why the instance is in the error state (repeated when a later call is refused)
        self._last_discard = ""  # why the last doStep was discarded ("" after a successful one)
        self._gen = 0  # counts changes of inputs, parameters and state: output caches compare it
        self._comp = None
        self._units = {}  # variable name -> unit of every Real variable (written by to_xml)
        self._checks = {}  # parameter name -> (unit, low, high, low_open, choices)
        self._kind = {}  # value reference -> "parameter" | "input" | "output"
        self._raw_get = {}  # value reference -> raw getter of a Real variable (fast path of get_real)
        self._in_vr = {}  # value reference of a Real input -> position in self._input_values
        self._blocks = {}  # value reference of a block output -> (block function, index in its array)
        self._set_plans = {}  # tuple of value references -> index array into self._input_values (or None: no fast path)
        self._get_plans = {}  # tuple of value references -> block plan (or None: no fast path)
        self._ranges = {}  # variable name -> (min, max) written into the model description
        self._deps = {}  # output name -> input names it depends on at communication points (None: all)
        self._init_deps = {}  # calculated output name -> input names it depends on in initialization mode
        self._status_from_log = bool(self.resources) and (Path(self.resources) / STATUS_FROM_LOG).is_file()
        self._describing = False  # True while to_xml reads the start values (the only get before initialization)
        self._build = self._build_options()

    def _build_options(self):
        """The build options of this FMU (``resources/frb_build.json``); defaults when there is none."""
        import json

        path = Path(self.resources) / BUILD_OPTIONS if self.resources else None
        opts = {"linearization": False}
        if path is not None and path.is_file():
            opts.update(json.loads(path.read_text(encoding="utf-8")))
        return opts

    def _changed(self):
        """Inputs, parameters or state changed: every cached output is stale."""
        self._gen += 1

    def _in(self, name):
        """Value of the Real input ``name`` (a float)."""
        return float(self._input_values[self._input_pos[name]])

    # ------------------------------------------------------------------ registration
    def _register(self, var, kind, unit):
        if isinstance(var, Real):
            if not unit:
                raise ValueError(f"{type(self).__name__}: Real variable {var.name!r} is registered without a unit")
            self._units[var.name] = unit
        self.register_variable(var, nested=False)
        self._kind[var.value_reference] = kind
        return var.value_reference

    def _param(self, name, value, desc, kind="real", unit=None, low=-math.inf, high=math.inf, low_open=False,
               choices=None):
        """Register a ``fixed`` parameter; ``low``/``high`` (``low_open``: low excluded) or ``choices`` are
        checked at fmi2ExitInitializationMode (:meth:`_check_parameters`)."""
        self._values[name] = value
        cls = {"real": Real, "int": Integer, "bool": Boolean, "str": String}[kind]
        var = cls(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed, description=desc,
                  getter=lambda n=name: self._values[n], setter=lambda v, n=name: self._set_param(n, v))
        vr = self._register(var, "parameter", unit)
        if kind == "real":
            self._raw_get[vr] = var.getter
            self._checks[name] = (unit, low, high, low_open, None)
            self._ranges[name] = (low, high)
        elif choices is not None:
            self._checks[name] = (None, None, None, False, tuple(choices))

    def _input(self, name, desc, start=0.0, unit=None, low=-math.inf, high=math.inf):
        """Register a continuous Real input (``low``/``high``: its valid range, written as min/max)."""
        self._ranges[name] = (low, high)
        k = self._input_values.size
        self._input_values = np.append(self._input_values, float(start))
        self._input_low, self._input_high = np.append(self._input_low, low), np.append(self._input_high, high)
        self._input_pos[name] = k
        var = Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous, description=desc,
                   getter=lambda k=k: float(self._input_values[k]), setter=lambda v, n=name: self._set_input(n, v))
        vr = self._register(var, "input", unit)
        self._raw_get[vr] = var.getter
        self._in_vr[vr] = k

    def _output(self, name, desc, fn, kind="real", unit=None, block=None, depends=None, init_depends=None,
                low=-math.inf, high=math.inf):
        """Register an output read by ``fn()``; ``block = (block_fn, index)``: it is also ``block_fn()[index]``,
        an array the slave computes once for many outputs (the fast path of :meth:`get_real`).

        ``depends``: the inputs it depends on at communication points (direct feedthrough; () none, None all);
        ``init_depends``: those it depends on in initialization mode (default ``depends``), besides the parameters.
        ``low``/``high``: its range (min/max). ``kind="const"``: an Integer constant ``fn()`` (a size)."""
        self._deps[name] = None if depends is None else tuple(depends)
        if kind == "const":
            var = Integer(name, causality=Fmi2Causality.output, variability=Fmi2Variability.constant,
                          initial=Fmi2Initial.exact, description=desc, getter=fn)
            self._register(var, "output", None)
            return
        if kind == "int":
            var = Integer(name, causality=Fmi2Causality.output, variability=Fmi2Variability.discrete,
                          initial=Fmi2Initial.calculated, description=desc,
                          getter=lambda f=fn, n=name: self._evaluate(n, f, int, 0))
        else:
            var = Real(name, causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                       initial=Fmi2Initial.calculated, description=desc,
                       getter=lambda f=fn, n=name: self._evaluate(n, f, float, math.nan))
        vr = self._register(var, "output", unit)
        self._init_deps[name] = self._deps[name] if init_depends is None else tuple(init_depends)
        if kind != "int":
            self._raw_get[vr] = fn
            self._ranges[name] = (low, high)
        if block is not None:
            self._blocks[vr] = block

    def _linearization_outputs(self, x_units, u_units, y_units, what, depends=None):
        """In an FMU built with the linearization option only (``frb build-fmus --linearization``): the Integer
        constants nx, nu, ny and the Real outputs A_i_j, B_i_j, C_i_j, D_i_j (1-based row i, column j) read from
        ``self._linear()`` for states, inputs and outputs of the units ``x_units``, ``u_units``, ``y_units`` (each
        entry's unit follows: A_i_j = unit(x_i)/(s unit(x_j)), ...); ``what`` = (states, inputs, outputs)
        descriptions; ``depends`` as for :meth:`_output`."""
        from frbmodel.cosim.units import ratio

        if not self._build["linearization"]:
            return
        for name, n, desc in (("nx", len(x_units), what[0]), ("nu", len(u_units), what[1]),
                              ("ny", len(y_units), what[2])):
            self._output(name, f"linearization: number of {desc}", lambda n=n: n, "const")
        for name, rows, cols, tp in (("A", x_units, x_units, -1), ("B", x_units, u_units, -1),
                                     ("C", y_units, x_units, 0), ("D", y_units, u_units, 0)):
            for i, ru in enumerate(rows):
                for k, cu in enumerate(cols):
                    self._output(f"{name}_{i + 1}_{k + 1}", f"linearization matrix {name}, row {i + 1}, column "
                                 f"{k + 1}", lambda name=name, i=i, k=k: self._linear()[name][i, k],
                                 unit=ratio(ru, cu, tp), depends=depends)

    def to_xml(self, model_options=None):
        """pythonfmu's model description plus what it does not write: units (``unit`` of each Real,
        UnitDefinitions), ranges (min/max), ModelStructure with the real dependencies
        (:mod:`frbmodel.cosim.fmu_description`). pythonfmu reads the start values through get_real etc. of this
        instance, which is in the instantiated state: :attr:`_describing` lets those reads through."""
        from frbmodel.cosim.fmu_description import finish
        from frbmodel.cosim.units import declare_units

        self._describing = True  # pythonfmu reads each start value through get_real etc.: let those through
        try:
            root = declare_units(super().to_xml(model_options or {}), self._units)
        finally:
            self._describing = False
        params = [v.name for v in self.vars.values() if self._kind[v.value_reference] == "parameter"]
        initial = {n: self._init_deps[n] for n in self._init_deps}
        return finish(root, self._ranges, self._deps, initial, params)

    # ------------------------------------------------------------------ status protocol
    def _refuse(self, msg):
        """Log ``msg`` with fmi2Error: the current FMI call is refused."""
        self.log(f"{self.instance_name}: {msg}", Fmi2Status.error)

    def _discard(self, msg):
        """Log ``msg`` with fmi2Discard: the current step or output cannot be computed from these inputs."""
        self.log(f"{self.instance_name}: {msg}", Fmi2Status.discard)

    # ------------------------------------------------------------------ set
    def _set_param(self, name, v):
        if self._mode not in (INSTANTIATED, INITIALIZATION):
            self._refuse(f"parameter {name} = {v!r} refused in {self._mode}: its variability is 'fixed', so it can "
                         f"only be set before fmi2ExitInitializationMode; it keeps its value {self._values[name]!r}")
            return
        self._values[name] = v
        self._changed()
        if self._mode == INITIALIZATION:
            self._comp = None  # outputs evaluated in initialization mode are rebuilt from the new parameters

    def _set_input(self, name, v):
        if self._mode in (TERMINATED, ERROR):
            self._refuse(f"input {name} = {v!r} refused in {self._mode}")
            return
        self._input_values[self._input_pos[name]] = float(v)
        self._changed()

    def set_real(self, vrs, values):
        if self._mode == STEP:  # fast path of the per-step traffic: inputs only, one array assignment
            key = tuple(vrs)
            idx = self._set_plans.get(key, False)
            if idx is False:
                if len(self._set_plans) >= MAX_PLANS:
                    self._set_plans.clear()
                idx = self._set_plans[key] = (np.array([self._in_vr[vr] for vr in key], dtype=np.intp)
                                              if all(vr in self._in_vr for vr in key) else None)
            if idx is not None:
                self._input_values[idx] = values
                self._changed()
                return
        self._set_each(vrs, values, Real)

    def set_integer(self, vrs, values):
        self._set_each(vrs, values, Integer)

    def set_boolean(self, vrs, values):
        self._set_each(vrs, values, Boolean)

    def set_string(self, vrs, values):
        self._set_each(vrs, values, String)

    def _set_each(self, vrs, values, cls):
        for vr, v in zip(vrs, values):
            var = self.vars.get(vr)
            if not isinstance(var, cls) or self._kind.get(vr) not in ("parameter", "input"):
                what = (f"no variable has value reference {vr}" if var is None else
                        f"{var.name} is not a {cls.__name__} variable" if not isinstance(var, cls) else
                        f"{var.name} is an output and cannot be set")
                self._refuse(f"set{cls.__name__} refused: {what}")
                continue
            var.setter(v)

    # ------------------------------------------------------------------ get
    def get_real(self, vrs):
        if self._comp is not None and self._mode in (STEP, TERMINATED) and not self._out_of_range():
            try:  # fast paths while every value is finite (otherwise the guarded path reports)
                out = self._get_blocks(vrs)
                if out is None:  # raw getters, one per variable
                    raw = self._raw_get
                    out = [float(raw[vr]()) for vr in vrs]
                if math.isfinite(sum(out)):
                    return out
            except Exception:  # noqa: BLE001  (the guarded path below reports it)
                pass
        return self._get_each(vrs, Real, math.nan)

    def _get_blocks(self, vrs):
        """The values of ``vrs`` read from the slave's output blocks by prepared index arrays, or None when one of
        them is not a block output."""
        key = tuple(vrs)
        plan = self._get_plans.get(key, False)
        if plan is False:
            if len(self._get_plans) >= MAX_PLANS:
                self._get_plans.clear()
            plan = self._get_plans[key] = self._block_plan(key)
        if plan is None:
            return None
        if len(plan) == 1:  # all from one block, in the requested order
            fn, _, src = plan[0]
            return fn()[src].tolist()
        out = np.empty(len(key))
        for fn, dst, src in plan:
            out[dst] = fn()[src]
        return out.tolist()

    def _block_plan(self, vrs):
        """``[(block_fn, positions in the request, indices in the block)]`` for ``vrs``, or None."""
        if not vrs or not all(vr in self._blocks for vr in vrs):
            return None
        groups = {}
        for pos, vr in enumerate(vrs):
            fn, index = self._blocks[vr]
            dst, src = groups.setdefault(fn, ([], []))
            dst.append(pos)
            src.append(index)
        return [(fn, np.array(dst, dtype=np.intp), np.array(src, dtype=np.intp)) for fn, (dst, src) in groups.items()]

    def get_integer(self, vrs):
        return self._get_each(vrs, Integer, 0)

    def get_boolean(self, vrs):
        return self._get_each(vrs, Boolean, False)

    def get_string(self, vrs):
        return self._get_each(vrs, String, "")

    def _get_each(self, vrs, cls, default):
        why = self._get_refusal(vrs, cls)
        if why is not None:
            self._refuse(why)
            return [default] * len(vrs)
        out = []
        for vr in vrs:
            var = self.vars.get(vr)
            if not isinstance(var, cls):
                what = f"no variable has value reference {vr}" if var is None else f"{var.name} is not a " \
                                                                                   f"{cls.__name__} variable"
                self._refuse(f"get{cls.__name__} refused: {what}")
                out.append(default)
            else:
                out.append(var.getter())
        return out

    def _get_refusal(self, vrs, cls):
        """Why fmi2Get<cls> of ``vrs`` is refused, or None: FMI 2.0 (section 4.2.4, the table of the co-simulation
        state machine) allows the getters from initialization mode on, not in the instantiated state, i.e. before
        fmi2EnterInitializationMode and after fmi2Reset (pythonfmu's reset makes a new slave, which cannot tell the
        two apart). The model description's start values are read in that state (:meth:`to_xml`)."""
        if self._mode != INSTANTIATED or self._describing:
            return None
        names = [self.vars[vr].name if vr in self.vars else f"value reference {vr}" for vr in vrs]
        shown = ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")
        call = f"fmi2Get{cls.__name__}"
        return (f"{call} of {shown or 'no variable'} refused in the instantiated state (before "
                f"fmi2EnterInitializationMode: a new instance, or one after fmi2Reset): FMI 2.0 allows {call} only "
                "from initialization mode on; no value is returned")

    def _evaluate(self, name, fn, cast, failed):
        """Value of the output ``name`` = ``fn()``, evaluated in initialization mode from the parameters and inputs
        set so far (initial="calculated"); after an error, without a component outside initialization mode, or
        when the evaluation fails or gives a non-finite value, ``failed`` with the reason logged (fmi2Error /
        fmi2Discard), never a silent NaN or 0."""
        if self._mode == ERROR:
            self._refuse(f"output {name} is not available: the instance failed ({self._failure})")
            return failed
        if self._comp is None:
            if self._mode != INITIALIZATION:  # (the getters refuse the instantiated state before this)
                self._refuse(f"output {name} is not available in {self._mode}: the instance was not initialized")
                return failed
            try:  # initialization mode: the outputs of the parameters and inputs set so far (initial="calculated")
                self._check_parameters()
                self._initialize()
            except Exception as exc:  # noqa: BLE001
                self._comp = None
                self._discard(f"output {name} cannot be evaluated in initialization mode: {exc}")
                return failed
        bad = self._range_message(name)
        if bad:
            self._discard(f"output {name} cannot be evaluated at the current inputs: {bad}")
            return failed
        try:
            value = cast(fn())
        except Exception as exc:  # noqa: BLE001
            self._discard(f"output {name} cannot be evaluated at the current inputs: {exc}")
            return failed
        if cast is float and not math.isfinite(value):
            self._discard(f"output {name} = {value} is not finite at the current inputs")
        return value

    def _out_of_range(self):
        """Names of the Real inputs that are not finite or outside their declared range (min/max of the model
        description), also those the slave's current settings do not use (a host that feeds NaN into the drive
        torque of a ramp-driven turbocharger has a bug worth naming), checked again only when an input value
        changed (the cache is keyed on the values' bytes, whichever path set them). A doStep and the reads after it
        cost one comparison of the values' bytes instead of a masked range test under numpy's error state each
        (3.0 µs): the main job's co-simulation calls it 800,000 times."""
        x = self._input_values
        key = x.tobytes()
        if self._violation[0] != key:
            bad = ~np.isfinite(x) | (x < self._input_low) | (x > self._input_high)  # (NaN compares False, silently)
            names = [n for n, k in self._input_pos.items() if bad[k]] if bad.any() else []
            self._violation = (key, names)
        return self._violation[1]

    @staticmethod
    def _check_unused_inputs(values_and_starts):
        """Raise ValueError for an oil-supply input that differs from its start value (to :data:`UNUSED_INPUT_RTOL`)
        while the parameter oil is empty: the films have constant viscosities, so the input would be ignored.
        ``values_and_starts``: (name, value, start value) triples."""
        for name, value, start in values_and_starts:
            if not math.isclose(value, start, rel_tol=UNUSED_INPUT_RTOL, abs_tol=0.0):
                raise ValueError(f"{name} = {float(value)!r} needs the thermal model: set the parameter oil (the films "
                                 f"have constant viscosities); leave the input at its start value {start!r} otherwise")

    def _range_message(self, output=None):
        """Why the inputs are out of range (those ``output`` depends on; all for a doStep), or ''."""
        names = self._out_of_range()
        if names and output is not None:
            deps = (self._init_deps if self._mode == INITIALIZATION else self._deps).get(output)
            names = names if deps is None else [n for n in names if n in deps]
        msgs = []
        for n in names:
            k, u = self._input_pos[n], self._units.get(n, "")
            u = "" if u in ("", "1") else f" {u}"
            lo, hi = self._input_low[k], self._input_high[k]
            value = float(self._input_values[k])
            rng = f"{'[' if math.isfinite(lo) else '('}{lo:g}, {hi:g}{']' if math.isfinite(hi) else ')'}{u}"
            if math.isfinite(value):
                msgs.append(f"input {n} = {value!r}{u} is invalid: valid range {rng}")
            else:
                bounded = math.isfinite(lo) or math.isfinite(hi)
                msgs.append(f"input {n} = {value!r}{u} is invalid: it must be finite"
                            + (f" (valid range {rng})" if bounded else ""))
        return "; ".join(msgs)

    # ------------------------------------------------------------------ state machine
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        if self._mode != INSTANTIATED:
            self._refuse(f"fmi2SetupExperiment called in {self._mode}; it is only allowed after fmi2Instantiate")

    def enter_initialization_mode(self):
        if self._mode != INSTANTIATED:
            self._refuse(f"fmi2EnterInitializationMode called in {self._mode}; it is only allowed once, after "
                         "fmi2Instantiate")
            return
        self._mode = INITIALIZATION

    def exit_initialization_mode(self):
        """Check the version and the parameters and build the component (the slave's ``_initialize``). A failure
        leaves the instance in the error state with the reason logged (fmi2Error); it can still be freed."""
        if self._mode != INITIALIZATION:
            self._refuse(f"fmi2ExitInitializationMode called in {self._mode}; call fmi2EnterInitializationMode "
                         "first")
            return
        try:
            msg = self._check_version()
            if msg is None:
                self._check_parameters()
                self._initialize()
        except Exception as exc:  # noqa: BLE001  (any parameter problem is an FMI error, not a crash)
            msg = f"invalid parameters or input start values: {exc}"
        if msg is None:
            self._mode = STEP
            self._changed()
            return
        self._mode, self._comp, self._failure = ERROR, None, msg
        self._refuse(msg)
        if not self._status_from_log:
            raise RuntimeError(msg)

    def _check_parameters(self):
        """ValueError naming each parameter outside its declared range or values (quantity, value, range)."""
        bad = []
        for name, (unit, low, high, low_open, choices) in self._checks.items():
            v = self._values[name]
            if choices is not None:
                if v not in choices:
                    bad.append(f"{name} = {v!r} is invalid: valid values {', '.join(map(repr, choices))}")
                continue
            try:
                x = float(v)
            except (TypeError, ValueError):
                x = math.nan
            if not (math.isfinite(x) and (x > low if low_open else x >= low) and x <= high):
                rng = f"{'(' if low_open else '['}{low:g}, {high:g}{']' if math.isfinite(high) else ')'}"
                u = "" if unit == "1" else f" {unit}"
                if not (math.isfinite(low) or math.isfinite(high)):  # (it read "valid range [-inf, inf) m")
                    bad.append(f"{name} = {v!r}{u} is invalid: it must be a finite real number")
                else:
                    bad.append(f"{name} = {v!r}{u} is invalid: valid range {rng}{u}")
        if bad:
            raise ValueError("; ".join(bad))

    def terminate(self):
        """fmi2Terminate: allowed in step mode only (FMI 2.0 section 4.2.4: after initialization, a discarded doStep
        included); elsewhere refused (fmi2Error) with the mode unchanged, so that an instance terminated before
        its initialization can still be initialized or freed (it went to the terminated state, refused every call
        after it and read 0 with fmi2OK). Returns whether the instance is terminated now."""
        if self._mode != STEP:
            why = {INSTANTIATED: "before initialization (fmi2ExitInitializationMode); the instance can still be "
                                 "initialized",
                   INITIALIZATION: "in initialization mode (call fmi2ExitInitializationMode first)",
                   TERMINATED: "again: the instance is terminated already",
                   ERROR: f"after the instance failed ({self._failure}); it can be reset or freed"}[self._mode]
            self._refuse(f"fmi2Terminate called {why}")
            return False
        self._mode = TERMINATED
        return True

    def do_step(self, current_time, step_size):
        """One communication step: refused (fmi2Error) or discarded (fmi2Discard, the state is restored) with the
        reason logged, see the class description. The slave's ``_advance(t, h)`` does the step."""
        why = self._step_refusal(current_time, step_size)
        if why is not None:
            self._refuse(why)
            return False
        saved = self._component_state()
        try:
            bad = self._range_message()
            if bad:
                raise ValueError(bad)
            self._advance(current_time, step_size)
        except Exception as exc:  # noqa: BLE001
            self._set_component_state(saved)
            self._changed()
            at = getattr(self._comp, "t", None)  # the component's own time where it has one (a skipped step)
            at = current_time if not isinstance(at, float) else at
            self._last_discard = (f"doStep from t = {current_time:.6g} s by {step_size:.3g} s discarded, the state "
                                  f"stays at t = {at:.6g} s: {self._step_context()}{exc}")
            self._discard(self._last_discard)
            return False
        self._last_discard = ""
        self._changed()
        return True

    def _step_refusal(self, t, h):
        """Why a doStep at ``t`` by ``h`` [s] is refused, or None."""
        if self._mode != STEP:
            return {INSTANTIATED: "doStep called before initialization (fmi2ExitInitializationMode)",
                    INITIALIZATION: "doStep called in initialization mode (call fmi2ExitInitializationMode first)",
                    TERMINATED: "doStep called after fmi2Terminate",
                    ERROR: f"doStep called after the instance failed ({self._failure})"}[self._mode]
        if not (math.isfinite(h) and h > 0):
            return f"doStep communicationStepSize = {h!r} s is invalid: valid range (0, inf) s"
        if not math.isfinite(t):
            return f"doStep currentCommunicationPoint = {t!r} s is invalid: it must be finite"
        return None

    def _step_context(self):
        """Prefix of a discard message (e.g. the rotor speed); empty by default."""
        return ""

    # FMU state (fmi2GetFMUstate / SetFMUstate, used for rollback): the parameter and input values, the mode and
    # the component's own state — not pythonfmu's default, which calls every getter (all outputs, all linearization
    # matrices) and cannot bring a slave back after a failed step.
    def _get_fmu_state(self):
        state = {"_values": dict(self._values), "_input_values": self._input_values.copy(), "_mode": self._mode,
                 "_failure": self._failure}
        if self._comp is not None:
            state["_component"] = self._component_state()
        return state

    def _set_fmu_state(self, state):
        """Restore a state of :meth:`_get_fmu_state`. An instance without a component (after fmi2Reset, or a new
        one) builds it from the state's parameters first: it would step nothing and read 0 otherwise. A state that
        cannot be restored is refused (fmi2Error) and leaves the instance as it was."""
        comp = state.get("_component")
        if comp is not None and self._comp is None:
            old = self._values, self._input_values.copy()
            self._values, self._input_values[:] = dict(state["_values"]), state["_input_values"]
            try:
                self._check_parameters()
                self._initialize()
            except Exception as exc:  # noqa: BLE001
                self._values, self._input_values[:], self._comp = old[0], old[1], None
                self._refuse(f"fmi2SetFMUstate refused: the state's component cannot be rebuilt: {exc}")
                return
        self._values = dict(state["_values"])
        self._input_values[:] = state["_input_values"]
        self._mode, self._failure = state["_mode"], state.get("_failure", "")
        if self._comp is not None and comp is not None:
            self._set_component_state(comp)
        elif comp is None and self._mode in (INSTANTIATED, INITIALIZATION):
            self._comp = None  # a state taken before the component existed: it is built at initialization again
        self._changed()

    # FMU state serialization (fmi2SerializeFMUstate): the state above as JSON, arrays tagged so they come back as
    # arrays; floats round-trip exactly (JSON writes their shortest repr)
    @staticmethod
    def _fmu_state_to_bytes(state):
        import json

        def encode(x):
            if isinstance(x, np.ndarray):
                return {"__ndarray__": x.tolist(), "dtype": str(x.dtype)}
            if isinstance(x, np.generic):
                return x.item()
            raise TypeError(f"cannot serialize {type(x).__name__}")

        return json.dumps(state, default=encode).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(data):
        import json

        def decode(d):
            return np.array(d["__ndarray__"], dtype=d["dtype"]) if "__ndarray__" in d else d

        return json.loads(bytes(data).decode("utf-8"), object_hook=decode)

    def _check_version(self):
        """Refuse to start if the imported frbmodel is not the bundled version (pythonfmu slaves share the
        host's sys.modules, so a host with another frbmodel would silently replace ours)."""
        import frbmodel

        bundled = None
        if self.resources:
            init = Path(self.resources) / "frbmodel" / "core" / "version.py"
            if init.exists():
                m = re.search(r'__version__\s*=\s*"([^"]+)"', init.read_text(encoding="utf-8"))
                bundled = m.group(1) if m else None
        if bundled is not None and bundled != frbmodel.__version__:
            return (f"frbmodel version mismatch: this FMU bundles frbmodel {bundled} but the process imported "
                    f"frbmodel {frbmodel.__version__} from {Path(frbmodel.__file__).parent}; use the same version "
                    "(rebuild the FMUs or run them in a process without another frbmodel)")
        return None


def import_bundled_package_from_stable_copy(name="frbmodel", resources=None):
    """Make ``import frbmodel`` use a per-user copy of this FMU's bundled package that outlives the extraction.

    Hosts unzip an FMU into a new folder at every start; numba finds its cached kernels by the source file's path
    and modification time, so a package imported from the fresh folder recompiles every kernel (8-12 s) at every
    start. The copy ``$XDG_CACHE_HOME/frbmodel/fmu-pkg/<version>-<content hash>/<name>`` (default ``~/.cache``)
    is made once per package content and reused afterwards together with the numba cache numba writes into it.
    Nothing changes when ``name`` is already imported (a Python host with its own frbmodel, or an FMU instantiated
    before in this process; ``_check_version`` compares the versions) or when the copy cannot be made or does not
    match (e.g. a read-only home): the bundled folder is then imported as before, with a warning. Called when this
    module is first imported and again by every slave before it imports the package (:meth:`FrbSlaveMixin._init_state`):
    this module is imported once per process, from the first FMU's folder, and pythonfmu puts each further FMU's
    resources folder first on ``sys.path``, which would otherwise shadow the copy (measured in ecos: an engine FMU
    instantiated before the turbocharger FMU made the latter recompile its kernels at every start, 17 s).

    Parameters
    ----------
    name : str
        The package bundled in the FMU's resources folder.
    resources : str or Path, optional
        That folder (default: the folder of this file).

    Returns
    -------
    pathlib.Path or None
        The folder put first on ``sys.path``, or None if nothing was changed.
    """
    import hashlib
    import os
    import shutil
    import sys
    import tempfile
    import warnings

    src = (Path(resources) if resources else Path(__file__).resolve().parent) / name
    if name in sys.modules or not (src / "__init__.py").is_file():
        return None

    def digest(root):  # the package's sources, not the caches written into it
        h = hashlib.sha256()
        for f in sorted(root.rglob("*")):
            rel = f.relative_to(root)
            if f.is_file() and "__pycache__" not in rel.parts and f.suffix not in (".pyc", ".nbi", ".nbc"):
                h.update(rel.as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
        return h.hexdigest()[:16]

    try:
        m = re.search(r'__version__\s*=\s*"([^"]+)"', (src / "core" / "version.py").read_text(encoding="utf-8"))
        content = digest(src)
        cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "frbmodel" / "fmu-pkg"
        dest = cache / f"{m.group(1) if m else 'unknown'}-{content}"
        if not (dest / name / "__init__.py").is_file():
            cache.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}-", dir=cache))
            shutil.copytree(src, tmp / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc"))
            try:
                os.rename(tmp, dest)  # atomic: concurrent first starts never see a half-made copy
            except OSError:  # another process made it first
                shutil.rmtree(tmp, ignore_errors=True)
        if digest(dest / name) != content:
            raise OSError(f"{dest / name} differs from the bundled {name}")
    except (OSError, RuntimeError, KeyError) as exc:
        warnings.warn(f"{name}: no stable copy outside the FMU ({exc}); importing the bundled copy, whose numba "
                      "kernels recompile at every start", RuntimeWarning, stacklevel=2)
        return None
    if str(dest) in sys.path:
        sys.path.remove(str(dest))
    sys.path.insert(0, str(dest))
    return dest


import_bundled_package_from_stable_copy()
