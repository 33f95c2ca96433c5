"""Figures: holistic Campbell diagram (matplotlib PNG and plotly HTML), RSR and equilibrium-cost figures, the
run-up / run-down composite (spectrogram with Campbell overlay and RSR).

Bearing and film names come from the results (``RunupResult.bearing_names``, the system in the run's metadata,
the Campbell result's films), never from the Table 2 preset.

matplotlib and plotly are imported inside the functions that draw, so ``import frbmodel`` needs neither; the
matplotlib backend is the caller's choice (the CLI and the tests select Agg), never switched here.
"""
from __future__ import annotations

import contextlib
import contextvars

import numpy as np

from ..system.films import FILM_NAMES
from .style import D_MAX, D_MIN, HTML_HEIGHT_PX, damping_cmap, damping_colorscale, html_layout, readable

MARKERS = {"forward": ("^", "triangle-up"), "backward": ("v", "triangle-down"), "mixed": ("o", "circle")}
#: colour of neutral modes (|D| within its round-off bound), which the damping colour map would draw white
NEUTRAL_COLOR, NEUTRAL_COLOR_PLOTLY = "0.45", "rgb(115, 115, 115)"
NEUTRAL_LABEL = "neutral (|D| <= round-off bound)"
WHIRL_STYLES = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a")
#: colours of the run's RSR per bearing (matplotlib's C0, C1, ...: the PNG's and the page's alike)
RUN_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728")
#: two film whirl curves closer than this (relative to the larger curve's highest frequency, wherever both are
#: defined) coincide on a figure: they are drawn with interleaved dashes, so that both stay visible
WHIRL_COINCIDE_RTOL = 0.01
#: dash length of interleaved whirl curves [pt] (matplotlib, scaled by the line width) and [px] (plotly)
WHIRL_DASH = 5


def film_names(cd):
    """Names of the films of a Campbell result, in the order of its whirl columns: its ``film_labels`` if it has
    them, else the ``"films"`` of its metadata, else the module's default order; "film k" for any further column.

    Parameters
    ----------
    cd : CampbellResult

    Returns
    -------
    tuple of str
    """
    n = cd.whirl_hz.shape[1]
    names = tuple(getattr(cd, "film_labels", None) or cd.meta.get("films") or FILM_NAMES)
    return tuple(names[k] if k < len(names) else f"film {k}" for k in range(n))


def whirl_curves(cd):
    """Film whirl curves of a Campbell sweep, for the films that are past their onset somewhere in it.

    Parameters
    ----------
    cd : CampbellResult

    Returns
    -------
    list of tuple
        ``(film index, film name, speeds [rpm], whirl frequency [Hz] — NaN below the film's onset)``.
    """
    out = []
    for k, name in enumerate(film_names(cd)):
        w = np.where(cd.whirl_margin[:, k] > 0, cd.whirl_hz[:, k], np.nan)
        if np.isfinite(w).any():
            out.append((k, name, cd.speeds_rpm, w))
    return out


def _whirl_style(k):
    """Colour and line style of film ``k`` (films come in inner/outer pairs per bearing)."""
    return WHIRL_STYLES[k % len(WHIRL_STYLES)], "--" if (k // 2) % 2 == 0 else (0, (6, 2, 1, 2))


def _coincide(w1, w2):
    """Whether two whirl curves (NaN where undefined) lie on each other: both defined over most (80 %) of the speeds
    where either is, and within :data:`WHIRL_COINCIDE_RTOL` of their highest frequency there."""
    both, either = np.isfinite(w1) & np.isfinite(w2), np.isfinite(w1) | np.isfinite(w2)
    if both.sum() < 0.8 * either.sum():
        return False
    scale = max(np.abs(w1[both]).max(), np.abs(w2[both]).max())
    return bool(np.all(np.abs(w1[both] - w2[both]) <= WHIRL_COINCIDE_RTOL * scale))


def whirl_lines(cd):
    """The film whirl curves of :func:`whirl_curves` as figures draw them: coincident curves (e.g. the same film of
    two identical bearings, :func:`_coincide`) get interleaved dashes (each shows in the gaps of the others) and a
    label naming the curve they lie on.

    Parameters
    ----------
    cd : CampbellResult

    Returns
    -------
    list of dict
        ``k`` (film index), ``name``, ``label``, ``speeds_rpm``, ``whirl_hz``, ``color``, ``ls`` (matplotlib line
        style), ``dash`` (plotly dash).
    """
    curves = whirl_curves(cd)
    group = []
    for i, (_, _, _, w) in enumerate(curves):
        group.append(next((group[j] for j in range(i) if group[j] == j and _coincide(w, curves[j][3])), i))
    out = []
    for i, (k, name, s, w) in enumerate(curves):
        members = [j for j in range(len(curves)) if group[j] == group[i]]
        n, pos = len(members), members.index(i)
        color, ls = _whirl_style(k)
        dash = "dash" if (k // 2) % 2 == 0 else "dashdot"
        label = f"whirl {readable(name)}"
        if n > 1:
            L = WHIRL_DASH
            ls = (pos * L, (L, (n - 1) * L))
            dash = f"0px,{pos * L}px,{L}px,{(n - 1 - pos) * L}px"
            if pos:
                label += f" (on {readable(curves[members[0]][1])})"
        out.append(dict(k=k, name=name, label=label, speeds_rpm=s, whirl_hz=w, color=color, ls=ls, dash=dash))
    return out


def _plot_whirl(ax, cd, lw=1.3):
    for line in whirl_lines(cd):
        ax.plot(line["speeds_rpm"] / 1e3, line["whirl_hz"], ls=line["ls"], lw=lw, color=line["color"],
                label=line["label"])


#: the default frequency axis of a Campbell diagram ends at this multiple of its highest unstable-mode frequency
CAMPBELL_FMAX_FACTOR = 1.3


def full_fmax(cd):
    """Upper frequency [Hz] of a Campbell diagram's full range: 1.15 × the highest rotor frequency, at least 500 Hz.

    Parameters
    ----------
    cd : CampbellResult

    Returns
    -------
    float
    """
    f1x = cd.speeds_rpm.max() / 60.0
    return float(max(1.15 * f1x, 500.0))


def _default_fmax(cd):
    """Default upper frequency [Hz] of a Campbell figure: :data:`CAMPBELL_FMAX_FACTOR` × the highest frequency of
    an unstable mode (at least 500 Hz, at most :func:`full_fmax`), so that the unstable modes fill the figure; the
    full range without unstable modes."""
    f = cd.frequencies_hz[cd.unstable]
    f = f[np.isfinite(f)]
    full = full_fmax(cd)
    return float(min(full, max(CAMPBELL_FMAX_FACTOR * f.max(), 500.0))) if f.size else full


def campbell_range_note(cd, fmax_hz=None):
    """What a Campbell figure's frequency axis shows, for its title: the default range (the unstable modes) and
    the value that shows the full range; empty when the axis is given or is the full range.

    Parameters
    ----------
    cd : CampbellResult
    fmax_hz : float, optional
        The upper frequency the caller chose [Hz].

    Returns
    -------
    str
    """
    full = full_fmax(cd)
    if fmax_hz or _default_fmax(cd) >= full:
        return ""
    return (f"frequency axis to {CAMPBELL_FMAX_FACTOR:g} × the highest unstable mode; full range: fmax "
            f"{full:.0f} Hz (frb campbell --fmax {full:.0f})")


def _mark_critical_speeds(ax, cs, fmax):
    """Critical speeds (a table with ``speed [rpm]`` and ``frequency [Hz]``: the 1X crossings the analysis found) as
    stars on the 1X line."""
    if cs is None:
        return
    cs = cs[cs["frequency [Hz]"] <= fmax]
    if len(cs):
        ax.scatter(cs["speed [rpm]"] / 1e3, cs["frequency [Hz]"], marker="*", s=110, color="gold",
                   edgecolors="k", linewidths=0.7, zorder=4, label="critical speeds (1X crossings)")


def campbell_figure(cd, fmax_hz=None, whirl=True, one_x=True, ax=None, title=None, critical=None):
    """Holistic Campbell diagram: frequency vs speed, colour = modal damping (unstable red, stable blue,
    :data:`frbmodel.plots.style.DAMPING_STOPS`), marker = precession (▲ forward, ▼ backward, ● mixed), unstable
    modes enlarged with a black edge, neutral modes
    (|D| within its round-off bound, e.g. every mode of the undamped methods A, B, E) grey; dashed film whirl curves
    above their onset; optional 1X line with the critical speeds (its crossings with the damped branches) starred.

    Parameters
    ----------
    cd : CampbellResult
    fmax_hz : float, optional
        Upper frequency limit [Hz] (default: :data:`CAMPBELL_FMAX_FACTOR` × the highest unstable-mode frequency,
        said in the title with the value of the full range, :func:`campbell_range_note`; the full range,
        :func:`full_fmax`, without unstable modes).
    whirl, one_x : bool
        Draw the film whirl curves and the 1X line (with the critical speeds).
    ax : matplotlib.axes.Axes, optional
        Draw into these axes (default: a new figure).
    title : str, optional

    critical : pandas.DataFrame, optional
        Critical speeds to mark on the 1X line (``speed [rpm]``, ``frequency [Hz]``;
        :func:`frbmodel.linear.unbalance.critical_speeds`, as :meth:`CampbellResult.plot` passes them).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    fmax = fmax_hz or _default_fmax(cd)
    if ax is None:
        fig, ax = plt.subplots(figsize=(9, 6))
    else:
        fig = ax.figure
    norm, cmap = Normalize(vmin=D_MIN, vmax=D_MAX), damping_cmap()
    S = np.repeat(cd.speeds_rpm[:, None], cd.n_modes, axis=1) / 1e3
    F, D, P = cd.frequencies_hz, cd.damping, cd.precession
    state = cd.stability
    shown = np.isfinite(F) & (F <= fmax)
    sc = None
    for prec, (mk, _) in MARKERS.items():
        for unstable in (False, True):
            sel = shown & (P == prec) & (state == ("unstable" if unstable else "stable"))
            if not sel.any():
                continue
            sc = ax.scatter(S[sel], F[sel], c=np.clip(D[sel], D_MIN, D_MAX), cmap=cmap, norm=norm, marker=mk,
                            s=46 if unstable else 16, edgecolors="k" if unstable else "none",
                            linewidths=0.8 if unstable else 0, zorder=3 if unstable else 2)
        sel = shown & (P == prec) & (state == "neutral")
        if sel.any():
            ax.scatter(S[sel], F[sel], color=NEUTRAL_COLOR, marker=mk, s=16, linewidths=0, zorder=2)
    if whirl:
        _plot_whirl(ax, cd)
    if one_x:
        ax.plot(cd.speeds_rpm / 1e3, cd.speeds_rpm / 60.0, color="0.4", lw=1, ls=":", label="1X")
        _mark_critical_speeds(ax, critical, fmax)
    for prec, (mk, _) in MARKERS.items():  # shape = precession (hollow: the fill is the damping colour)
        ax.scatter([], [], marker=mk, facecolors="none", edgecolors="0.2", s=25, label=prec)
    ax.scatter([], [], marker="o", color=cmap(norm(-0.5)), edgecolors="k", linewidths=0.8, s=46,
               label="unstable (D < -round-off bound)")
    if (shown & (state == "neutral")).any():
        ax.scatter([], [], marker="s", color=NEUTRAL_COLOR, s=25, label=NEUTRAL_LABEL)
    lo, hi = cd.speeds_rpm.min() / 1e3, cd.speeds_rpm.max() / 1e3
    ax.set_xlim(lo - 0.05 * max(hi, 1.0) if hi == lo else lo, hi + 0.05 * max(hi, 1.0) if hi == lo else hi)
    ax.set_ylim(0, fmax)
    ax.set_xlabel("rotor speed [krpm]")
    ax.set_ylabel("frequency [Hz]")
    note = campbell_range_note(cd, fmax_hz)
    ax.set_title(title or f"Holistic Campbell diagram, method {cd.method} ({cd.system_name})"
                 + (f"\n{note}" if note else ""), fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3)  # below: never on the data
    if sc is not None:
        cb = fig.colorbar(sc, ax=ax, pad=0.01)
        cb.set_label("modal damping D = -Re(λ)/|λ| [-]")
    return fig


def _campbell_trace(go, S, F, D, P, Kd, modes, sel, name, unstable, text, colorbar):
    """One marker trace of :func:`campbell_plotly`: the points ``sel``, coloured by damping, shaped by precession
    (unstable ones larger, black edged)."""
    shape_line = "" if text is None else "<br>shape (orbit semi-major axis, phase of x, whirl):<br>%{text}"
    symbols = np.array([MARKERS.get(p, MARKERS["mixed"])[1] for p in P[sel]], dtype=object)
    return go.Scatter(
        x=S[sel], y=F[sel], mode="markers", name=name, legendgroup=name,
        marker=dict(symbol=symbols, size=10 if unstable else 6, color=np.clip(D[sel], D_MIN, D_MAX),
                    colorscale=damping_colorscale(), cmin=D_MIN, cmax=D_MAX,
                    line=dict(width=1.2 if unstable else 0, color="black"), showscale=colorbar,
                    colorbar=dict(title="D [-]", len=0.75, y=0.62) if colorbar else None),
        customdata=np.stack([D[sel], modes[sel], Kd[sel], P[sel]], axis=-1),
        text=None if text is None else text[sel],
        hovertemplate=("speed %{x:.0f} rpm<br>f %{y:.1f} Hz<br>D %{customdata[0]:.4f}"
                       + (" (unstable)" if unstable else "") + "<br>%{customdata[3]} precession<br>"
                       "mode %{customdata[1]} (%{customdata[2]})" + shape_line + "<extra></extra>"))


def campbell_plotly(cd, fmax_hz=None, whirl=True, one_x=True, hover=None, critical=None):
    """Interactive holistic Campbell diagram (plotly), the content of :func:`campbell_figure`: one trace per
    precession of the stable modes, one of the unstable modes ("unstable", larger, black edged), one of the
    neutral modes (|D| within its round-off bound, grey), the whirl curves (:func:`whirl_lines`), 1X and the
    critical speeds (stars). The points up to ``fmax_hz`` (default: the full range, :func:`full_fmax`) are in
    the page; the axis opens at ``fmax_hz`` or the default range of :func:`campbell_figure` (double-click: all).
    Hover shows speed, frequency, D, its stability, the precession, the mode's kind and — with ``hover`` — its
    shape (the texts of :func:`frbmodel.linear.modeshape.shape_hover_text`).

    Parameters
    ----------
    cd, fmax_hz, whirl, one_x, critical
        As for :func:`campbell_figure`.
    hover : (n, m) ndarray of str, optional
        Mode-shape text per point (``""`` for none), e.g. :func:`frbmodel.linear.modeshape.shape_hover_text`.

    Returns
    -------
    plotly.graph_objects.Figure
    """
    import plotly.graph_objects as go

    top = fmax_hz or full_fmax(cd)
    fig = go.Figure()
    S = np.repeat(cd.speeds_rpm[:, None], cd.n_modes, axis=1)
    F, D, P, Kd = cd.frequencies_hz, cd.damping, cd.precession, cd.mode_kind
    modes = np.repeat(np.arange(cd.n_modes)[None, :], cd.speeds_rpm.size, axis=0)
    state = cd.stability
    shown = np.isfinite(F) & (F <= top)
    first = True
    for prec in MARKERS:
        sel = shown & (P == prec) & (state == "stable")
        if sel.any():
            fig.add_trace(_campbell_trace(go, S, F, D, P, Kd, modes, sel, prec, False, hover, first))
            first = False
    sel = shown & (state == "unstable")
    if sel.any():
        fig.add_trace(_campbell_trace(go, S, F, D, P, Kd, modes, sel, "unstable (D < -round-off bound)", True,
                                      hover, first))
    _campbell_plotly_neutral(go, fig, S, F, D, P, Kd, modes, shown & (state == "neutral"), hover)
    if whirl:
        for line in whirl_lines(cd):
            fig.add_trace(go.Scatter(x=line["speeds_rpm"], y=line["whirl_hz"], mode="lines", name=line["label"],
                                     line=dict(dash=line["dash"], color=line["color"], width=2),
                                     hovertemplate="speed %{x:.0f} rpm<br>whirl %{y:.1f} Hz<extra>"
                                     + readable(line["name"]) + "</extra>"))
    if one_x:
        fig.add_trace(go.Scatter(x=cd.speeds_rpm, y=cd.speeds_rpm / 60, mode="lines", name="1X",
                                 line=dict(dash="dot", color="gray")))
        _critical_plotly(go, fig, critical)
    note = campbell_range_note(cd, fmax_hz)
    title = f"Holistic Campbell diagram, method {cd.method} ({cd.system_name})"
    fig.update_layout(title=title + (f"<br><sup>{note}; double-click the plot for all points</sup>" if note else ""),
                      xaxis_title="rotor speed [rpm]", yaxis_title="frequency [Hz]",
                      yaxis_range=[0, fmax_hz or _default_fmax(cd)], template="plotly_white",
                      **html_layout())
    return fig


def _campbell_plotly_neutral(go, fig, S, F, D, P, Kd, modes, sel, text):
    """The neutral modes of :func:`campbell_plotly`: one grey trace."""
    if not sel.any():
        return
    shape_line = "" if text is None else "<br>shape (orbit semi-major axis, phase of x, whirl):<br>%{text}"
    symbols = np.array([MARKERS.get(p, MARKERS["mixed"])[1] for p in P[sel]], dtype=object)
    fig.add_trace(go.Scatter(
        x=S[sel], y=F[sel], mode="markers", name=NEUTRAL_LABEL,
        marker=dict(symbol=symbols, size=6, color=NEUTRAL_COLOR_PLOTLY),
        customdata=np.stack([D[sel], modes[sel], Kd[sel], P[sel]], axis=-1),
        text=None if text is None else text[sel],
        hovertemplate=("speed %{x:.0f} rpm<br>f %{y:.1f} Hz<br>D %{customdata[0]:.2e} (neutral)<br>"
                       "%{customdata[3]} precession<br>mode %{customdata[1]} (%{customdata[2]})" + shape_line
                       + "<extra></extra>")))


def _critical_plotly(go, fig, cs):
    """Critical speeds (the table of :func:`_mark_critical_speeds`) as stars on the 1X line."""
    if cs is None or not len(cs):
        return
    fig.add_trace(go.Scatter(x=cs["speed [rpm]"], y=cs["frequency [Hz]"], mode="markers",
                             name="critical speeds (1X crossings)",
                             marker=dict(symbol="star", size=14, color="gold", line=dict(width=1, color="black")),
                             hovertemplate="critical speed %{x:.0f} rpm<br>%{y:.1f} Hz<extra></extra>"))


def rsr_figure(results, title="Ring-speed ratio", bearing_names=None):
    """Ring-speed ratio vs speed for several Campbell/equilibrium sweeps, one panel per bearing side by side.

    Parameters
    ----------
    results : dict
        Label (method letter) -> ``(speeds [rpm] (n,), RSR [-] (n, nb))``, bearings in the system's order.
    title : str
    bearing_names : sequence of str, optional
        Bearing names, e.g. ``[b.name for b in system.bearings]``: panel titles "<name> bearing" (default
        "bearing 1", "bearing 2", ...).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    nb = np.asarray(next(iter(results.values()))[1]).shape[1]
    titles = [f"{n} bearing" for n in bearing_names] if bearing_names is not None else \
        [f"bearing {j + 1}" for j in range(nb)]
    fig, axes = plt.subplots(1, nb, figsize=(5 * nb, 4), sharey=True, squeeze=False)
    axes = axes[0]
    styles = ["-", "--", "-.", ":"]
    for k, (label, (s, r)) in enumerate(results.items()):
        for j, ax in enumerate(axes):
            ax.plot(np.asarray(s) / 1e3, np.asarray(r)[:, j], ls=styles[k % 4], lw=1.6, label=f"method {label}")
    for j, ax in enumerate(axes):
        ax.set_title(titles[j], fontsize=10)
        ax.set_xlabel("rotor speed [krpm]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("RSR = ω_FR / ω_R [-]")
    axes[0].legend()
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def equilibrium_cost_figure(stats, title="Equilibrium cost per speed"):
    """Bar chart of CPU time [ms], iterations and film evaluations per equilibrium for several methods (mean and
    standard deviation over speeds).

    Parameters
    ----------
    stats : dict
        Method letter -> dict with keys ``time_ms``, ``iterations``, ``evaluations`` (arrays over speeds).
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(11, 3.6))
    letters = list(stats)
    for ax, key, lab in zip(axes, ("time_ms", "iterations", "evaluations"),
                            ("CPU time per equilibrium [ms]", "iterations [-]", "film evaluations [-]")):
        vals = [np.mean(stats[k][key]) for k in letters]
        err = [np.std(stats[k][key]) for k in letters]
        ax.bar(letters, vals, yerr=err, color=["#4c72b0", "#55a868", "#c44e52", "#8172b2"][:len(letters)])
        ax.set_title(lab, fontsize=10)
        ax.grid(alpha=0.3, axis="y")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def unstable_lines(cd, fmax):
    """(speed_krpm, f_hz) arrays per mode, NaN where the mode is stable."""
    out = []
    for j in range(cd.n_modes):
        f = np.where(cd.unstable[:, j], cd.frequencies_hz[:, j], np.nan)  # D < -round-off bound
        if np.isfinite(f).any() and np.nanmin(f) < fmax:
            out.append((cd.speeds_rpm / 1e3, f, j))
    return out


def _bearing_names(run):
    """Bearing names of a run-up result, in the column order of its ring-speed ratio."""
    names = getattr(run, "bearing_names", None)
    return tuple(names) if names is not None else tuple(run.journal)


def _rsr_panel(ax, run, xscale, linear=None):
    """Ring-speed ratios of the run and, if given, of the linear methods' equilibria (``linear``: (speeds [rpm],
    {method letter: RSR (n, nb)}, bearing names), :func:`frbmodel.linear.equilibrium.linear_rsr`); one line per
    bearing, named as in the run."""
    names = _bearing_names(run)
    rr = run.ring_speed_ratio
    kind = "run-down" if run.speed_rpm[-1] < run.speed_rpm[0] else "run-up"
    for j, name in enumerate(names):
        ax.plot(run.speed_rpm / 1e3, rr[:, j], lw=0.8, alpha=0.8, color=RUN_COLORS[j % len(RUN_COLORS)],
                label=f"{kind}, {name}")
    if linear is not None:
        speeds, by_method, bearing_names = linear
        styles = {"F": "-", "I": "-.", "J": "--"}
        greys = ("k", "0.55", "0.3", "0.75")
        for m, arr in by_method.items():
            for j, b in enumerate(bearing_names):
                ax.plot(speeds / 1e3, arr[:, j], styles.get(m, ":"), color=greys[j % len(greys)], lw=1.2,
                        label=f"method {m}{' (eq. 6)' if m == 'F' else ''}, {b}")
    ax.set_xscale(xscale)
    ax.set_xlabel(_speed_label(kind))
    ax.set_ylabel("RSR = ω_FR / ω_R [-]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.1), ncol=2)  # below the panel, never on it
    ax.set_title("ring-speed ratio", fontsize=10)


def _speed_label(kind, unit="krpm"):
    """Speed-axis label; a run-down's axis still increases to the right, so the label says time runs leftwards."""
    return f"rotor speed [{unit}]" + (" (run-down: time runs right to left)" if kind == "run-down" else "")


def _kind(sp):
    """The kind of run of a spectrogram: "run-down", else "run-up" (also at constant speed)."""
    return "run-down" if sp.speeds_rpm[-1] < sp.speeds_rpm[0] else "run-up"


def _speed_order(sp):
    """Segment order by increasing speed (a run-down's segments reversed), stable for equal speeds: the
    spectrogram drawn against an increasing speed axis whatever the direction of the run."""
    return np.argsort(sp.speeds_rpm, kind="stable")


def content_fmax(sp, db_range=None, margin=1.2):
    """Default upper frequency of the spectrogram figures [Hz]: ``margin`` × the highest frequency whose amplitude
    (forward or backward, any segment) lies within ``db_range`` of the largest, at most the Nyquist frequency.

    Parameters
    ----------
    sp : SpectrogramResult
    db_range : float, optional
        Colour range [dB] (default ``sp.db_range``).
    margin : float
        Factor on the highest visible frequency.

    Returns
    -------
    float

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> f = np.arange(0.0, 5000.0, 10.0)
    >>> a = np.where(f <= 800.0, 1e-6, 1e-9)[:, None] * np.ones((1, 3))
    >>> sp = SimpleNamespace(freqs_hz=f, amplitude=a, db_range=25.0)
    >>> content_fmax(sp)
    960.0
    """
    rng = sp.db_range if db_range is None else db_range
    a = sp.amplitude.max(axis=1)
    vis = np.flatnonzero(a >= a.max() * 10 ** (-rng / 20.0))
    top = sp.freqs_hz[vis[-1]] if vis.size else sp.freqs_hz[-1]
    return float(min(sp.freqs_hz[-1], margin * max(top, sp.freqs_hz[1])))


def order_label(k):
    """Label of the order line k × f_rot: ``"1X"``, ``"0.5X"``, ``"2X"``."""
    return f"{k:g}X"


def spectrogram_colour(sp, amplitude="db_max"):
    """Colour data, limits and colour-bar label of a spectrogram figure.

    Parameters
    ----------
    sp : SpectrogramResult
    amplitude : {"db_max", "um", "db_um"}
        dB relative to the largest amplitude (the paper's figures), orbit amplitude in µm (linear), or dB re 1 µm;
        each over ``sp.db_range`` below the largest amplitude (µm: from 0).

    Returns
    -------
    z : (f, k) ndarray
    vmin, vmax : float
    label : str
    """
    a = sp.amplitude
    top = float(a.max())
    if amplitude == "db_max":
        return sp.db(), -sp.db_range, 0.0, f"orbit amplitude [dB re max], {sp.db_range:g} dB range"
    if amplitude == "um":
        return a * 1e6, 0.0, top * 1e6, "orbit amplitude [µm]"
    if amplitude == "db_um":
        hi = 20 * np.log10(top / 1e-6)
        return (20 * np.log10(np.maximum(a, 1e-300) / 1e-6), hi - sp.db_range, hi,
                f"orbit amplitude [dB re 1 µm], {sp.db_range:g} dB range")
    raise ValueError(f"amplitude = {amplitude!r} is invalid: valid 'db_max', 'um', 'db_um'")


def component_marks(sp):
    """Where a composite figure labels the tracked components, and which it leaves out: only components whose
    largest amplitude lies within the colour range (``sp.db_range`` below the largest amplitude of the
    spectrogram) are drawn.

    Parameters
    ----------
    sp : SpectrogramResult

    Returns
    -------
    marks : list of dict
        Per drawn component: ``text`` (its label, "(from start)" without an onset), ``at`` ((speed [rpm],
        frequency [Hz]) of the label: the onset, else the first detection within the colour range), ``end``
        (where it vanishes, if it vanishes while within the colour range, else None) and ``fade`` (its last
        detection within the colour range, if it then falls below the range — vanishing later or not — else None).
    hidden : list of tuple
        ``(label, largest amplitude [dB re the spectrogram's largest])`` of the components below the colour range.
    """
    top = float(sp.amplitude.max())
    floor = top * 10 ** (-sp.db_range / 20.0)
    marks, hidden = [], []
    for c in sp.components():
        vis = np.asarray(c.amplitude_m) >= floor
        if not vis.any():
            hidden.append((c.label, float(20 * np.log10(np.max(c.amplitude_m) / top))))
            continue
        s, f = np.asarray(c.speeds_rpm)[vis], np.asarray(c.freqs_hz)[vis]
        if np.isfinite(c.onset_rpm):
            at, text = (c.onset_rpm, c.onset_hz), c.label
        else:
            at, text = (s[0], f[0]), f"{c.label} (from start)"
        end = (c.end_rpm, c.end_hz) if np.isfinite(c.end_rpm) and vis[-1] else None
        fade = None if vis[-1] else (s[-1], f[-1])
        marks.append(dict(text=text, at=at, end=end, fade=fade))
    return marks, hidden


def hidden_note(sp, hidden):
    """The line a composite figure adds for the components below its colour range (:func:`component_marks`);
    empty if there are none."""
    if not hidden:
        return ""
    items = ", ".join(f"{label} (max {db:.1f} dB)" for label, db in hidden)
    return f"not drawn, below the {sp.db_range:g} dB colour range: {items} (see components_{sp.node}.csv)"


#: where a component label may sit relative to its point [pt] (first free one is taken): right-above,
#: right-below, left-above, left-below, further up, further down
LABEL_OFFSETS = ((3, 4), (3, -13), (-3, 4), (-3, -13), (3, 14), (3, -23))


def _label_components(ax, marks):
    """Component labels (``marks`` of :func:`component_marks`) at their onset, or "(from start)" at their first visible
    detection; a cross where a component vanishes, a hollow circle where it falls below the colour range.

    Returns
    -------
    list
        The label annotations (placed clear of the markers by :func:`_place_labels`).
    """
    labels, legend = [], {"end": "component vanishes", "fade": "falls below the colour range"}
    for m in marks:
        labels.append(ax.annotate(m["text"], (m["at"][0] / 1e3, m["at"][1]), color="w", fontsize=9,
                                  fontweight="bold", xytext=LABEL_OFFSETS[0], textcoords="offset points",
                                  ha="left", zorder=6))
        for key, style in (("end", dict(marker="x", color="w", mew=1.5)),
                           ("fade", dict(marker="o", mfc="none", mec="w", mew=1.2))):
            if m[key] is not None:
                ax.plot(m[key][0] / 1e3, m[key][1], ls="none", ms=7, label=legend.pop(key, None), zorder=5,
                        gid="component-marker", **style)
    return labels


def _place_labels(ax, labels, down=False):
    """Move each label to the first offset of :data:`LABEL_OFFSETS` (left ones first in a run-down, which
    starts at the right edge) where it covers no component marker and no label placed before it."""
    renderer = getattr(ax.figure.canvas, "get_renderer", lambda: None)()
    if renderer is None or not labels:
        return
    pts = [ax.transData.transform(np.column_stack(ln.get_data())) for ln in ax.lines
           if ln.get_gid() == "component-marker"]
    pts = np.vstack(pts) if pts else np.empty((0, 2))
    order = sorted(LABEL_OFFSETS, key=lambda o: (o[0] > 0) if down else 0)
    placed = []
    for ann in labels:
        for dx, dy in order:
            ann.set_position((dx, dy))
            ann.set_horizontalalignment("left" if dx > 0 else "right")
            bb = ann.get_window_extent(renderer).padded(5)  # (a marker reaches ~5 px from its point)
            on_marker = ((pts[:, 0] >= bb.x0) & (pts[:, 0] <= bb.x1) & (pts[:, 1] >= bb.y0) & (pts[:, 1] <= bb.y1))
            if not (on_marker.any() or any(bb.overlaps(o) for o in placed)):
                break
        placed.append(ann.get_window_extent(renderer))


def composite_figure(sp, campbell=None, whirl=True, rsr=True, fmax_hz=None, components=True, title=None,
                     xscale="linear", amplitude="db_max", orders=(1.0,), linear_rsr=None):
    """The paper's Figs. 12–14: spectrogram (25 dB, log) with unstable Campbell modes (solid), film whirl
    curves (dashed), 1X (dotted), component labels; RSR of the run vs the linear methods beside it.

    The speed axis increases to the right for run-ups and run-downs alike (so the Campbell overlay reads as
    usual); a run-down is titled and labelled as one, its components are labelled at their onset (or "(from
    start)" at their first detection) and a cross marks where one vanishes.

    Parameters
    ----------
    sp : SpectrogramResult
    campbell : CampbellResult, optional
        Method-J Campbell diagram for the overlay.
    whirl : bool
        Draw the film whirl curves of ``campbell``.
    rsr : bool
        Add the RSR panel (needs ``sp.run``).
    linear_rsr : tuple, optional
        The linear methods' RSR drawn in that panel: (speeds [rpm], {method letter: RSR (n, nb)}, bearing names),
        e.g. :func:`frbmodel.linear.equilibrium.linear_rsr` (:meth:`SpectrogramResult.plot` computes it when the
        run carries its system).
    fmax_hz : float, optional
        Upper frequency limit [Hz] (default: :func:`content_fmax`, the content within the colour range).
    components : bool
        Label the tracked components (those within the colour range).
    title : str, optional
    xscale : {"linear", "log"}
    amplitude : {"db_max", "um", "db_um"}
        Colour scale (:func:`spectrogram_colour`).
    orders : sequence of float
        Order lines k × f_rot drawn dotted (1X by default; e.g. ``(0.5, 1, 2)``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    run = sp.run
    kind = _kind(sp)
    fmax = fmax_hz or content_fmax(sp)
    if rsr and run is not None:
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(14, 6), gridspec_kw={"width_ratios": [2.3, 1]})
    else:
        fig, ax = plt.subplots(figsize=(10, 6))
        ax2 = None
    sel = sp.freqs_hz <= fmax
    order = _speed_order(sp)
    s_all = sp.speeds_rpm[order]
    z, vmin, vmax, clabel = spectrogram_colour(sp, amplitude)
    mesh = ax.pcolormesh(s_all / 1e3, sp.freqs_hz[sel], z[sel][:, order], shading="nearest", cmap="magma",
                         vmin=vmin, vmax=vmax, rasterized=True)
    cb = fig.colorbar(mesh, ax=ax, pad=0.01)
    cb.set_label(clabel)
    for k in orders:
        ax.plot(s_all / 1e3, k * s_all / 60.0, ":", color="w" if k == 1 else "#bbbbbb", lw=1, label=order_label(k))
    if campbell is not None:
        for i, (sk, f, _) in enumerate(unstable_lines(campbell, fmax)):
            label = None if i else f"unstable modes, method {campbell.method}"
            ax.plot(sk, f, "-", color="#00e5ff", lw=1.6, label=label)
        if whirl:
            _plot_whirl(ax, campbell, lw=1.2)
    marks, hidden = component_marks(sp) if components else ([], [])
    labels = _label_components(ax, marks)
    ax.set_xlim(s_all.min() / 1e3, s_all.max() / 1e3)
    ax.set_ylim(0, fmax)
    ax.set_xscale(xscale)
    ax.set_xlabel(_speed_label(kind))
    ax.set_ylabel("frequency [Hz]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.1), ncol=3,  # below the heatmap, never on it
              facecolor="0.2", labelcolor="w", framealpha=1.0)  # (dark: the white lines and markers show)
    note = hidden_note(sp, hidden)
    ax.set_title((title or f"{kind.capitalize()} spectrogram, {readable(sp.node)} (orbit x + iy)")
                 + (f"\n{note}" if note else ""), fontsize=10)
    if ax2 is not None:
        _rsr_panel(ax2, run, xscale, linear_rsr)
    fig.tight_layout()
    _place_labels(ax, labels, down=kind == "run-down")
    return fig


#: the largest heatmap an interactive spectrogram file keeps (``compact``): columns (speeds) × rows (frequencies),
#: about the pixels of a full-screen plot area. Nothing is lost that the data holds: the segments overlap by 75 %
#: and the spectrum is zero padded 4× (4 columns and 4 rows per independent value), and blocks keep their maximum.
HTML_MAX_COLUMNS, HTML_MAX_ROWS = 1000, 250


def peak_decimate(z, coord, max_n, axis):
    """Merge consecutive entries of ``z`` along ``axis`` into blocks so that at most ``max_n`` remain, each block
    keeping its largest value (so no peak is lost) at the mean coordinate of the block.

    Parameters
    ----------
    z : ndarray
        Values (e.g. a spectrogram, frequency × speed).
    coord : (n,) ndarray
        Coordinates of the entries along ``axis`` (increasing).
    max_n : int
        Largest number of blocks.
    axis : int

    Returns
    -------
    z : ndarray
        Block maxima (NaN ignored).
    coord : ndarray
        Block mean coordinates.

    Examples
    --------
    >>> z, c = peak_decimate(np.array([[1.0, 5.0, 2.0, 0.0, 3.0]]), np.arange(5.0), 3, axis=1)
    >>> z.tolist(), c.tolist()
    ([[5.0, 2.0, 3.0]], [0.5, 2.5, 4.0])
    """
    n = coord.size
    size = -(-n // max(1, int(max_n)))
    if size <= 1:
        return z, coord
    starts = np.arange(0, n, size)
    counts = np.diff(np.append(starts, n))
    return np.fmax.reduceat(z, starts, axis=axis), np.add.reduceat(coord, starts) / counts


def _compact_heatmap(speeds, freqs, z):
    """The heatmap of an interactive file: peak-decimated to the screen, in single precision."""
    z, speeds = peak_decimate(z, speeds, HTML_MAX_COLUMNS, axis=1)
    z, freqs = peak_decimate(z, freqs, HTML_MAX_ROWS, axis=0)
    return speeds.astype(np.float32), freqs.astype(np.float32), z.astype(np.float32)


def composite_plotly(sp, campbell=None, fmax_hz=None, amplitude="db_max", orders=(1.0,), compact=False, rsr=True,
                     linear_rsr=None, components=True):
    """Interactive composite (plotly), the content of :func:`composite_figure`: spectrogram heatmap with the
    unstable modes (one legend entry, hover names the mode), whirl curves (:func:`whirl_lines`), order lines and
    the component labels and markers (:func:`component_marks`), and the ring-speed ratio panel beside it; the
    speed axis increases to the right for run-ups and run-downs alike (a run-down is titled as one).

    Parameters
    ----------
    sp, campbell, fmax_hz, amplitude, orders, rsr, linear_rsr, components
        As for :func:`composite_figure`.
    compact : bool
        For a file: at most :data:`HTML_MAX_COLUMNS` × :data:`HTML_MAX_ROWS` heatmap cells (blocks of segments /
        frequencies merged by :func:`peak_decimate`, which keeps every peak's value), arrays in single precision
        (7 digits), order lines by their end points (they are straight). Default: the full arrays.

    Returns
    -------
    plotly.graph_objects.Figure
    """
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    kind = _kind(sp)
    fmax = fmax_hz or content_fmax(sp)
    with_rsr = rsr and sp.run is not None
    fig = make_subplots(rows=1, cols=2 if with_rsr else 1, column_widths=[0.66, 0.34] if with_rsr else None,
                        horizontal_spacing=0.12, subplot_titles=("", "ring-speed ratio") if with_rsr else None)
    sel = sp.freqs_hz <= fmax
    order = _speed_order(sp)
    s_all = sp.speeds_rpm[order]
    z, vmin, vmax, _ = spectrogram_colour(sp, amplitude)
    x, y, z = s_all, sp.freqs_hz[sel], z[sel][:, order]
    num = (lambda a: np.asarray(a, dtype=np.float32)) if compact else np.asarray
    if compact:
        x, y, z = _compact_heatmap(x, y, z)
    unit = "µm" if amplitude == "um" else "dB"
    cb_x = fig.layout.xaxis.domain[1] + 0.005
    fig.add_trace(go.Heatmap(x=x, y=y, z=z, zmin=vmin, zmax=vmax, colorscale="Magma",
                             colorbar=dict(title=unit, x=cb_x, xanchor="left", len=1.0, thickness=14),
                             hovertemplate="speed %{x:.0f} rpm<br>f %{y:.1f} Hz<br>%{z:.3g} " + unit
                             + "<extra></extra>"), 1, 1)
    s_line = s_all[[0, -1]] if compact else s_all
    for k in orders:
        fig.add_trace(go.Scatter(x=num(s_line), y=num(k * s_line / 60), mode="lines", name=order_label(k),
                                 line=dict(dash="dot", color="white" if k == 1 else "#bbbbbb")), 1, 1)
    if campbell is not None:
        _campbell_overlay_plotly(go, fig, campbell, fmax, num)
    marks, hidden = component_marks(sp) if components else ([], [])
    _components_plotly(go, fig, marks, (float(s_all.min()), float(s_all.max())), (0.0, fmax), kind == "run-down")
    if with_rsr:
        _rsr_plotly(go, fig, sp.run, linear_rsr, num)
    note = hidden_note(sp, hidden)
    title = f"{kind.capitalize()} spectrogram, {readable(sp.node)}" + (f"<br><sup>{note}</sup>" if note else "")
    fig.update_xaxes(title_text=_speed_label(kind, "rpm"), range=[float(s_all.min()), float(s_all.max())],
                     row=1, col=1)
    fig.update_yaxes(title_text="frequency [Hz]", range=[0, fmax], row=1, col=1)
    fig.update_layout(title=title, **html_layout())
    fig.update_layout(legend=dict(bgcolor="rgb(50,50,50)", font=dict(color="white")))  # (the white lines show)
    return fig


def _campbell_overlay_plotly(go, fig, cd, fmax, num):
    """Unstable modes (one legend entry, the mode in the hover) and whirl curves of ``cd`` on the heatmap."""
    for i, (sk, f, j) in enumerate(unstable_lines(cd, fmax)):
        fig.add_trace(go.Scatter(x=num(sk * 1e3), y=num(f), mode="lines", name=f"unstable modes, method {cd.method}",
                                 legendgroup="unstable", showlegend=i == 0, line=dict(color="#00e5ff", width=2),
                                 hovertemplate=f"unstable mode {j}<br>" + "speed %{x:.0f} rpm<br>f %{y:.1f} Hz"
                                 "<extra></extra>"), 1, 1)
    for line in whirl_lines(cd):
        w = line["whirl_hz"]
        if not np.nanmin(w) <= fmax:  # above the frequency axis: invisible
            continue
        fig.add_trace(go.Scatter(x=num(line["speeds_rpm"]), y=num(w), mode="lines", name=line["label"],
                                 line=dict(dash=line["dash"], color=line["color"], width=2)), 1, 1)


#: the plot area a label placement of an interactive composite assumes [px] (the heatmap on a laptop screen), and
#: the size of a label's character [px] (bold, 12 px font)
HTML_PLOT_PX, HTML_CHAR_PX = (820.0, 520.0), (7.5, 15.0)


def label_boxes(marks, x_range, y_range, down=False):
    """Where an interactive composite puts the component labels: for each, the first of right-above, right-below,
    left-above, left-below of its point (left first in a run-down) whose box — estimated in data units from
    :data:`HTML_PLOT_PX` and :data:`HTML_CHAR_PX` — holds no marker and no label placed before it.

    Parameters
    ----------
    marks : list of dict
        :func:`component_marks`.
    x_range, y_range : (float, float)
        Axis ranges [rpm], [Hz].
    down : bool
        A run-down (its labels prefer the left side).

    Returns
    -------
    list of tuple
        Per label ``(xanchor, yanchor, (x0, x1, y0, y1))``: the anchors of the annotation and its estimated box.
    """
    px = ((x_range[1] - x_range[0]) / HTML_PLOT_PX[0], (y_range[1] - y_range[0]) / HTML_PLOT_PX[1])
    pts = np.array([m[k] for m in marks for k in ("end", "fade") if m[k] is not None], dtype=float).reshape(-1, 2)
    sides = [("left", "bottom"), ("left", "top"), ("right", "bottom"), ("right", "top")]
    if down:
        sides = sides[2:] + sides[:2]
    placed = []
    for m in marks:
        x, y = (float(v) for v in m["at"])
        w, h = (len(m["text"]) * HTML_CHAR_PX[0] + 6) * px[0], (HTML_CHAR_PX[1] + 6) * px[1]
        for xa, ya in sides:
            box = (x, x + w) if xa == "left" else (x - w, x)
            box = box + ((y, y + h) if ya == "bottom" else (y - h, y))
            inside = ((pts[:, 0] >= box[0]) & (pts[:, 0] <= box[1]) & (pts[:, 1] >= box[2]) & (pts[:, 1] <= box[3]))
            if not (inside.any() or any(_boxes_overlap(box, b[2]) for b in placed)):
                break
        placed.append((xa, ya, box))
    return placed


def _boxes_overlap(a, b):
    return a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3]


def _components_plotly(go, fig, marks, x_range, y_range, down):
    """Component labels (annotations, placed by :func:`label_boxes`) and their "vanishes" (×) and "falls below the
    colour range" (○) markers."""
    for m, (xa, ya, _) in zip(marks, label_boxes(marks, x_range, y_range, down)):
        fig.add_annotation(x=float(m["at"][0]), y=float(m["at"][1]), text=f"<b>{m['text']}</b>", showarrow=False,
                           xanchor=xa, yanchor=ya, xshift=3 if xa == "left" else -3,
                           yshift=3 if ya == "bottom" else -3, font=dict(color="white", size=12), row=1, col=1)
    for key, name, symbol in (("end", "component vanishes", "x-thin"),
                              ("fade", "falls below the colour range", "circle-open")):
        pts = [(m[key], m["text"]) for m in marks if m[key] is not None]
        if pts:
            fig.add_trace(go.Scatter(x=[p[0][0] for p in pts], y=[p[0][1] for p in pts], mode="markers", name=name,
                                     text=[p[1] for p in pts],
                                     marker=dict(symbol=symbol, size=11, color="white", line=dict(width=2,
                                                                                                  color="white")),
                                     hovertemplate="%{text}: " + name + "<br>%{x:.0f} rpm, %{y:.1f} Hz"
                                     "<extra></extra>"), 1, 1)


#: the RSR panel's traces have the panel's own legend, at its top, above the data (:func:`_rsr_headroom`)
RSR_LEGEND = dict(legend="legend2")
#: the height of the RSR panel of a page [px] and of one legend entry [px], for :func:`_rsr_headroom`
HTML_PANEL_PX, HTML_LEGEND_ENTRY_PX = 530.0, 19.0


def _rsr_headroom(values, n_entries):
    """RSR axis range [-] of a page whose top leaves room for the panel's legend of ``n_entries`` entries
    (:data:`HTML_PANEL_PX`, :data:`HTML_LEGEND_ENTRY_PX`), so that the legend covers no data."""
    v = np.concatenate([np.ravel(np.asarray(a, dtype=float)) for a in values])
    v = v[np.isfinite(v)]
    lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)
    span = max(hi - lo, 1e-3)
    frac = min(0.6, (n_entries * HTML_LEGEND_ENTRY_PX + 20.0) / HTML_PANEL_PX)
    return [lo - 0.03 * span, hi + span * frac / (1.0 - frac) + 0.03 * span]


def _rsr_plotly(go, fig, run, linear, num):
    """The ring-speed ratio panel of :func:`composite_plotly` (the content of :func:`_rsr_panel`; the run's
    samples thinned to about a screen's width, :data:`HTML_MAX_COLUMNS`)."""
    rr = run.ring_speed_ratio
    kind = "run-down" if run.speed_rpm[-1] < run.speed_rpm[0] else "run-up"
    step = max(1, run.speed_rpm.size // HTML_MAX_COLUMNS)
    for j, name in enumerate(_bearing_names(run)):
        fig.add_trace(go.Scatter(x=num(run.speed_rpm[::step]), y=num(rr[::step, j]), mode="lines",
                                 name=f"{kind}, {name}", line=dict(width=1, color=RUN_COLORS[j % len(RUN_COLORS)]),
                                 **RSR_LEGEND), 1, 2)
    if linear is not None:
        speeds, by_method, bearing_names = linear
        dashes = {"F": "solid", "I": "dashdot", "J": "dash"}
        greys = ("black", "rgb(140,140,140)", "rgb(77,77,77)", "rgb(190,190,190)")
        for m, arr in by_method.items():
            for j, b in enumerate(bearing_names):
                fig.add_trace(go.Scatter(x=speeds, y=arr[:, j], mode="lines",
                                         name=f"method {m}{' (eq. 6)' if m == 'F' else ''}, {b}",
                                         line=dict(dash=dashes.get(m, "dot"), color=greys[j % len(greys)]),
                                         **RSR_LEGEND), 1, 2)
    rsr = [t.y for t in fig.data if t.legend == "legend2"]
    fig.update_xaxes(title_text=_speed_label(kind, "rpm"), row=1, col=2)
    fig.update_yaxes(title_text="RSR = ω_FR / ω_R [-]", range=_rsr_headroom(rsr, len(rsr)), row=1, col=2)
    fig.update_layout(legend2=dict(x=1.0, xanchor="right", y=1.0, yanchor="top", bgcolor="rgba(255,255,255,0.8)",
                                   font=dict(size=10)))


def waterfall_lines(sp, fmax_hz=None, amplitude="um", n_lines=40):
    """The spectra drawn in a waterfall: up to ``n_lines`` segments, evenly spread in speed order.

    Parameters
    ----------
    sp : SpectrogramResult
    fmax_hz : float, optional
        Upper frequency [Hz] (default :func:`content_fmax`).
    amplitude : {"um", "db_um"}
        Orbit amplitude (max of forward and backward) in µm, or in dB re 1 µm clipped at ``sp.db_range`` below
        the largest.
    n_lines : int
        Largest number of spectra.

    Returns
    -------
    freqs_hz : (f,) ndarray
    speeds_rpm : (m,) ndarray
        Increasing.
    z : (f, m) ndarray
        Amplitudes of the spectra in the unit of ``amplitude``.
    """
    fmax = fmax_hz or content_fmax(sp)
    sel = sp.freqs_hz <= fmax
    order = _speed_order(sp)
    pick = order[np.unique(np.linspace(0, order.size - 1, min(n_lines, order.size)).round().astype(int))]
    z, vmin, _, _ = spectrogram_colour(sp, amplitude)
    z = np.maximum(z[sel][:, pick], vmin) if amplitude == "db_um" else z[sel][:, pick]
    return sp.freqs_hz[sel], sp.speeds_rpm[pick], z


def waterfall_figure(sp, fmax_hz=None, amplitude="um", orders=(1.0,), n_lines=40, title=None):
    """3-D waterfall (cascade): spectra of the orbit (frequency × amplitude) stacked along the rotor speed, with
    order lines k × f_rot on the floor.

    Parameters
    ----------
    sp : SpectrogramResult
    fmax_hz, amplitude, n_lines
        As for :func:`waterfall_lines`.
    orders : sequence of float
        Order lines (1X by default).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    f, s, z = waterfall_lines(sp, fmax_hz, amplitude, n_lines)
    fig = plt.figure(figsize=(10, 7))
    ax = fig.add_subplot(projection="3d")
    cmap = plt.get_cmap("viridis")
    base = float(z.min())
    for j in range(s.size):
        ax.plot(f, np.full(f.size, s[j] / 1e3), z[:, j], lw=0.8, color=cmap(j / max(1, s.size - 1)))
    for k in orders:
        fk = k * s / 60.0
        ok = fk <= f[-1]
        ax.plot(fk[ok], s[ok] / 1e3, np.full(ok.sum(), base), "--", color="C3" if k == 1 else "0.4", lw=1,
                label=f"{order_label(k)} (k × f_rot)")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(_speed_label(_kind(sp)).replace(" (run-down: time runs right to left)", ""))
    ax.set_zlabel("orbit amplitude [µm]" if amplitude == "um" else "orbit amplitude [dB re 1 µm]")
    ax.view_init(elev=28, azim=-60)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title or f"Waterfall, {_kind(sp)}, {readable(sp.node)} (orbit x + iy, max of forward/backward)",
                 fontsize=10)
    return fig


def waterfall_plotly(sp, fmax_hz=None, amplitude="um", orders=(1.0,), n_lines=40, title=None):
    """Interactive 3-D waterfall (plotly), as :func:`waterfall_figure`.

    Returns
    -------
    plotly.graph_objects.Figure
    """
    import plotly.graph_objects as go

    f, s, z = waterfall_lines(sp, fmax_hz, amplitude, n_lines)
    unit = "µm" if amplitude == "um" else "dB re 1 µm"
    fig = go.Figure()
    for j in range(s.size):
        fig.add_trace(go.Scatter3d(x=f, y=np.full(f.size, s[j]), z=z[:, j], mode="lines", showlegend=False,
                                   line=dict(width=2, color=z[:, j], colorscale="Viridis", cmin=z.min(),
                                             cmax=z.max()),
                                   hovertemplate=f"{s[j]:.0f} rpm<br>%{{x:.1f}} Hz<br>%{{z:.3g}} {unit}"
                                   "<extra></extra>"))
    for k in orders:
        fk = k * s / 60.0
        ok = fk <= f[-1]
        fig.add_trace(go.Scatter3d(x=fk[ok], y=s[ok], z=np.full(ok.sum(), float(z.min())), mode="lines",
                                   name=order_label(k), line=dict(dash="dash", color="red", width=3)))
    fig.update_layout(title=title or f"Waterfall, {_kind(sp)}, {readable(sp.node)}", height=HTML_HEIGHT_PX,
                      scene=dict(xaxis_title="frequency [Hz]", yaxis_title="rotor speed [rpm]",
                                 zaxis_title=f"orbit amplitude [{unit}]"))
    return fig


#: the plotly.js bundle that the HTML figures of a folder share (the name plotly's ``include_plotlyjs="directory"``
#: refers to, whatever the figure)
PLOTLY_JS = "plotly.min.js"
#: how interactive figures get plotly.js by default: from :data:`PLOTLY_JS` beside them (offline, small files)
HTML_PLOTLYJS = "directory"
#: how the interactive figures written now get plotly.js when the caller does not say (:func:`html_plotlyjs`)
_PLOTLYJS_NOW = contextvars.ContextVar("frb_html_plotlyjs", default=HTML_PLOTLYJS)
#: shown by a page whose plotly.js did not load (or that runs no scripts), instead of a blank page
HTML_FALLBACK = ("This interactive figure needs plotly.js: the file {js} beside this page (copy the results "
                 "folder as a whole), or write self-contained pages: frb ... --html self-contained.")


@contextlib.contextmanager
def html_plotlyjs(mode):
    """Within the block, interactive figures written without an explicit ``include_plotlyjs`` get plotly.js
    as ``mode`` says (``frb ... --html self-contained`` sets ``True``).

    Parameters
    ----------
    mode : {"directory", True}
        ``"directory"``: :data:`PLOTLY_JS` beside each page (the default); ``True``: embedded in each page.

    Yields
    ------
    None
    """
    token = _PLOTLYJS_NOW.set(mode)
    try:
        yield
    finally:
        _PLOTLYJS_NOW.reset(token)


def _with_fallback(html):
    """The page with a message that shows when plotly.js is missing or scripts do not run (:data:`HTML_FALLBACK`):
    a ``<noscript>`` and a note that a script after the figures hides once plotly.js has loaded."""
    text = HTML_FALLBACK.format(js=PLOTLY_JS)
    style = "font:15px sans-serif;color:#8b0000;border:1px solid #8b0000;padding:8px;margin:8px"
    note = (f'<noscript><p style="{style}">{text}</p></noscript>'
            f'<p id="frb-no-plotly" style="{style}">{text}</p>')
    hide = ('<script>if (typeof Plotly !== "undefined") '
            '{document.getElementById("frb-no-plotly").style.display = "none";}</script>')
    head, sep, rest = html.partition("<body>")
    body, end, tail = rest.rpartition("</body>")
    return head + sep + note + body + hide + end + tail


def _plotlyjs_source():
    from plotly.offline import get_plotlyjs

    return get_plotlyjs()


def plotly_bundle(folder):
    """Make sure ``folder`` holds the installed plotly.js as :data:`PLOTLY_JS` (one copy per folder).

    The file is written when missing or when its header (which names the plotly.js version) differs from the installed
    one, so figures written by a newer plotly never load an older bundle; a current one is touched, so that it counts
    among the files of the run that uses it (:mod:`frbmodel.core.manifest` removes a previous run's files that the new
    run did not write). It is written to a temporary name first and then renamed, so a reader never sees half a file.

    Parameters
    ----------
    folder : str or Path
        The folder of the HTML figures (must exist).

    Returns
    -------
    Path
        The bundle.
    """
    import os
    from pathlib import Path

    path = Path(folder) / PLOTLY_JS
    source = _plotlyjs_source()
    head = source[:200].encode("utf-8")
    if path.exists():
        with open(path, "rb") as f:
            current = f.read(len(head)) == head
        if current:
            os.utime(path)  # used by this run: a results folder's manifest keeps it with the run's files
            return path
    tmp = path.with_name(f".{PLOTLY_JS}.{os.getpid()}.tmp")
    tmp.write_text(source, encoding="utf-8")
    os.replace(tmp, path)
    return path


def write_html(fig, path, include_plotlyjs=None):
    """Write an interactive (plotly) figure as an HTML file: small, and shown offline.

    Every interactive figure of the package is written here. By default (``"directory"``) the page loads plotly.js
    from :data:`PLOTLY_JS` in its own folder, written there once (:func:`plotly_bundle`, 4.8 MB) and shared by all
    figures of the folder: the figures open without a network and each file holds only its data. Copy or move the
    folder as a whole (or a figure together with :data:`PLOTLY_JS`), or write self-contained pages (``True``,
    ``frb ... --html self-contained``). A page whose plotly.js does not load shows :data:`HTML_FALLBACK` instead
    of staying blank.

    Parameters
    ----------
    fig : plotly.graph_objects.Figure or sequence of them
        The figure; several figures are written one below the other into one page (plotly.js loaded once).
    path : str or Path
        The HTML file (its folder must exist).
    include_plotlyjs : {"directory", True}, optional
        ``"directory"``: :data:`PLOTLY_JS` beside the file; ``True``: plotly.js embedded in the file (a
        self-contained file, 4.8 MB larger). Default: as :func:`html_plotlyjs` set it, else ``"directory"``.

    Returns
    -------
    Path
        The HTML file.
    """
    from pathlib import Path

    path = Path(path)
    mode = _PLOTLYJS_NOW.get() if include_plotlyjs is None else include_plotlyjs
    if mode not in ("directory", True):
        raise ValueError(f"include_plotlyjs = {mode!r} is invalid: valid 'directory', True")
    if mode == "directory":
        plotly_bundle(path.parent)
    figs = list(fig) if isinstance(fig, (list, tuple)) else [fig]
    config = {"responsive": True}
    divs = [f.to_html(full_html=False, include_plotlyjs=mode if k == 0 else False, config=config)
            for k, f in enumerate(figs)]
    page = ("<html><head><meta charset='utf-8'><meta name='viewport' content='width=device-width'></head><body>"
            + "\n".join(divs) + "</body></html>")
    path.write_text(_with_fallback(page), encoding="utf-8")
    return path


def system_run_figure(run, signals=None, title=None, orbit_windows_s=0.01):
    """A run of the turbocharger FMU in a system (e.g. ``frb cosim build/engine_turbocharger.ssp``): rotor speed
    and the drive torque the system passed, the bearings' power loss, and the turbine wheel's orbit over the last
    ``orbit_windows_s`` [s] of the first and second half of the run.

    Parameters
    ----------
    run : RunupResult
        The turbocharger FMU's record (its ``record_folder``).
    signals : pandas.DataFrame, optional
        The master's ``signals.csv`` (time and connected values at the communication points).
    title : str, optional
    orbit_windows_s : float
        Length of each orbit window [s].

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    t = run.time
    ax = axes[0]
    ax.plot(t, run.speed_rpm / 1e3, color="k", lw=1.4, label="rotor speed")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("rotor speed [krpm]")
    torque = [c for c in (signals.columns if signals is not None else []) if "drive_torque" in c]
    if torque:
        tw = ax.twinx()
        tw.plot(signals["time [s]"], signals[torque[0]], color="tab:red", lw=0.6, alpha=0.7)
        tw.set_ylabel(f"{torque[0]} (at the communication points)", color="tab:red")
    ax.set_title("speed and drive torque")
    ax = axes[1]
    for name, p in run.power_loss.items():
        ax.plot(t, p, lw=0.8, label=f"{name} bearing")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("power loss [W]")
    ax.legend(frameon=False)
    ax.set_title("bearing power loss (both films)")
    ax = axes[2]
    disc = "turbine_wheel" if "turbine_wheel" in run.displacement else next(iter(run.displacement))
    xy = run.displacement[disc] * 1e6
    for end, style in ((t[-1] / 2, "tab:blue"), (t[-1], "tab:orange")):
        sel = (t > end - orbit_windows_s) & (t <= end)
        rpm = float(np.interp(end, t, run.speed_rpm))
        ax.plot(xy[sel, 0], xy[sel, 1], color=style, lw=0.8, label=f"{end - orbit_windows_s:.3g}-{end:.3g} s, "
                f"{rpm / 1e3:.0f} krpm")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{readable(disc)} x [µm]")
    ax.set_ylabel(f"{readable(disc)} y [µm]")
    ax.legend(frameon=False, fontsize=8)
    ax.set_title("orbit (relative to the housing)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
