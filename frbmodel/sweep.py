"""Parameter studies on Dask: grids or lists of cases × an analysis, resumable, with a stability map.

A *case* is a set of system parameters (outer clearance, viscosities, unbalance, ring mass, ...) and an analysis:
``campbell`` (linear, given methods), ``runup`` (monolithic nonlinear run-up) or ``cosim`` (co-simulated
run-up through the FMUs). Cases run as Dask tasks — on a ``distributed.LocalCluster`` (one worker process per
core) by default, or on an existing cluster (``scheduler="tcp://host:port"``), or in-process
(``scheduler="serial"``). Every finished case is written at once to ``<out>/cases/<id>.json`` (atomic rename), a
failing case too (with its error); ``<out>/index.csv`` lists all cases. Rerunning a study skips the finished
ones, so a killed study loses no finished case.
"""
from __future__ import annotations

import hashlib
import json
import os
import time
import traceback
from dataclasses import asdict, dataclass, field
from itertools import product
from pathlib import Path

import numpy as np

from .errors import ParameterError

#: parameters a study can vary (name -> (unit, description))
PARAMETERS = {
    "outer_clearance": ("m", "radial clearance of both outer films"),
    "inner_clearance": ("m", "radial clearance of both inner films"),
    "viscosity_turbine": ("Pa s", "oil viscosity of both films of the turbine bearing"),
    "viscosity_compressor": ("Pa s", "oil viscosity of both films of the compressor bearing"),
    "viscosity_scale": ("-", "factor on all film viscosities (oil temperature)"),
    "ring_mass": ("kg", "mass of both rings"),
    "unbalance_turbine": ("kg m", "unbalance of the turbine wheel"),
    "unbalance_compressor": ("kg m", "unbalance of the compressor wheel"),
}
ANALYSES = ("campbell", "runup", "cosim")


@dataclass
class Case:
    """One case of a study: ``params`` {name: value (SI)}, ``analysis`` and its ``options``."""

    params: dict
    analysis: str
    options: dict = field(default_factory=dict)

    @property
    def case_id(self) -> str:
        key = json.dumps({"p": self.params, "a": self.analysis, "o": self.options}, sort_keys=True)
        readable = "_".join(f"{k}={v:.4g}" for k, v in sorted(self.params.items())) or "base"
        return f"{self.analysis}_{readable}_{hashlib.sha1(key.encode()).hexdigest()[:8]}".replace("/", "-")


def grid(params: dict, analysis="campbell", **options):
    """Cases for the Cartesian product of ``params`` {name: list of values}."""
    names = list(params)
    for n in names:
        if n not in PARAMETERS:
            raise ParameterError(f"study parameter = {n!r} is unknown; valid: {', '.join(PARAMETERS)}")
    if analysis not in ANALYSES:
        raise ParameterError(f"analysis = {analysis!r} is unknown; valid: {', '.join(ANALYSES)}")
    return [Case(dict(zip(names, map(float, vals))), analysis, options) for vals in product(*(params[n] for n in names))]


def build_case_system(params, base=None):
    """System and unbalance list of a case (SI parameters applied to ``base``, default the Table 2 system)."""
    from dataclasses import replace

    from .presets import turbocharger
    from .runup import Unbalance

    tc = base or turbocharger()
    p = dict(params)
    if "outer_clearance" in p:
        tc = tc.with_outer_clearance(p.pop("outer_clearance"))
    bs = list(tc.bearings)
    if "inner_clearance" in p:
        c = p.pop("inner_clearance")
        bs = [replace(b, inner=replace(b.inner, clearance=c)) for b in bs]
    for i, key in enumerate(("viscosity_turbine", "viscosity_compressor")):
        if key in p:
            mu = p.pop(key)
            bs[i] = replace(bs[i], inner=replace(bs[i].inner, viscosity=mu), outer=replace(bs[i].outer, viscosity=mu))
    if "viscosity_scale" in p:
        s = p.pop("viscosity_scale")
        bs = [replace(b, inner=replace(b.inner, viscosity=b.inner.viscosity * s),
                      outer=replace(b.outer, viscosity=b.outer.viscosity * s)) for b in bs]
    if "ring_mass" in p:
        m = p.pop("ring_mass")
        bs = [replace(b, ring_mass=m) for b in bs]
    unb = []
    for wheel, key in (("turbine_wheel", "unbalance_turbine"), ("compressor_wheel", "unbalance_compressor")):
        if key in p:
            amount = p.pop(key)
            if amount > 0:
                unb.append(Unbalance(wheel, amount, 0.0))
    if p:
        raise ParameterError(f"study parameters {sorted(p)} are unknown; valid: {', '.join(PARAMETERS)}")
    return tc.with_(bearings=tuple(bs)), unb


# --------------------------------------------------------------------------------------------------
# one case (runs on a worker)
# --------------------------------------------------------------------------------------------------
def _onset_rows_campbell(cd):
    """Onset rows of a Campbell result; modes are named by precession and shape, numbered by frequency among
    modes of the same name (mode track indices are not comparable between cases)."""
    rows = []
    ur = cd.unstable_ranges()
    ur = ur.assign(name=ur["precession"] + " " + ur["kind"]).sort_values("f at start [Hz]")
    ur["rank"] = ur.groupby("name").cumcount() + 1
    for _, r in ur.iterrows():
        rows.append({"kind": "linear", "method": cd.method, "item": f"{r['name']} #{r['rank']}",
                     "onset [rpm]": float(r["from [rpm]"]), "end [rpm]": float(r["to [rpm]"]),
                     "f at onset [Hz]": float(r["f at start [Hz]"]),
                     "onset at sweep start": bool(r["from [rpm]"] <= cd.speeds_rpm[0])})
    return rows


def _onset_rows_run(run, label, node="turbine_wheel"):
    from .spectral import spectrogram

    seg = min(0.1, max(0.01, (run.time[-1] - run.time[0]) / 40))
    rows = []
    for c in spectrogram(run, node, segment_s=seg).components():
        if c.label.startswith("sub"):
            rows.append({"kind": "nonlinear", "method": label, "item": f"{c.label} ({c.direction})",
                         "onset [rpm]": c.onset_rpm, "end [rpm]": c.end_rpm, "f at onset [Hz]": c.onset_hz,
                         "first detection [rpm]": c.onset_threshold_rpm,
                         "onset at sweep start": bool(c.onset_rpm <= run.speed_rpm[0] * 1.001)})
    return rows


def run_case(case: Case, out_dir) -> dict:
    """Run one case and write ``<out>/cases/<id>.json`` (status, parameters, onset rows, timing; or the error)."""
    out = Path(out_dir)
    (out / "cases").mkdir(parents=True, exist_ok=True)
    rec = {"case_id": case.case_id, "params": case.params, "analysis": case.analysis, "options": case.options,
           "host": os.uname().nodename, "pid": os.getpid(), "started": time.time()}
    try:
        tc, unb = build_case_system(case.params)
        o = dict(case.options)
        rows = []
        if case.analysis == "campbell":
            from .campbell import campbell

            speeds = np.linspace(*o.get("speeds_rpm", (10e3, 250e3, 100)))
            for m in o.get("methods", ["J"]):
                rows += _onset_rows_campbell(campbell(tc, m, speeds))
        elif case.analysis == "runup":
            from .runup import SpeedProfile, runup

            lo, hi = o.get("speed_rpm", (1e3, 250e3))
            dur = float(o.get("duration", 2.0))
            prof = SpeedProfile.exponential(lo, hi, dur) if o.get("profile", "exponential") == "exponential" \
                else SpeedProfile.ramp(lo, hi, dur)
            run = runup(tc, profile=prof, duration=dur, unbalance=unb, progress=False,
                        output_rate_hz=float(o.get("output_rate_hz", 10e3)))
            rows += _onset_rows_run(run, "run-up")
        elif case.analysis == "cosim":
            from .cosim.master import cosimulate, operating_point_overrides

            lo, hi = o.get("speed_rpm", (20e3, 250e3))
            dur = float(o.get("duration", 1.0))
            ov = operating_point_overrides(tc, lo, end_rpm=hi, ramp_time=dur, perturbation=0.05)
            for name, b in zip(("turbine", "compressor"), tc.bearings):
                for fname, film in (("inner", b.inner), ("outer", b.outer)):
                    ov[name][f"{fname}.clearance"] = ("Real", film.clearance)
                    ov[name][f"{fname}.viscosity"] = ("Real", film.viscosity)
                ov[name]["ring.mass"] = ("Real", b.ring_mass)
            for u in unb:
                ov["rotor"][f"{u.disc}.unbalance"] = ("Real", u.amount)
            run = cosimulate(o["ssp"], o.get("parameter_set", "co36"), stop_time=dur, overrides=ov, progress=False)
            rows += _onset_rows_run(run, "co-sim")
        else:
            raise ParameterError(f"analysis = {case.analysis!r} is unknown")
        rec.update({"status": "finished", "rows": rows})
    except Exception as exc:  # noqa: BLE001  (a failing case is recorded, the study goes on)
        rec.update({"status": "failed", "error": f"{type(exc).__name__}: {exc}",
                    "traceback": traceback.format_exc(limit=5)})
    rec["wall_time_s"] = time.time() - rec["started"]
    tmp = out / "cases" / f".{case.case_id}.json.tmp{os.getpid()}"
    tmp.write_text(json.dumps(rec, indent=1, default=float))
    os.replace(tmp, out / "cases" / f"{case.case_id}.json")  # atomic: a case file is complete or absent
    return {"case_id": case.case_id, "status": rec["status"], "error": rec.get("error", ""),
            "wall_time_s": rec["wall_time_s"]}


# --------------------------------------------------------------------------------------------------
# study
# --------------------------------------------------------------------------------------------------
def _load(out):
    recs = {}
    for f in sorted((Path(out) / "cases").glob("*.json")):
        try:
            recs[f.stem] = json.loads(f.read_text())
        except (OSError, json.JSONDecodeError):
            continue  # a damaged file counts as not finished
    return recs


def write_index(cases, out):
    import pandas as pd

    recs = _load(out)
    rows = []
    for c in cases:
        r = recs.get(c.case_id, {})
        rows.append({"case_id": c.case_id, "analysis": c.analysis, **{f"{k} [{PARAMETERS[k][0]}]": v
                                                                       for k, v in c.params.items()},
                     "status": r.get("status", "pending"), "error": r.get("error", ""),
                     "wall time [s]": r.get("wall_time_s", float("nan")), "file": f"cases/{c.case_id}.json"})
    df = pd.DataFrame(rows)
    tmp = Path(out) / ".index.csv.tmp"
    df.to_csv(tmp, index=False)
    os.replace(tmp, Path(out) / "index.csv")
    (Path(out) / "study.json").write_text(json.dumps([asdict(c) | {"case_id": c.case_id} for c in cases], indent=1))
    return df


def run_study(cases, out_dir, scheduler=None, n_workers=None, progress=print, retry_failed=False):
    """Run all unfinished cases of a study; returns the index DataFrame.

    Parameters
    ----------
    cases : list of Case
    out_dir : path
    scheduler : None | "serial" | str
        None: a new dask.distributed LocalCluster with ``n_workers`` processes (default: one per core);
        "serial": in this process, no Dask; otherwise the address of an existing Dask scheduler.
    retry_failed : bool
        Also rerun cases that failed before.
    """
    out = Path(out_dir)
    (out / "cases").mkdir(parents=True, exist_ok=True)
    ids = [c.case_id for c in cases]
    if len(set(ids)) != len(ids):
        raise ParameterError("the study has duplicate cases")
    done = _load(out)
    todo = [c for c in cases if c.case_id not in done or (retry_failed and done[c.case_id].get("status") == "failed")]
    write_index(cases, out)
    n_total, n_skip = len(cases), len(cases) - len(todo)
    progress(f"study: {n_total} cases, {n_skip} already finished, {len(todo)} to run -> {out.resolve()}")
    t0 = time.time()
    n_done = 0

    def report(res):
        nonlocal n_done
        n_done += 1
        el = time.time() - t0
        eta = el / n_done * (len(todo) - n_done)
        msg = f"  [{n_skip + n_done}/{n_total}] {res['case_id']}: {res['status']} ({res['wall_time_s']:.1f} s)"
        if res["status"] == "failed":
            msg += f" - {res['error'][:200]}"
        progress(msg + f"  elapsed {el:.0f} s, ETA {eta:.0f} s")
        write_index(cases, out)

    if not todo:
        return write_index(cases, out)
    if scheduler == "serial":
        for c in todo:
            report(run_case(c, out))
        return write_index(cases, out)
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        n = n_workers or os.cpu_count() or 1
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        progress(f"dask: {len(client.scheduler_info().get('workers', {}))} workers, dashboard "
                 f"{client.dashboard_link}")
        futures = [client.submit(run_case, c, str(out), key=f"frb-{c.case_id}", pure=False) for c in todo]
        for fut in as_completed(futures):
            try:
                report(fut.result())
            except Exception as exc:  # noqa: BLE001  (a lost worker: the case stays pending, rerun picks it up)
                progress(f"  a task failed outside the case handler: {exc}")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return write_index(cases, out)


def stability_map(out_dir):
    """Long table of onsets per finished case: swept parameters, linear (method-mode) and nonlinear
    (sub-synchronous component) onsets [rpm] and frequencies [Hz]."""
    import pandas as pd

    rows = []
    for cid, rec in _load(out_dir).items():
        if rec.get("status") != "finished":
            continue
        for r in rec.get("rows", []):
            rows.append({"case_id": cid, "analysis": rec["analysis"],
                         **{f"{k} [{PARAMETERS[k][0]}]": v for k, v in rec["params"].items()}, **r})
    return pd.DataFrame(rows)


def plot_stability_map(out_dir, parameter=None):
    """Onset speed vs the (first) swept parameter, one line per linear mode / nonlinear component; writes
    ``stability_map.png`` / ``.html`` / ``.csv`` into ``out_dir``.

    Parameters
    ----------
    out_dir : path
        Folder of a study (:func:`run_study`).
    parameter : str, optional
        Swept parameter on the x axis (default: the first).

    Returns
    -------
    list of Path
        The CSV and, if there are onsets, the PNG and HTML figures.
    """
    import matplotlib.pyplot as plt
    import plotly.graph_objects as go

    out = Path(out_dir)
    df = stability_map(out)
    paths = [out / "stability_map.csv"]
    df.to_csv(paths[0], index=False)
    if df.empty:
        return paths
    pcols = [c for c in df.columns if c.split(" [")[0] in PARAMETERS]
    pcol = next((c for c in pcols if parameter and c.startswith(parameter)), pcols[0] if pcols else None)
    scale, xlabel = (1e6, pcol.replace("[m]", "[um]")) if pcol and pcol.endswith("[m]") else (1.0, pcol)
    fig, ax = plt.subplots(figsize=(9, 5.5))
    pfig = go.Figure()
    for (kind, method, item), g in df.groupby(["kind", "method", "item"]):
        g = g.sort_values(pcol)
        x = g[pcol].to_numpy() * scale
        y = g["onset [rpm]"].to_numpy() / 1e3
        lab = f"{method}: {item}"
        ls = "-" if kind == "linear" else "--"
        mk = "o" if kind == "linear" else "s"
        ax.plot(x, y, ls, marker=mk, label=lab)
        pfig.add_trace(go.Scatter(x=x, y=y, mode="lines+markers", name=lab,
                                  line=dict(dash="solid" if kind == "linear" else "dash"),
                                  customdata=g["f at onset [Hz]"].to_numpy(),
                                  hovertemplate=f"{xlabel} %{{x:.4g}}<br>onset %{{y:.1f}} krpm<br>"
                                                f"f %{{customdata:.1f}} Hz<extra>{lab}</extra>"))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("onset speed [krpm]")
    ax.set_title("Stability map: linear (solid) and nonlinear (dashed) onsets", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    p = out / "stability_map.png"
    fig.savefig(p, dpi=110, bbox_inches="tight")
    plt.close(fig)
    paths.append(p)
    pfig.update_layout(xaxis_title=xlabel, yaxis_title="onset speed [krpm]", title="Stability map")
    p = out / "stability_map.html"
    pfig.write_html(str(p))
    paths.append(p)
    return paths


EXAMPLES = {
    "outer-clearance": dict(params={"outer_clearance": [36e-6, 38e-6, 40e-6, 42e-6, 44e-6, 46e-6]},
                            analyses=[("campbell", {"methods": ["J"], "speeds_rpm": (1e3, 250e3, 250)}),
                                      ("runup", {"speed_rpm": (1e3, 250e3), "duration": 2.0})]),
}


def example_cases(name):
    if name not in EXAMPLES:
        raise ParameterError(f"example = {name!r} is unknown; valid: {', '.join(EXAMPLES)}")
    ex = EXAMPLES[name]
    return [c for a, o in ex["analyses"] for c in grid(ex["params"], a, **o)]


__all__ = ["Case", "grid", "run_case", "run_study", "stability_map", "plot_stability_map", "example_cases",
           "PARAMETERS", "ANALYSES", "build_case_system"]
