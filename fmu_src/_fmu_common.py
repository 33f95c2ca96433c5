"""Helpers shared by the frbmodel FMU slaves (bundled into each FMU next to the slave script)."""
import math
import re
from pathlib import Path

from pythonfmu import Boolean, Fmi2Causality, Fmi2Initial, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status


class FrbSlaveMixin:
    """Variable registration with explicit getters/setters, version check and error logging."""

    def _init_state(self):
        """Common slave state: variable values, readiness, last failure, output cache flag, the component."""
        self._values = {}
        self._ready = False
        self._failed = None
        self._dirty = True
        self._comp = None
        self._raw_get = {}  # value reference -> raw getter of a Real variable (fast path of get_real)
        self._set_name = {}  # value reference -> name in self._values of a Real input or parameter

    def _param(self, name, value, desc, kind="real"):
        self._values[name] = value
        cls = {"real": Real, "int": Integer, "bool": Boolean, "str": String}[kind]
        var = cls(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed, description=desc,
                  getter=lambda n=name: self._values[n], setter=lambda v, n=name: self._set_param(n, v))
        self.register_variable(var, nested=False)
        if kind == "real":
            self._raw_get[var.value_reference] = var.getter
            self._set_name[var.value_reference] = name

    def _set_param(self, name, v):
        self._values[name] = v
        self._dirty = True

    def _input(self, name, desc, start=0.0):
        self._values[name] = start
        var = Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous, description=desc,
                   getter=lambda n=name: self._values[n], setter=lambda v, n=name: self._set_input(n, v))
        self.register_variable(var, nested=False)
        self._raw_get[var.value_reference] = var.getter
        self._set_name[var.value_reference] = name

    def _set_input(self, name, v):
        self._values[name] = float(v)
        self._dirty = True

    def _output(self, name, desc, fn, kind="real"):
        if kind == "int":
            var = Integer(name, causality=Fmi2Causality.output, variability=Fmi2Variability.discrete,
                          initial=Fmi2Initial.exact, description=desc, getter=lambda f=fn: int(self._safe(f)))
        else:
            var = Real(name, causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                       initial=Fmi2Initial.exact, description=desc, getter=lambda f=fn: float(self._safe(f)))
        self.register_variable(var, nested=False)
        if kind != "int":
            self._raw_get[var.value_reference] = fn

    # Fast paths for the per-macro-step traffic (pythonfmu's generic loop checks types and goes through the
    # guarded getters one by one): read all requested values with the raw getters while the slave is healthy, and
    # fall back to the guarded per-variable path (zeros before initialization, logging + NaN on failure) otherwise.
    def get_real(self, vrs):
        if self._ready and self._failed is None:
            try:
                raw = self._raw_get
                return [float(raw[vr]()) for vr in vrs]
            except Exception:  # noqa: BLE001  (the guarded path below logs it)
                pass
        return super().get_real(vrs)

    def set_real(self, vrs, values):
        try:
            names = [self._set_name[vr] for vr in vrs]
        except KeyError:  # an output or unknown reference: pythonfmu reports it
            return super().set_real(vrs, values)
        for n, v in zip(names, values):
            self._values[n] = float(v)
        self._dirty = True

    def _linearization_outputs(self, nx, nu, ny, what):
        """Integer outputs nx, nu, ny and Real outputs A[i,j], B[i,j], C[i,j], D[i,j] (1-based, row-major) read
        from ``self._linear()``; ``what`` = (states, inputs, outputs) descriptions."""
        for name, n, desc in (("nx", nx, what[0]), ("nu", nu, what[1]), ("ny", ny, what[2])):
            self._output(name, f"linearization: number of {desc}", lambda n=n: n, "int")
        for name, (nr, nc) in (("A", (nx, nx)), ("B", (nx, nu)), ("C", (ny, nx)), ("D", (ny, nu))):
            for i in range(nr):
                for k in range(nc):
                    self._output(f"{name}[{i + 1},{k + 1}]", f"linearization matrix {name} (row-major, 1-based)",
                                 lambda name=name, i=i, k=k: self._linear()[name][i, k])

    def _safe(self, fn):
        """Evaluate an output. Before initialization outputs read 0; if the evaluation fails (e.g. a film at
        its wall) the error is logged and the output reads NaN — an exception here would make pythonfmu report
        fmi2Fatal — and the next doStep returns Discard."""
        if not getattr(self, "_ready", False):
            return 0
        try:
            return fn()
        except Exception as exc:  # noqa: BLE001
            if self._failed is None:
                self._error(f"{self.instance_name}: output evaluation failed: {exc}")
            self._ready = False
            return math.nan

    # FMU state (fmi2GetFMUstate / SetFMUstate, used for rollback): the variable values, the health flags and the
    # component's own state — not pythonfmu's default, which calls every getter (all outputs, all linearization
    # matrices) and cannot bring a slave back after a failed step.
    def _get_fmu_state(self):
        state = {"_values": dict(self._values), "_ready": self._ready, "_failed": self._failed}
        if self._comp is not None:
            state["_component"] = self._component_state()
        return state

    def _set_fmu_state(self, state):
        self._values = dict(state["_values"])
        self._ready, self._failed = state["_ready"], state["_failed"]
        if self._comp is not None and state.get("_component") is not None:
            self._set_component_state(state["_component"])
        self._dirty = True

    def _error(self, msg):
        self.log(msg, Fmi2Status.error)
        self._failed = msg
        return False

    def _require_version(self):
        msg = self._check_version()
        if msg:
            self._error(msg)
            raise RuntimeError(msg)

    def _check_version(self):
        """Refuse to start if the imported frbmodel is not the bundled version (pythonfmu slaves share the
        host's sys.modules, so a host with another frbmodel would silently replace ours)."""
        import frbmodel

        bundled = None
        if self.resources:
            init = Path(self.resources) / "frbmodel" / "__init__.py"
            if init.exists():
                m = re.search(r'__version__\s*=\s*"([^"]+)"', init.read_text())
                bundled = m.group(1) if m else None
        if bundled is not None and bundled != frbmodel.__version__:
            return (f"frbmodel version mismatch: this FMU bundles frbmodel {bundled} but the process imported "
                    f"frbmodel {frbmodel.__version__} from {Path(frbmodel.__file__).parent}; use the same version "
                    "(rebuild the FMUs or run them in a process without another frbmodel)")
        return None


def finite(name, v, lo=-math.inf, hi=math.inf, unit=""):
    v = float(v)
    if not (math.isfinite(v) and lo <= v <= hi):
        raise ValueError(f"{name} = {v!r} {unit} is invalid: valid range [{lo:g}, {hi:g}] {unit}".replace("  ", " "))
    return v
