"""Pseudo-arclength continuation of whirl limit cycles in rotor speed, with bifurcation detection.

Unknowns X = (u0, τ, p): the scaled start state u0 = z0 / scale of a periodic orbit (:mod:`frbmodel.cycles.limitcycle`),
its period τ = T / T_ref and the rotor speed p = Ω / Ω_ref. Equations: the shooting residual (Φ_T(z0; Ω) − z0) /
scale, the phase condition (the start point on the hyperplane through the previous point normal to the flow there)
and the arclength condition t·(X − X_prev) = Δs along the unit tangent t of the branch. A predictor step along the
tangent is corrected by Newton iterations starting from the Jacobian of the last point (monodromy by forward
differences of the flow, ∂Φ/∂Ω by one more flow; after a failed step, and at a Hopf point, one computed at the
predicted point) and updated by Broyden's formula; the Jacobian and monodromy are then computed at the new point
(its multipliers, the next tangent, the next corrector). The step length adapts to the number of corrector
iterations. Folds (the speed turns: a multiplier through +1), period doublings (a real multiplier through −1) and
Neimark-Sacker points (a complex pair leaving the unit circle: a second whirl frequency, a torus) are detected from
the Floquet multipliers of consecutive points and located by linear interpolation between them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import MAX_SPEED_COUNT, ParameterError, check_distinct, check_positive
from ..core.results import NETCDF_ENGINE, Result, decode_attr, netcdf_attrs, variable
from ..linear.campbell import campbell
from ..linear.thermal import check_oil_supply
from ..linear.whirl import film_names
from ..nonlinear.runup import SpeedProfile, build_problem, check_speed
from ..physics.film import check_model
from ..plots.bifurcation import diagram_figure, diagram_html
from .branch import (
    COLLAPSE,
    FOLD_MIN_REL,
    BranchPoint,
    ContinuationProblem,
    HopfPoint,
    check_segments,
    check_speed_range,
    equilibrium_jacobian,
    follow_branch,
    hopf_branch,
    hopf_guess,
    hopf_points,
    shoot_segments,
    start_tangent,
    trivial_error,
)
from .flow import MULTIPLIER_TOL, SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS
from .limitcycle import LimitCycle, limit_cycle


def _nontrivial(p):
    """Multipliers of a branch point without the trivial one (the one closest to 1)."""
    return np.delete(p.multipliers, int(np.argmin(np.abs(p.multipliers - 1.0))))


def _outside(p):
    """Non-trivial multipliers of a branch point outside the unit circle (by more than their accuracy)."""

    mu = _nontrivial(p)
    return mu[np.abs(mu) > 1.0 + MULTIPLIER_TOL]


def _classify(a, b):
    """Bifurcations between consecutive branch points a, b: [(type, fraction along a -> b)]. The number of
    multipliers outside the unit circle changes; the crossing one (outside on the unstable side, closest to the
    circle) decides the type by its angle: ~0 fold, ~π period doubling, otherwise Neimark-Sacker (a complex pair
    counts twice). Located where its modulus, interpolated (or extrapolated by up to one interval: the count uses
    :data:`frbmodel.cycles.flow.MULTIPLIER_TOL`) linearly, is 1."""
    out_a, out_b = _outside(a), _outside(b)
    if out_a.size == out_b.size:
        return []
    side = out_b if out_b.size > out_a.size else out_a
    mu = side[np.argmin(np.abs(side))]
    angle = abs(float(np.angle(mu)))
    kind = "fold" if angle < 0.05 else "period doubling" if angle > math.pi - 0.05 else "Neimark-Sacker"
    other = b if side is out_a else a
    mo = _nontrivial(other)
    rest = mo[np.argsort(np.abs(mo - mu))][:1]
    r_in = float(np.abs(rest[0])) if rest.size else 1.0
    r_out = float(abs(mu))
    frac = (1.0 - r_in) / (r_out - r_in) if r_out != r_in else 0.5
    # detected beyond MULTIPLIER_TOL, located where the modulus is 1: possibly up to one interval before (after)
    frac = float(np.clip(frac if side is out_b else 1.0 - frac, -1.0, 2.0))
    return [(kind, frac)]


@dataclass
class BifurcationDiagram(Result):
    """Branches of limit cycles vs rotor speed and their bifurcation points (:func:`continuation`).

    Attributes
    ----------
    points : list of BranchPoint
        The computed orbits, in branch order (arclength).
    bifurcations : list of dict
        Each: ``speed_rpm``, ``type`` (Hopf, fold, period doubling, Neimark-Sacker), ``criticality`` (of a Hopf
        point: super- or subcritical), ``frequency_hz``, ``turbine_radius_um``, ``mode`` (the Campbell mode of the
        branch's Hopf point), ``film`` (Hopf: the film moving most in the eigenvector; others: the film with the
        largest eccentricity ratio, :func:`hopf_record`), ``between`` (indices of the two points it lies between).
    meta : dict
        System, film model, tolerances, steps taken.
    """

    NC_GLOB = "branch.nc"  # (Result.load of a folder)
    points: list
    bifurcations: list
    meta: dict = field(default_factory=dict)

    def to_dataframe(self):
        """The branch points as a table (units in the column names). ``trivial multiplier error`` is the distance from
        1 of the multiplier closest to it (1 exactly on a periodic orbit): the accuracy of the multipliers there."""
        import pandas as pd

        rows = [{"speed [rpm]": p.speed_rpm, "frequency [Hz]": 1 / p.period, "period [s]": p.period,
                 "turbine wheel orbit radius [um]": p.turbine_radius_m * 1e6, "stable": p.stable,
                 "max |multiplier| (nontrivial) [-]": float(np.max(np.abs(np.delete(
                     p.multipliers, int(np.argmin(np.abs(p.multipliers - 1.0))))))),
                 "trivial multiplier error [-]": trivial_error(p.multipliers),
                 **{f"max eps {k} [-]": v for k, v in zip(("turbine inner", "turbine outer", "compressor inner",
                                                          "compressor outer"), p.max_eps)}} for p in self.points]
        return pd.DataFrame(rows)

    def bifurcation_table(self):
        """The bifurcation points as a table."""
        import pandas as pd

        return pd.DataFrame([{k: v for k, v in b.items() if k != "between"} for b in self.bifurcations],
                            columns=["speed_rpm", "type", "criticality", "frequency_hz", "turbine_radius_um", "mode",
                                     "film"])

    def to_xarray(self):
        """Branch points as an :class:`xarray.Dataset` along ``point`` (units in the attributes)."""
        import xarray as xr


        df = self.to_dataframe()
        ds = xr.Dataset({
            "speed": variable(("point",), df["speed [rpm]"].values, "rpm", "rotor speed"),
            "frequency": variable(("point",), df["frequency [Hz]"].values, "Hz", "orbit frequency 1/T"),
            "turbine_radius": variable(("point",), df["turbine wheel orbit radius [um]"].values * 1e-6, "m",
                                       "turbine wheel orbit radius"),
            "stable": variable(("point",), df["stable"].values.astype(int), "-", "1: stable orbit"),
            "max_eps": variable(("point", "film"), np.array([p.max_eps for p in self.points]), "-",
                                "largest eccentricity ratio over one period"),
            "multiplier_real": variable(("point", "multiplier"), np.array([p.multipliers.real for p in self.points]),
                                        "-", "Floquet multipliers, real part (largest modulus first)"),
            "multiplier_imag": variable(("point", "multiplier"), np.array([p.multipliers.imag for p in self.points]),
                                        "-", "Floquet multipliers, imaginary part"),
        })
        ds.attrs.update(netcdf_attrs({"bifurcations": self.bifurcations, **self.meta}))
        return ds

    @classmethod
    def from_xarray(cls, ds):
        """The diagram from a dataset of :meth:`to_xarray` (e.g. ``branch.nc`` of :meth:`save`; :meth:`load` reads
        it, or the folder holding it).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        BifurcationDiagram
        """

        mult = ds["multiplier_real"].values + 1j * ds["multiplier_imag"].values
        pts = [BranchPoint(float(s), 1.0 / float(f), m, bool(st), float(r), e) for s, f, m, st, r, e in
               zip(ds["speed"].values, ds["frequency"].values, mult, ds["stable"].values,
                   ds["turbine_radius"].values, ds["max_eps"].values)]
        meta = {k: decode_attr(v) for k, v in ds.attrs.items()}
        return cls(pts, meta.pop("bifurcations", []), meta)

    def save(self, out_dir, envelopes=(), spectrogram=None, campbell=None):
        """Write ``branch.csv``, ``bifurcations.csv``, ``branch.nc`` and the figures ``bifurcation.png`` and
        ``bifurcation.html`` (with the run envelopes, spectrogram and Campbell lines of :meth:`plot`) into
        ``out_dir``; returns the paths."""
        from pathlib import Path

        import matplotlib.pyplot as plt


        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "branch.csv", out / "bifurcations.csv", out / "branch.nc", out / "bifurcation.png",
                 out / "bifurcation.html"]
        self.to_dataframe().to_csv(paths[0], index=False)
        self.bifurcation_table().to_csv(paths[1], index=False)
        self.to_xarray().to_netcdf(paths[2], engine=NETCDF_ENGINE)
        fig = self.plot(envelopes=envelopes, spectrogram=spectrogram, campbell=campbell)
        fig.savefig(paths[3], dpi=130)
        plt.close(fig)
        self.plot_html(paths[4], envelopes=envelopes, campbell=campbell)
        return paths

    def plot(self, title=None, envelopes=(), spectrogram=None, campbell=None):
        """Bifurcation diagram (matplotlib): turbine-wheel orbit radius [µm] and orbit frequency [Hz] vs speed;
        stable solid, unstable dashed, bifurcation points marked; behind them run envelopes (label, speeds [rpm],
        radius [µm]), a run's spectrogram and a Campbell diagram's unstable modes and film whirl lines
        (:func:`frbmodel.plots.bifurcation.diagram_figure`)."""

        return diagram_figure(self, title, envelopes, spectrogram, campbell)

    def plot_html(self, path=None, title=None, envelopes=(), campbell=None, include_plotlyjs=None):
        """The diagram as an interactive figure, written to ``path`` (HTML) if given
        (:func:`frbmodel.plots.bifurcation.diagram_html`); returns the plotly figure."""

        return diagram_html(self, path, title, envelopes, campbell, include_plotlyjs)


def continuation(system, speeds_rpm, start="hopf", film_model=None, ds=1.0, ds_max=8.0, max_points=100,
                 progress=False, on_point=None, segments=1, oil_supply=None):
    """Branches of limit cycles in rotor speed (pseudo-arclength), from the Hopf points or from a given orbit.

    Parameters
    ----------
    system : Turbocharger
        The system.
    speeds_rpm : (float, float)
        Speed range [rpm]; a branch is followed until it leaves it (or ``max_points`` are computed).
    start : "hopf", LimitCycle or float, or a list of them
        ``"hopf"``: one branch from each Hopf point of the full model in the range (:func:`hopf_points`), started
        along the Hopf eigenvector; a limit cycle or a speed [rpm] to compute one at: the branch through it, both
        directions; a list: each of them in turn (e.g. ``[25e3, 60e3]``: the branches of the whirls settled on at
        25 and 60 krpm).
    film_model : str, optional
        Default: the system's.
    ds, ds_max : float
        Initial and largest arclength step (scaled units: 1 ~ 1 % of the start speed or 1 µm of orbit).
    max_points : int
        Points per branch and direction at most.
    progress : bool
        Print a line per point on stderr.
    on_point : callable, optional
        Called with each new :class:`BranchPoint` as soon as it is computed (e.g. to stream it to a file).
    segments : int
        Shooting segments per orbit: 1 single shooting; m > 1 multiple shooting (m flows of T/m, the defects between
        them as equations; same cost per Newton step), for strongly unstable orbits: a flow over the whole period
        amplifies errors by the largest multiplier |mu|, a segment by about |mu|^(1/m).
    oil_supply : OilSupply, optional
        Film viscosities from the oil's temperatures (:class:`~frbmodel.linear.thermal.OilSupply`, method J's
        thermal operating point at each speed of the branch: quasi-static temperatures, as in a slow run-up); the
        Hopf points are those of :func:`hopf_points` with the same supply. Default: the films' constant viscosities.
        A LimitCycle start must have been computed with the same supply.

    Returns
    -------
    BifurcationDiagram
    """
    supply = check_oil_supply(oil_supply, bearings=system.bearings)
    lo, hi = _check_steps(speeds_rpm, ds, ds_max, max_points)
    model = check_model(film_model or system.film_model)
    segments = check_segments("segments", segments)
    starts = check_starts(start, (lo, hi))
    _check_start_supply(starts, supply)
    branches, origins = [], []  # origins: the Hopf point a branch starts at, None for a branch through an orbit
    for s0 in starts:
        if isinstance(s0, str):
            for hp in hopf_points(system, (lo, hi), model, restabilizing=True, oil_supply=supply):
                branches.append(hopf_branch(system, model, hp, lo, hi, ds_max, max_points, progress, on_point,
                                             segments, supply))
                origins.append(hp)
        else:
            lc = s0 if isinstance(s0, LimitCycle) else limit_cycle(system, float(s0), film_model=model,
                                                                   oil_supply=supply)
            branches.append(_branch_through(system, model, lc, lo, hi, ds, ds_max, max_points, progress, on_point,
                                            segments, supply))
            origins.append(None)
    return _diagram(system, model, branches, origins, lo, hi, supply)


def _check_steps(speeds_rpm, ds, ds_max, max_points):
    """``(lo, hi)`` of a continuation's speed range (two speeds, lo < hi), with its steps checked: 0 < ds <= ds_max
    finite and max_points an integer >= 1 (ds = 0, -1 or nan and a range of one speed were accepted: an empty or a
    one-point diagram)."""
    lo, hi = check_speed_range(speeds_rpm)
    ds, ds_max = check_positive("ds", ds), check_positive("ds_max", ds_max)
    if ds > ds_max:
        raise ParameterError(f"ds = {ds:g} is invalid with ds_max = {ds_max:g}: valid range 0 < ds <= ds_max")
    check_max_points("max_points", max_points)
    return lo, hi


#: most points of a branch (per direction): the speed-grid bound of every command
#: (:data:`frbmodel.core.errors.MAX_SPEED_COUNT`, 25 rpm steps over 250 krpm) — a branch's points are the speeds of
#: its diagram; at 1-5 s a point (measured at 36 um) that is 3-14 h per branch and direction (1e9 was accepted)
MAX_BRANCH_POINTS = MAX_SPEED_COUNT


def check_max_points(name, max_points, lowest=1):
    """``int(max_points)`` if it is a whole number ``lowest`` ... :data:`MAX_BRANCH_POINTS`, else a
    :class:`ParameterError` naming ``name``, the value and the range (the API, bifurcation studies and the CLI).

    Examples
    --------
    >>> try:
    ...     check_max_points("max_points", 10**9)
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    max_points = 1000000000 is invalid: valid range integer 1 ... 10000 (points per branch and direction: ...
    """
    ok = isinstance(max_points, (int, float, np.integer, np.floating)) and not isinstance(max_points, bool)
    if not (ok and int(max_points) == max_points and lowest <= max_points <= MAX_BRANCH_POINTS):
        raise ParameterError(f"{name} = {max_points!r} is invalid: valid range integer {lowest} ... "
                             f"{MAX_BRANCH_POINTS} (points per branch and direction: the speed-grid bound)")
    return int(max_points)


def _check_start_supply(starts, supply):
    """Refuse a LimitCycle start computed with another oil supply than the continuation's (its orbit is not on the
    branch: the viscosities differ)."""
    want = None if supply is None else supply.to_dict()
    for s0 in starts:
        if isinstance(s0, LimitCycle) and s0.meta.get("oil_supply") != want:
            raise ParameterError(f"start = the limit cycle at {s0.speed_rpm:.0f} rpm was computed with oil_supply = "
                                 f"{s0.meta.get('oil_supply')!r:.80}, the continuation has {want!r:.80}: compute it "
                                 "with the same oil_supply (limit_cycle(oil_supply=...))")


def check_starts(start, speeds_rpm, name="start", range_name="the speed range"):
    """The branch starts of :func:`continuation` as a list (``start``: "hopf", a LimitCycle, a speed [rpm] or a list
    of them, each speed and "hopf" once), or a ParameterError naming the bad one and the valid values (used by the
    API, ``frb bifurcation`` and the ``bifurcation`` study before any computation).

    Examples
    --------
    >>> check_starts([25e3, "hopf"], (1e3, 40e3))
    [25000.0, 'hopf']
    >>> try:
    ...     check_starts(60e3, (1e3, 40e3))
    ... except ParameterError as exc:
    ...     print(exc)
    start = 60000 rpm is outside the speed range 1000:40000 rpm
    """

    lo, hi = sorted(float(s) for s in speeds_rpm)
    starts = [start] if isinstance(start, (str, LimitCycle)) or np.ndim(start) == 0 else list(start)
    out = []
    for s0 in starts:
        if isinstance(s0, str):
            if s0 != "hopf":
                raise ParameterError(f"{name} = {s0!r} is invalid: 'hopf', a LimitCycle or a speed [rpm] (or a "
                                     "list of them)")
            out.append(s0)
            continue
        speed = s0.speed_rpm if isinstance(s0, LimitCycle) else check_speed(name, s0)
        if not lo <= speed <= hi:
            raise ParameterError(f"{name} = {speed:.0f} rpm is outside {range_name} {lo:.0f}:{hi:.0f} rpm")
        out.append(s0 if isinstance(s0, LimitCycle) else speed)
    # (the same branch was followed twice: hours; two LimitCycles at one speed may be two coexisting orbits)
    check_distinct(name, [s for s in out if not isinstance(s, LimitCycle)], "rpm")
    return out


def _branch_through(system, model, lc, lo, hi, ds, ds_max, max_points, progress, on_point, segments, supply):
    """The branch through the orbit ``lc``, followed in both directions (lower speeds first in the result)."""

    br = ContinuationProblem(system, model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, lc.speed_rpm, segments,
                             supply)
    n = br.segments * br.n
    t_ref, w_ref = 0.01 * lc.period, 0.01 * lc.speed_rpm
    starts = br.flow(lc.speed_rpm).states(lc.state, lc.period * np.arange(br.segments + 1) / br.segments)
    x0 = np.concatenate([starts[:-1, :-1].ravel() / br.scale(), [lc.period / t_ref, lc.speed_rpm / w_ref]])
    halves = []
    for direction in (+1, -1):
        tangent, first, jac0 = start_tangent(br, x0, n, t_ref, w_ref, direction)
        halves.append([first] + follow_branch(br, x0, n, t_ref, w_ref, tangent, lo, hi, ds, ds_max, max_points,
                                              progress, on_point=on_point, jac0=jac0))
    return halves[1][::-1] + halves[0][1:]


def _event(kind, a, c, frac, between, films=(), mode=""):
    """A bifurcation record between branch points a and c at fraction ``frac`` (linear interpolation); ``film`` is
    the film with the largest eccentricity ratio there (of ``films``, the names), ``mode`` the branch's Hopf mode."""
    eps = a.max_eps + frac * (np.asarray(c.max_eps) - a.max_eps)
    return {"speed_rpm": a.speed_rpm + frac * (c.speed_rpm - a.speed_rpm), "type": kind, "criticality": "",
            "frequency_hz": 1 / a.period + frac * (1 / c.period - 1 / a.period),
            "turbine_radius_um": max(0.0, 1e6 * (a.turbine_radius_m
                                                 + frac * (c.turbine_radius_m - a.turbine_radius_m))),
            "mode": mode, "film": f"{films[int(np.argmax(eps))]} (eps {np.max(eps):.2f})" if len(films) else "",
            "between": between}


def hopf_record(system, hp, branch=(), film_model=None, oil_supply=None):
    """The bifurcation-table record of a Hopf point.

    ``type``: "Hopf", or "Hopf (restabilizing)" where the pair regains stability with rising speed
    (:attr:`HopfPoint.restabilizing`). ``criticality``: "supercritical" if its branch grows towards the side where
    the crossing pair is unstable (higher speeds; lower ones at a restabilizing point), "subcritical" if it grows
    towards the other side — the side of the first branch point more than :data:`FOLD_MIN_REL` from the Hopf speed
    —, "" without a branch or when all its points stay within that of the Hopf speed (a vertical branch).
    ``mode``: precession and kind of the method-J Campbell mode nearest in frequency at that speed (the linear
    onsets agree to 0.03 %). ``film``: the film whose relative motion in the crossing eigenvector, over its
    clearance, is largest (inner: journal minus ring, outer: ring), with that share of the four.

    Parameters
    ----------
    system : Turbocharger
    hp : HopfPoint
    branch : sequence of BranchPoint
        The branch started there (may be empty).
    film_model : str, optional
    oil_supply : OilSupply, optional
        The supply ``hp`` was found with (the Campbell mode is matched at its thermal operating point).

    Returns
    -------
    dict
    """

    cd = campbell(system, "J", [hp.speed_rpm], whirl=False, oil_supply=oil_supply)
    j = int(np.nanargmin(np.abs(cd.frequencies_hz[0] - hp.frequency_hz)))
    p = build_problem(system, SpeedProfile.constant(hp.speed_rpm, 1.0), film_model or system.film_model)
    v, rel = hp.eigenvector, []
    for i, b in enumerate(system.bearings):
        ring = v[p.ring_index(i):p.ring_index(i) + 2]
        rel += [np.linalg.norm(v[4 * b.node:4 * b.node + 2] - ring) / b.inner.clearance,
                np.linalg.norm(ring) / b.outer.clearance]
    rel = np.array(rel) / np.sum(rel)
    k = int(np.argmax(rel))
    # the side of the branch's first speed excursion beyond the jitter of a vertical branch (the first points may
    # all lie within it: small first steps, or a degenerate Hopf point whose branch bends only at finite amplitude)
    ahead = next((d for d in (q.speed_rpm - hp.speed_rpm for q in branch) if abs(d) > FOLD_MIN_REL * hp.speed_rpm),
                 0.0)
    unstable_side = -1.0 if hp.restabilizing else 1.0
    crit = "" if ahead == 0.0 else "supercritical" if ahead * unstable_side > 0 else "subcritical"  # "": vertical
    return {"speed_rpm": hp.speed_rpm, "type": "Hopf (restabilizing)" if hp.restabilizing else "Hopf",
            "criticality": crit, "frequency_hz": hp.frequency_hz,
            "turbine_radius_um": 0.0, "mode": f"{cd.precession[0, j]} {cd.mode_kind[0, j]}",
            "film": f"{film_names(system)[k]} ({100 * rel[k]:.0f} %)", "between": []}


def _end_hopf(system, model, b, at_start, offset, films, supply):
    """The record of the Hopf point at which the branch ``b`` (through a given orbit) collapses onto the equilibrium:
    the full model's Hopf point (either direction of crossing) within :data:`END_HOPF_REL` of the end's speed and
    frequency, recorded as from :func:`hopf_record` with the branch read from that end; without one, the end point
    itself (type "Hopf", no criticality or mode)."""
    end = b[0] if at_start else b[-1]
    s, f = end.speed_rpm, 1.0 / end.period
    near = [hp for hp in hopf_points(system, ((1 - END_HOPF_REL) * s, (1 + END_HOPF_REL) * s), model, n_grid=8,
                                     restabilizing=True, oil_supply=supply)
            if abs(hp.frequency_hz / f - 1) < END_HOPF_REL]
    if not near:
        return _event("Hopf", end, end, 0.0, [offset + b.index(end)], films)
    hp = min(near, key=lambda h: abs(h.speed_rpm - s))
    rec = hopf_record(system, hp, b if at_start else b[::-1], model, supply)
    rec["between"] = [offset + b.index(end)]
    return rec


def _branch_events(b, off, films=(), mode=""):
    """Bifurcations along one branch: folds where the speed turns (the branch point of extreme speed; a multiplier
    passes +1 there, which the multipliers near the turn, with the trivial one beside it, cannot tell reliably), and
    the period doublings and Neimark-Sacker points of :func:`_classify` away from the folds (2 points or more)."""
    s = np.array([p.speed_rpm for p in b])
    turns = [i for i in range(1, len(b) - 1) if (s[i] - s[i - 1]) * (s[i + 1] - s[i]) < 0
             and min(np.max(np.abs(s[max(i - 3, 0):i] - s[i])), np.max(np.abs(s[i + 1:i + 4] - s[i])))
             > FOLD_MIN_REL * s[i]]
    events = [_event("fold", b[i], b[i], 0.0, [off + i], films, mode) for i in turns]
    for i in range(len(b) - 1):
        if any(abs(i - j) <= 2 or abs(i + 1 - j) <= 2 for j in turns):
            continue
        # a real multiplier through +1 without a turn in speed is not generic without a symmetry (none here, with
        # gravity): it is the radial multiplier of a nearly vertical branch drifting about 1 + MULTIPLIER_TOL
        events += [_event(kind, b[i], b[i + 1], frac, [off + i, off + i + 1], films, mode)
                   for kind, frac in _classify(b[i], b[i + 1]) if kind != "fold"]
    return events


#: largest relative distance in speed and frequency between the end of a branch that collapses onto the equilibrium
#: and the Hopf point it is attributed to (the end is one step short of the point: 0.1 % measured at 30.7 krpm)
END_HOPF_REL = 0.03


def _diagram(system, model, branches, origins, lo, hi, supply=None):
    """The BifurcationDiagram of computed branches (``origins``: per branch the Hopf point it starts at, or None):
    Hopf points, folds and multiplier crossings."""

    films = film_names(system)
    points, bifs = [], []
    for b, hp in zip(branches, origins):
        ends = [hopf_record(system, hp, b, model, supply)] if hp is not None else []
        for end in ((b[0], b[-1]) if hp is None and len(b) > 1 else ()):
            if end.turbine_radius_m < COLLAPSE * max(p.turbine_radius_m for p in b):  # the branch ends at a Hopf point
                ends.append(_end_hopf(system, model, b, end is b[0], len(points), films, supply))
        mode = next((e["mode"] for e in ends if e["mode"]), "")  # the branch's points inherit its Hopf point's mode
        bifs += ends + _branch_events(b, len(points), films, mode)
        points.extend(b)
    meta = {"system": system.to_dict(), "film_model": model, "speed_range_rpm": [lo, hi], "rtol": SHOOT_RTOL,
            "branches": [len(b) for b in branches]}
    if supply is not None:
        meta["oil_supply"] = supply.to_dict()
    return BifurcationDiagram(points, sorted(_unique_hopf(bifs), key=lambda e: e["speed_rpm"]), meta)


def _unique_hopf(bifs):
    """The records with each Hopf point once (a branch from it and a branch through an orbit that ends there both
    record it; the one with a criticality is kept)."""
    out = []
    for b in bifs:
        same = next((i for i, o in enumerate(out) if b["type"].startswith("Hopf") and o["type"] == b["type"]
                     and abs(o["speed_rpm"] - b["speed_rpm"]) <= 1e-5 * b["speed_rpm"]), None)
        if same is None:
            out.append(b)
        elif b["criticality"] and not out[same]["criticality"]:
            out[same] = b
    return out


__all__ = ["BifurcationDiagram", "BranchPoint", "HopfPoint", "continuation", "equilibrium_jacobian", "hopf_guess",
           "hopf_points", "hopf_record", "check_starts", "shoot_segments"]
