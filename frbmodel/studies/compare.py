"""Linear vs nonlinear: run-ups (or run-downs), their sub-synchronous components and the method-J stability
predictions.

For each outer clearance the run's sub-synchronous components are paired with the method-J mode that is
closest in frequency at the component's onset among the modes that lose stability somewhere in the speed
range; the linear prediction of the onset is the speed where the run enters that mode's unstable range (its
lower end in a run-up, its upper end in a run-down) nearest to the nonlinear onset. A component that is there
from the start of the run has no onset; it is paired with a mode that is unstable where it was first detected.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, check_distinct, check_system
from ..core.progress import counter_bar, note
from ..linear.campbell import campbell
from ..nonlinear.runup import DEFAULT_ATOL_M, DEFAULT_RTOL, RunupStopped, SpeedProfile, check_output_rate, runup
from ..plots.style import readable
from ..signals.convergence import convergence_table
from ..signals.spectral import spectrogram
from ..system.oil import check_no_oil
from ..system.presets import PAPER_OUTER_CLEARANCES


def _unstable_ranges_sorted(cd):
    """Unstable ranges of ``cd`` with ``lo``/``hi`` [rpm] and the frequencies there [Hz], whatever the order of
    its speed grid."""
    ur = cd.unstable_ranges()
    swap = (ur["from [rpm]"] > ur["to [rpm]"]).to_numpy()
    a, b = ur["from [rpm]"].to_numpy(), ur["to [rpm]"].to_numpy()
    fa, fb = ur["f at start [Hz]"].to_numpy(), ur["f at end [Hz]"].to_numpy()
    return ur.assign(lo=np.where(swap, b, a), hi=np.where(swap, a, b), f_lo=np.where(swap, fb, fa),
                     f_hi=np.where(swap, fa, fb))


def associate(component, cd, window=1.5, descending=False):
    """Pair a run component with a Campbell mode: among the modes with an unstable range that the run enters
    within a factor ``window`` of the component's onset speed (or that contains it), the one closest in frequency
    there. A component without an onset (there from the start of the run) is paired only with a mode that is
    unstable at its first detection.

    Parameters
    ----------
    component : Component
        A sub-synchronous component of the run (:meth:`SpectrogramResult.components`).
    cd : CampbellResult
        Its speed grid may be in any order.
    window : float
        Speed factor [-] around the component's onset in which an unstable range may start.
    descending : bool
        The run is a run-down: it enters an unstable range at its upper end.

    Returns
    -------
    dict or None
        Keys "cost" (relative frequency mismatch [-]), "mode", "kind", "precession", "linear onset [rpm]" (where
        the run enters the unstable range), "linear f at onset [Hz]", "starts at sweep begin" (that speed is the
        end of the Campbell grid the run starts from, so the true linear onset may lie outside the grid); None if
        no mode qualifies.
    """
    has_onset = math.isfinite(component.onset_rpm)
    s_ref = component.onset_rpm if has_onset else component.detected_from_rpm
    f_ref = component.onset_hz if has_onset else component.first_detection_hz
    order = np.argsort(cd.speeds_rpm)  # np.interp needs increasing abscissae
    speeds = cd.speeds_rpm[order]
    ur = _unstable_ranges_sorted(cd)
    best = None
    for j in sorted(set(ur["mode"])):
        f_mode = np.interp(s_ref, speeds, cd.frequencies_hz[order, j], left=np.nan, right=np.nan)
        if not np.isfinite(f_mode):
            continue
        rows = ur[ur["mode"] == j]
        lo, hi = rows["lo"].to_numpy(), rows["hi"].to_numpy()
        entry = hi if descending else lo
        near = (lo <= s_ref) & (hi >= s_ref)
        if has_onset:
            near |= (entry >= s_ref / window) & (entry <= s_ref * window)
        if not near.any():
            continue
        cand = np.flatnonzero(near)
        k = int(cand[np.argmin(np.abs(entry[cand] - s_ref))])
        cost = abs(f_mode - f_ref) / f_ref
        if best is None or cost < best["cost"]:
            r = rows.iloc[k]
            edge = speeds[-1] if descending else speeds[0]
            best = {"cost": cost, "mode": int(j), "kind": r["kind"], "precession": r["precession"],
                    "linear onset [rpm]": float(entry[k]),
                    "linear f at onset [Hz]": float(r["f_hi"] if descending else r["f_lo"]),
                    "starts at sweep begin": bool(entry[k] == edge)}
    return best


def write_spectrogram(sp, cd, folder, title, xscale="linear", fmax_hz=None):
    """Write the composite figure (PNG + HTML) and the components table of a spectrogram into ``folder``.

    Parameters
    ----------
    sp : SpectrogramResult
    cd : CampbellResult
        Method-J Campbell diagram for the overlay.
    folder : Path
    title : str
    xscale : {"linear", "log"}
    fmax_hz : float, optional
        Upper frequency limit [Hz].

    Returns
    -------
    list of Path
        ``composite.png``, ``composite.html``, ``components.csv``.
    """
    import matplotlib.pyplot as plt

    fig = sp.plot(campbell=cd, title=title, xscale=xscale, fmax_hz=fmax_hz)
    paths = [folder / "composite.png", folder / "composite.html", folder / "components.csv"]
    fig.savefig(paths[0], dpi=110, bbox_inches="tight")
    plt.close(fig)
    sp.plot_html(paths[1], campbell=cd, fmax_hz=fmax_hz)
    sp.components_table().to_csv(paths[2], index=False)
    return paths


def comparison_rows(clearance, sp, comps, cd, status):
    """Rows of the linear-vs-nonlinear table for one outer clearance: one per sub-synchronous component (with its
    associated method-J mode, :func:`associate`) and one per internal resonance.

    Parameters
    ----------
    clearance : float
        Outer clearance [m].
    sp : SpectrogramResult
    comps : list of Component
        ``sp.components()``.
    cd : CampbellResult
    status : str
        "finished", "stopped" or "interrupted" (the run's).

    Returns
    -------
    list of dict
        Per component: "nonlinear onset [rpm]" (empty if the component is there from the start; "onset estimate"
        says which), "first detection [rpm]", "vanishes at [rpm]" (empty if it lasts to the end), the paired mode
        and "rel. difference [-]" of the onsets; per internal resonance: "resonance from [rpm]" / "to [rpm]".
    """
    rows = []
    down = sp.direction == "down"
    kind = "run-down" if down else "run-up"
    for comp in comps:
        if not comp.label.startswith("sub"):
            continue
        a = associate(comp, cd, descending=down)
        row = {"c_o [um]": clearance * 1e6, "component": comp.label, "direction": comp.direction,
               "nonlinear onset [rpm]": comp.onset_rpm, "onset estimate": comp.onset_estimate,
               "first detection [rpm]": comp.onset_threshold_rpm, "f at onset [Hz]": comp.onset_hz,
               "f at first detection [Hz]": comp.first_detection_hz, "vanishes at [rpm]": comp.end_rpm,
               "max amplitude [um]": float(comp.amplitude_m.max() * 1e6), kind: status}
        if a:
            row.update({"J mode": f"{a['precession']} {a['kind']}", "linear onset [rpm]": a["linear onset [rpm]"],
                        "linear f [Hz]": a["linear f at onset [Hz]"],
                        "rel. difference [-]": comp.onset_rpm / a["linear onset [rpm]"] - 1.0,
                        "frequency mismatch [-]": a["cost"]})
        rows.append(row)
    for res in sp.internal_resonances(comps):
        rows.append({"c_o [um]": clearance * 1e6, "component": "total instability?",
                     "direction": f"{res['components'][0]} & {res['components'][1]}: {res['condition']}",
                     "resonance from [rpm]": res["from [rpm]"], "resonance to [rpm]": res["to [rpm]"], kind: status})
    return rows


def compare(system, clearances=PAPER_OUTER_CLEARANCES, speed_rpm=(1e3, 250e3), duration=4.0,
            profile="exponential", node=None, out_dir="results/compare", n_speeds=300, progress=False,
            runup_kw=None, segment_s=0.1, fmax_hz=1000.0, check_convergence=False):
    """Run the run-up (or run-down) and the method-J Campbell diagram per outer clearance; write per clearance the
    run data, the composite figure (PNG + HTML) and the components; return and write the comparison table.

    Parameters
    ----------
    system : Turbocharger
    clearances : sequence of float
        Outer film clearances [m].
    speed_rpm : (float, float)
        Start and end speed [rpm] of the runs (a run-down if end < start); the Campbell sweeps cover the same
        range in increasing order.
    duration : float
        Run duration [s].
    profile : {"exponential", "ramp"}
        Speed profile of the runs (and spacing of the Campbell speeds).
    node : str, optional
        Disc whose orbit is analysed (default: the system's first disc).
    out_dir : path
    n_speeds : int
        Speeds of the Campbell sweeps.
    progress : bool
        Show a progress bar over the clearances and the run's own bar, with one line per step
        (:mod:`frbmodel.core.progress`; default off, on in the CLI).
    runup_kw : dict, optional
        Further arguments of :func:`frbmodel.nonlinear.runup` (its ``progress`` defaults to ``progress``).
    segment_s : float
        Spectrogram segment length [s] (at most duration / 8).
    fmax_hz : float
        Upper frequency limit of the figures [Hz].
    check_convergence : bool
        Rerun each case with rtol and atol tightened tenfold and label every component's onset as converged or
        seeded by round-off (columns "converged", "note").

    Returns
    -------
    table : pandas.DataFrame
        :func:`comparison_rows` of all clearances (also written as ``linear_vs_nonlinear.csv`` / ``.md``).
    paths : list of Path
        Files written.
    """
    import pandas as pd


    check_no_oil(check_system(system), "frb compare (frbmodel.studies.compare)")
    if len(speed_rpm) != 2 or speed_rpm[0] == speed_rpm[1]:  # (4 run-ups, then an empty table, exit 0)
        raise ParameterError(f"speed_rpm = {tuple(speed_rpm)!r} is invalid: give (START, END) in rpm, START != END "
                             "(the run-up's range and the Campbell diagram's)")
    if profile not in ("exponential", "ramp"):  # (anything else ran as a ramp)
        raise ParameterError(f"profile = {profile!r} is unknown; valid: exponential, ramp")
    check_output_rate((runup_kw or {}).get("output_rate_hz", 20e3), duration)  # (was refused after a diagram)
    clearances = check_clearances(system, clearances)
    node = node or system.rotor.discs[0].name
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows, paths = [], []
    opts = dict(speed_rpm=speed_rpm, duration=duration, profile=profile, node=node, n_speeds=n_speeds,
                progress=progress, runup_kw=runup_kw, segment_s=segment_s, fmax_hz=fmax_hz,
                check_convergence=check_convergence)
    with counter_bar(len(clearances), "compare", progress, unit="clearance") as bar:
        for c in clearances:
            r, p = _compare_clearance(system, c, out, **opts)
            rows += r
            paths += p
            bar.update(1)
    table = pd.DataFrame(rows)
    p = out / "linear_vs_nonlinear.csv"
    table.to_csv(p, index=False)
    paths.append(p)
    p = out / "linear_vs_nonlinear.md"
    p.write_text(table_markdown(table))
    paths.append(p)
    return table, paths


def clearance_tag(clearance_m):
    """The result folder of an outer clearance [m]: ``co<µm>um``, the µm to 6 significant digits (36e-6: co36um;
    36.5e-6: co36.5um; it was rounded to whole µm, so 36.2e-6 and 36.4e-6 wrote one folder, the second's files over
    the first's)."""
    return f"co{clearance_m * 1e6:g}um"


def check_clearances(system, clearances):
    """The outer clearances [m] of :func:`compare` as floats, each one that ``system``'s films take
    (:meth:`~frbmodel.system.parameters.Turbocharger.with_outer_clearance`) and each with its own result folder
    (:func:`clearance_tag`), or a :class:`ParameterError` — before any diagram (a clearance the films refuse was
    refused after the Campbell diagrams and run-ups of the ones before it, their files left in the folder).

    Examples
    --------
    >>> from frbmodel.system.presets import turbocharger
    >>> try:
    ...     check_clearances(turbocharger(), [36e-6, 36.0000001e-6])
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    clearances = [3.6e-05, 3.60000001e-05]: their result folders ['co36um', 'co36um'] repeats co36um: give distinct ...
    """
    values = [float(system.with_outer_clearance(c).bearings[0].outer.clearance) for c in clearances]
    tags = [clearance_tag(c) for c in values]
    check_distinct(f"clearances = {values!r}: their result folders {tags}", tags)
    return values


def _compare_clearance(system, c, out, speed_rpm, duration, profile, node, n_speeds, progress, runup_kw, segment_s,
                       fmax_hz, check_convergence):
    """One clearance of :func:`compare`: Campbell diagram, run, spectrogram, figures; (table rows, paths)."""

    start, end = speed_rpm
    lo, hi = sorted((start, end))
    kind = "run-down" if end < start else "run-up"
    tag = clearance_tag(c)
    tc = system.with_outer_clearance(c)
    note(f"[{tag}] method-J Campbell diagram", progress)
    cd = campbell(tc, "J", np.geomspace(lo, hi, n_speeds) if profile == "exponential" else
                  np.linspace(lo, hi, n_speeds))
    paths = cd.save(out / tag, stem="campbell_J", png=False, html=False)
    prof = SpeedProfile.exponential(start, end, duration) if profile == "exponential" else \
        SpeedProfile.ramp(start, end, duration)
    note(f"[{tag}] {kind} {prof.description}", progress)
    status = "finished"
    try:
        run = runup(tc, profile=prof, duration=duration, out_dir=out / tag,
                    **{"progress": bool(progress), **(runup_kw or {})})
    except RunupStopped as exc:
        note(f"[{tag}] {kind} stopped: {exc}", progress)
        run, status = exc.result, "stopped"
    paths += [out / tag / "runup.csv", out / tag / "runup.json"]
    sp = spectrogram(run, node, segment_s=min(segment_s, duration / 8))
    title = f"c_o = {c * 1e6:g} µm: {kind} spectrogram ({readable(node)}) vs method J"
    paths += write_spectrogram(sp, cd, out / tag, title, "log" if profile == "exponential" else "linear", fmax_hz)
    rows = comparison_rows(c, sp, sp.components(), cd, status)
    if check_convergence:
        rows = _label_convergence(rows, sp, tc, prof, duration, out / tag / "convergence_check", node,
                                  min(segment_s, duration / 8), runup_kw, progress)
    return rows, paths


def _label_convergence(rows, sp, system, profile, duration, folder, node, segment_s, runup_kw, progress):
    """Rerun with rtol and atol tightened tenfold and add "converged" / "note" to the component rows."""

    kw = {"rtol": DEFAULT_RTOL, "atol": DEFAULT_ATOL_M, **(runup_kw or {})}
    kw.update(rtol=kw["rtol"] / 10, atol=kw["atol"] / 10, progress=bool(progress))
    try:
        tight = runup(system, profile=profile, duration=duration, out_dir=folder, **kw)
    except RunupStopped as exc:
        tight = exc.result
    tab = convergence_table(sp.components(), spectrogram(tight, node, segment_s=segment_s).components())
    labels = tab.set_index("component")[["converged", "note"]].to_dict("index") if len(tab) else {}
    for r in rows:
        r.update(labels.get(r.get("component"), {}))
    return rows


def table_markdown(table) -> str:
    """The main columns of a :func:`compare` table as a Markdown table (speeds with thousands separators,
    relative differences in %; empty cells where a value does not exist, e.g. no onset for a component that is
    there from the start).

    Parameters
    ----------
    table : pandas.DataFrame

    Returns
    -------
    str
    """
    cols = ["c_o [um]", "component", "direction", "nonlinear onset [rpm]", "onset estimate", "first detection [rpm]",
            "vanishes at [rpm]", "f at onset [Hz]", "J mode", "linear onset [rpm]", "linear f [Hz]",
            "rel. difference [-]", "resonance from [rpm]", "resonance to [rpm]", "converged"]
    cols = [c for c in cols if c in table.columns]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]

    def fmt(v, c):
        if isinstance(v, (bool, np.bool_)):
            return "yes" if v else "no: seeded by round-off"
        if isinstance(v, float):
            if math.isnan(v):
                return ""
            if "rel." in c:
                return f"{v:+.1%}"
            if "rpm" in c:
                return f"{v:,.0f}"
            return f"{v:.0f}" if "Hz" in c or "c_o" in c else f"{v:.3g}"
        return str(v)

    for _, r in table.iterrows():
        lines.append("| " + " | ".join(fmt(r.get(c, ""), c) for c in cols) + " |")
    return "\n".join(lines) + "\n"
