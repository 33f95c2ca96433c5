"""Co-simulation master for SSP systems around the whole-turbocharger FMU (``FloatingRingTurbocharger``), such as
the repository's example of an engine side driving it (``build/engine_turbocharger.ssp``).

A plain fixed-step Jacobi scheme over the SSP's connections, as a system-simulation tool runs it: at every
communication point each FMU's connected outputs are read (one getReal per FMU), passed to the inputs they are
connected to (one setReal per FMU), then every FMU steps. Outputs that depend directly on an input of their own FMU
(ModelStructure) are read after that FMU's inputs are set, in an order that follows those dependencies, so a chain
such as turbocharger speed -> engine torque -> turbocharger torque is passed within one communication point. The
turbocharger FMU integrates itself with error control (its own step inside any macro step), so this master needs
no rollback or step control; every FMI call goes through :class:`~frbmodel.cosim.fmu.FmuInstance` (status checked,
optional trace).

Results: the turbocharger FMU writes the run-up's result files itself at its ``check_rate`` (``record_folder``,
set by :meth:`SystemMaster.run` to ``out_dir``), so a run at a 1 ms macro step still has 20 kHz orbits for the
spectrogram and the composite figures; the master adds ``signals.csv`` with every connected value at every
communication point.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..core.errors import CosimStopped, ParameterError
from ..core.interrupt import deferred_signals
from ..core.progress import simulation_bar
from ..nonlinear.recorder import RunupResult
from .fmu import FmuHost
from .loader import model_identifier
from .ssp import read_ssp

TURBOCHARGER_FMU = "FloatingRingTurbocharger"


def is_system_ssp(ssp) -> bool:
    """True if the SSP has a whole-turbocharger FMU (run by :class:`SystemMaster`, not by the split's master).

    Parameters
    ----------
    ssp : str or Path
        ``.ssp`` archive or folder.

    Returns
    -------
    bool
    """

    with read_ssp(ssp, require_fmus=False) as s:
        return any(Path(f).is_file() and model_identifier(f) == TURBOCHARGER_FMU for f in s.components.values())


class SystemMaster(FmuHost):
    """Fixed-step Jacobi co-simulation of an SSP system with one turbocharger FMU (see the module description).

    Parameters
    ----------
    ssp : str or Path
        ``.ssp`` archive or folder.
    parameter_set : str, optional
        Parameter set of the SSP (default: the one its SystemStructure.ssd binds).
    stop_time, step_size : float, optional
        Default: the SSP's DefaultExperiment stop time and OSP fixed step [s].
    overrides : dict, optional
        ``{component: {parameter: (type, value)}}`` applied after the parameter set.
    trace : callable, optional
        Receives one line per FMI call (``frb cosim --trace-fmi``).

    Notes
    -----
    Use it as a context manager (or call :meth:`close`): the FMU instances are freed, the extracted files deleted.
    """

    def __init__(self, ssp, parameter_set=None, stop_time=None, step_size=None, overrides=None, trace=None):
        self.ssp_path, self.trace = ssp, trace
        self.ssp = read_ssp(ssp)
        self.fmus, self._tmp = {}, None
        try:
            self.parameter_set = parameter_set or self.ssp.default_set
            self.params = self.ssp.parameters(self.parameter_set)
            for comp, ov in (overrides or {}).items():
                if comp not in self.ssp.components:
                    raise ParameterError(f"override for component {comp!r}: the SSP has no such component; "
                                         f"components are {sorted(self.ssp.components)}")
                self.params.setdefault(comp, {}).update(ov)
            self.stop_time = float(stop_time if stop_time is not None else (self.ssp.stop_time or 1.0))
            self.step_size = float(step_size if step_size is not None else (self.ssp.step_size or 1e-3))
            H, T = self.step_size, self.stop_time
            if not (math.isfinite(H) and math.isfinite(T) and 0 < H <= T):
                raise ParameterError(f"step size = {H!r} s and stop time = {T!r} s are invalid: both finite, "
                                     "0 < step size <= stop time")
        except BaseException:
            self.ssp.close()
            raise
        self.steps_taken, self.fmi_time_s = 0, 0.0

    # ------------------------------------------------------------------ set-up
    def setup(self):
        """Extract and instantiate every FMU, find the turbocharger, plan the exchange."""
        self._instantiate("frb_system_")
        turbo = [f for f in self.fmus.values() if f.model_identifier == TURBOCHARGER_FMU]
        if len(turbo) != 1:
            raise ParameterError(f"{self.ssp_path}: the system needs exactly one {TURBOCHARGER_FMU} component, "
                                 f"found {[f.name for f in turbo]}")
        self.turbocharger = turbo[0]
        self._plan()
        return self

    def _plan(self):
        """The exchange as an ordered list of (source FMU, its output value references, [(destination FMU, input
        value references, positions in the source's values)]): sources whose outputs depend directly on their own
        connected inputs come after the sources feeding those inputs."""
        links = {}
        for s_el, s_c, e_el, e_c in self.ssp.connections:
            src, dst = self.fmus[s_el], self.fmus[e_el]
            links.setdefault(s_el, []).append((src.vr([s_c])[0], dst, dst.vr([e_c])[0], s_c, e_c))
        feeds = {name: {dst.name for _, dst, _, _, _ in lk} for name, lk in links.items()}
        order, pending = [], dict(links)
        while pending:  # a source goes once no pending source feeds an input its outputs depend on
            ready = [n for n in pending if not any(n in feeds[m] and self._feedthrough(n, links[n]) for m in pending
                                                   if m != n)]
            if not ready:
                raise ParameterError(f"{self.ssp_path}: the connections form an algebraic loop through direct "
                                     f"feedthrough ({sorted(pending)}); a Jacobi master cannot pass it within one "
                                     "communication point")
            for n in ready:
                order.append(n)
                del pending[n]
        self._phases = []
        for n in order:
            lk = links[n]
            out_vr = [s for s, *_ in lk]
            per_dst = {}
            for i, (_, dst, dvr, _, _) in enumerate(lk):
                per_dst.setdefault(dst.name, (dst, [], []))
                per_dst[dst.name][1].append(dvr)
                per_dst[dst.name][2].append(i)
            self._phases.append((self.fmus[n], out_vr, list(per_dst.values())))
        self.signal_names = [f"{n}.{s_c}" for n in order for *_, s_c, _ in links[n]]

    def _feedthrough(self, name, links):
        """True if an output of FMU ``name`` in ``links`` depends directly on one of its inputs (ModelStructure;
        no dependencies attribute: on all)."""
        md = self.fmus[name].md
        outs = {lk[3] for lk in links}
        for u in md.outputs:
            if u.variable.name in outs and (u.dependencies is None or u.dependencies):
                return True
        return False

    # ------------------------------------------------------------------ run
    def initialize(self, record_folder=None):
        """setupExperiment and the parameters in initialization mode (the turbocharger's ``record_folder`` if given),
        one exchange there (outputs are calculated in initialization mode), exit, then the first exchange."""
        params = {n: dict(p) for n, p in self.params.items()}
        if record_folder is not None:
            params.setdefault(self.turbocharger.name, {})["record_folder"] = ("String", str(record_folder))
        for fmu in self.fmus.values():
            fmu.call("setupExperiment", None, 0.0, self.stop_time)
            fmu.call("enterInitializationMode")
            fmu.set_parameters(params.get(fmu.name, {}))
        self.exchange()
        for fmu in self.fmus.values():
            fmu.call("exitInitializationMode")
        return self.exchange()

    def exchange(self):
        """Pass every connected value at the current communication point; returns them (order of
        :attr:`signal_names`)."""
        t0 = time.perf_counter()
        out = []
        try:
            for src, out_vr, dsts in self._phases:
                vals = src.call("getReal", out_vr)
                if not math.isfinite(sum(vals)):
                    raise CosimStopped(f"{src.name}: non-finite output among its connected outputs, with status OK")
                for dst, dvr, idx in dsts:
                    dst.call("setReal", dvr, [vals[i] for i in idx])
                out += vals
        finally:
            self.fmi_time_s += time.perf_counter() - t0
        return out

    def step(self, t, h):
        """Step every FMU from ``t`` by ``h`` [s], then exchange; returns the exchanged values."""
        t0 = time.perf_counter()
        try:
            for fmu in self.fmus.values():
                fmu.call("doStep", t, h, True)
        finally:
            self.fmi_time_s += time.perf_counter() - t0
        self.steps_taken += 1
        return self.exchange()

    def run(self, out_dir=None, progress=False):
        """Set up, initialize and step to the stop time. With ``out_dir``: the turbocharger FMU's record there
        (``runup.csv``, ``runup.json``) and ``signals.csv`` (time and connected values at every communication
        point). Returns the turbocharger's record as a :class:`~frbmodel.nonlinear.recorder.RunupResult` (None without
        ``out_dir``); raises :class:`CosimStopped` (``.result``: the record so far) when an FMU fails."""

        H, T = self.step_size, self.stop_time
        n = int(round(T / H))
        t_wall = time.perf_counter()
        status, message = "finished", ""
        out = None if out_dir is None else Path(out_dir)
        rows = []
        try:
            if not self.fmus:
                self.setup()
            rows.append([0.0] + self.initialize(None if out is None else out.resolve()))
            with deferred_signals() as signals, simulation_bar(T, "cosim", progress) as bar:
                for k in range(n):
                    t = k * H
                    rows.append([t + H] + self.step(t, H))
                    signals.check()
                    if k % 100 == 0:
                        bar.update(t + H - bar.n)
        except CosimStopped as exc:
            status, message = "stopped", str(exc)
        except KeyboardInterrupt:  # Ctrl-C / SIGTERM: the FMU closes its record as finished when freed; it was not
            self.close()
            if out is not None:
                self._write_signals(out, rows)
                _mark_record(out, "interrupted", f"interrupted at t = {rows[-1][0]:.6g} s; results up to there are "
                             "kept")
            raise
        finally:
            self.close()
        self.wall_time_s = time.perf_counter() - t_wall
        result = None
        if out is not None:
            self._write_signals(out, rows)
            if status != "finished":
                _mark_record(out, status, message)
            if (out / "runup.json").is_file():
                result = RunupResult.load(out)
                result.meta.update(master=self.meta(), wall_time_s=self.wall_time_s, fmi_time_s=self.fmi_time_s)
        if status != "finished":
            raise CosimStopped(message, result)
        return result

    def meta(self):
        """What the master did (for the result's metadata)."""
        return {"ssp": str(self.ssp_path), "parameter_set": self.parameter_set, "step_size_s": self.step_size,
                "stop_time_s": self.stop_time, "steps_taken": self.steps_taken,
                "master": "frbmodel.cosim.system_master (fmpy FMU2Slave, fixed-step Jacobi)"}

    def _write_signals(self, out, rows):
        import pandas as pd

        out.mkdir(parents=True, exist_ok=True)
        units = {"rotor_speed": "rad/s", "drive_torque": "N m"}
        cols = ["time [s]"] + [f"{n} [{units.get(n.split('.')[-1], '?')}]" for n in self.signal_names]
        pd.DataFrame(np.array(rows), columns=cols).to_csv(out / "signals.csv", index=False)



def _mark_record(out, status, message):
    """Set the status and message of the turbocharger's record in ``out`` (the FMU cannot know that the master
    stopped or was interrupted)."""
    import json

    path = Path(out) / "runup.json"
    if path.is_file():
        meta = json.loads(path.read_text())
        meta.update(status=status, message=message)
        path.write_text(json.dumps(meta, indent=2, default=str))


__all__ = ["SystemMaster", "is_system_ssp", "TURBOCHARGER_FMU"]
