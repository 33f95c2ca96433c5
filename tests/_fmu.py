"""A plain fmpy FMU2Slave loop for the tests (as any Python host drives an FMU)."""
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


class Slave:
    """One FMU instance driven through fmpy's FMU2Slave (a plain FMI loop, as any Python host)."""

    def __init__(self, fmu, name, tmp, params=None):
        self.md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        d = extract(str(fmu), unzipdir=str(tmp / name))
        self.s = FMU2Slave(guid=self.md.guid, unzipDirectory=d, modelIdentifier=self.md.coSimulation.modelIdentifier,
                           instanceName=name)
        self.s.instantiate()
        self.s.setupExperiment(startTime=0.0)
        self.s.enterInitializationMode()
        for k, v in (params or {}).items():
            setter = self.s.setString if isinstance(v, str) else self.s.setReal
            setter([self.vr[k]], [v])
        self.s.exitInitializationMode()

    def get(self, names):
        return np.array(self.s.getReal([self.vr[n] for n in names]))

    def set(self, values):
        self.s.setReal([self.vr[n] for n in values], list(values.values()))

    def run(self, h, t_end, names, inputs=None, every=None):
        """Step by ``h`` to ``t_end``; returns (times, outputs) at every ``every`` [s] (default every step);
        ``inputs(t)`` -> dict set before each step."""
        n = int(round(t_end / h))
        ts, ys = [], []
        for k in range(n):
            if inputs is not None:
                self.set(inputs(k * h))
            self.s.doStep(k * h, h)
            t = (k + 1) * h
            if every is None or abs(t / every - round(t / every)) < 1e-6:
                ts.append(t)
                ys.append(self.get(names))
        return np.array(ts), np.array(ys)

    def close(self):
        self.s.terminate()
        self.s.freeInstance()
