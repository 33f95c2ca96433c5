"""Figures of an unbalance response (:class:`frbmodel.linear.unbalance.UnbalanceResponse`): Bode plot, film orbits
over clearance and polar plot, as PNG (matplotlib) and interactive page (plotly). They take the result and draw it;
nothing here computes physics. (Moved here from :mod:`frbmodel.linear.unbalance`, which re-exports the names.)
"""
from __future__ import annotations

import numpy as np

from .style import html_layout, log_axis, log_ticks_mpl, readable

#: an x response whose imaginary parts are all below this fraction of its largest amplitude is real (an undamped
#: method: every phase is 0° or 180°), and its polar plot would be two lines along 0° and 180°
REAL_RESPONSE_RTOL = 1e-9
#: what the polar panel says instead for a real (undamped) response
REAL_RESPONSE_NOTE = ("no polar plot: method {m} is undamped, its response is real\n(phase 0° or 180°: the phase "
                      "plot shows it)")


#: line styles of the results overlaid by :func:`bode_figure` (one per result)
RESULT_STYLES = ("-", "--", ":", "-.")
#: phase curves are broken where the phase jumps by this much or more between two speeds [deg]
PHASE_BREAK_DEG = 179.0
#: the polar plot's radius is clipped at this multiple of the median amplitude (undamped peaks are unbounded)
POLAR_CLIP = 20.0
#: a speed label of the polar plot is left out within this fraction of the radius limit of a label drawn before
POLAR_LABEL_GAP = 0.12


def default_films(ur):
    """The films of ``ur`` whose relative orbit is defined and not identically zero (method C's inner film is).

    Parameters
    ----------
    ur : UnbalanceResponse

    Returns
    -------
    list of str
    """
    out = []
    for f in ur.film_names:
        c = ur.clearance_fraction(f)
        if np.isfinite(c).all() and np.any(c > 0):
            out.append(f)
    return out


def _disc_names(ur):
    return [d["name"] for d in ur.layout["discs"]]


def phase_curve(ur, name):
    """Speeds [krpm] and x phase [deg] of ``name`` for plotting: the phase in [−270°, 90°) (so that a phase of
    ±180° is drawn at one place, −180°), NaN inserted where it jumps by :data:`PHASE_BREAK_DEG` or more (the
    undamped methods jump by exactly 180° at each resonance and anti-resonance; the wrap point lies outside most
    damped curves).

    Parameters
    ----------
    ur : UnbalanceResponse
    name : str

    Returns
    -------
    x_krpm, phase_deg : ndarray

    Examples
    --------
    >>> import frbmodel as frb
    >>> ur = frb.unbalance_response(frb.turbocharger(), "A", [5e3, 6e3, 8e3, 9e3], critical=False)
    >>> x, ph = phase_curve(ur, "turbine_wheel")      # through the 6.9 krpm resonance: 0° to -180°, broken
    >>> x.tolist(), [round(float(p)) for p in ph if p == p]
    ([5.0, 6.0, nan, 8.0, 9.0], [0, 0, -180, -180])
    """
    x = ur.speeds_rpm / 1e3
    ph = (np.degrees(ur.phase(name)) + 270.0) % 360.0 - 270.0
    cut = np.flatnonzero(np.abs(np.diff(ph)) >= PHASE_BREAK_DEG) + 1
    return np.insert(x, cut, np.nan), np.insert(ph, cut, np.nan)


def _bode_lines(ax_amp, ax_phase, ur, names, style="-", prefix=""):
    """Semi-major axis [µm] (log) and x phase [deg] (:func:`phase_curve`) of each location vs speed [krpm];
    returns the amplitudes drawn [µm]."""
    x = ur.speeds_rpm / 1e3
    amps = []
    for c, name in enumerate(names):
        color = f"C{c}"
        amps.append(ur.major_axis(name) * 1e6)
        ax_amp.semilogy(x, amps[-1], ls=style, color=color, label=f"{prefix}{readable(name)}")
        ax_phase.plot(*phase_curve(ur, name), ls=style, color=color)
    ax_phase.set_yticks([-270, -180, -90, 0, 90])
    return amps


def is_real_response(ur, names):
    """Whether the x responses of ``names`` are real (:data:`REAL_RESPONSE_RTOL`): an undamped method, whose polar
    plot would only show two lines along 0° and 180°.

    Parameters
    ----------
    ur : UnbalanceResponse
    names : sequence of str

    Returns
    -------
    bool
    """
    X = np.concatenate([ur.orbit(n)[0] for n in names])
    X = X[np.isfinite(X)]
    return bool(X.size) and bool(np.all(np.abs(X.imag) <= REAL_RESPONSE_RTOL * np.abs(X).max()))


def _mark_crossings(ax, ur):
    """Dotted vertical lines at the 1X crossings (forward: darker)."""
    if ur.critical is None:
        return
    for r in ur.critical_speeds().itertuples(index=False):
        if r.source == "1X crossing":
            ax.axvline(r[1] / 1e3, color="0.35" if r.precession == "forward" else "0.75", ls=":", lw=0.9)


def _polar_rmax(ur, names):
    """Radius limit of the polar plot [µm] (at most :data:`POLAR_CLIP` × the median amplitude) and whether it
    clips."""
    r_all = np.concatenate([np.abs(ur.orbit(n)[0]) for n in names]) * 1e6
    r_all = r_all[np.isfinite(r_all)]
    if not r_all.size:
        return 1.0, False
    rmax = min(r_all.max(), POLAR_CLIP * np.median(r_all)) * 1.05
    return rmax, bool(r_all.max() > rmax)


def _polar(ax, ur, names):
    """Polar plot of the x response: radius |X| [µm], angle φ (speeds marked in krpm along the first curve)."""
    rmax, clipped = _polar_rmax(ur, names)
    for c, name in enumerate(names):
        X = ur.orbit(name)[0]
        ax.plot(np.angle(X), np.abs(X) * 1e6, color=f"C{c}", lw=1.2)
    X = ur.orbit(names[0])[0]
    placed = []
    for k in np.linspace(0, X.size - 1, min(6, X.size)).astype(int):
        z = X[k] * 1e6
        if abs(z) <= rmax and all(abs(z - p) > POLAR_LABEL_GAP * rmax for p in placed):  # (no label on another)
            ax.annotate(f"{ur.speeds_rpm[k] / 1e3:.0f}", (np.angle(z), abs(z)), fontsize=7)
            placed.append(z)
    ax.set_rlim(0, rmax)
    ax.set_title(f"polar: x amplitude [µm]{' (clipped)' if clipped else ''}, phase; labels krpm", fontsize=9)


def response_figure(ur, names=None, films=None, title=None):
    """Bode plot (semi-major axis [µm], log; x phase [deg]), film orbits / clearance, and polar plot.

    Parameters
    ----------
    ur : UnbalanceResponse
    names : sequence of str, optional
        Locations (default: the discs).
    films : sequence of str, optional
        Films of the clearance panel (default: :func:`default_films`).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    names = list(names or _disc_names(ur))
    films = default_films(ur) if films is None else list(films)
    rows = 3 if films else 2
    fig = plt.figure(figsize=(12.5, 2.9 * rows + 0.8))
    gs = fig.add_gridspec(rows, 2, width_ratios=(1.7, 1.0))
    ax_a = fig.add_subplot(gs[0, 0])
    ax_p = fig.add_subplot(gs[1, 0], sharex=ax_a)
    log_ticks_mpl(ax_a, _bode_lines(ax_a, ax_p, ur, names))
    axes = [ax_a, ax_p]
    if films:
        ax_f = fig.add_subplot(gs[2, 0], sharex=ax_a)
        for k, f in enumerate(films):
            ax_f.semilogy(ur.speeds_rpm / 1e3, ur.clearance_fraction(f), color=f"C{k + len(names)}", label=f)
        log_ticks_mpl(ax_f, [ur.clearance_fraction(f) for f in films])
        ax_f.set_ylabel("film orbit semi-major\naxis / clearance [-]")
        ax_f.legend(fontsize=8, ncol=2)
        axes.append(ax_f)
    for ax in axes:
        _mark_crossings(ax, ur)
        ax.grid(True, which="both", alpha=0.3)
    ax_a.set_ylabel("semi-major axis [µm]")
    ax_a.legend(fontsize=8)
    ax_p.set_ylabel("phase of x [deg]")
    axes[-1].set_xlabel("rotor speed [krpm] (dotted: 1X crossings of the Campbell branches)")
    if is_real_response(ur, names):
        ax_n = fig.add_subplot(gs[:, 1])
        ax_n.axis("off")
        ax_n.text(0.5, 0.5, REAL_RESPONSE_NOTE.format(m=ur.method), ha="center", va="center", fontsize=10,
                  transform=ax_n.transAxes, wrap=True)
    else:
        _polar(fig.add_subplot(gs[:, 1], projection="polar"), ur, names)
    unb = ", ".join(f"{readable(u['disc'])} {u['m e [kg m]'] * 1e6:g} g mm at {u['phase [rad]']:g} rad"
                    for u in ur.unbalance)
    fig.suptitle(title or f"Unbalance response, method {ur.method} ({unb})", fontsize=11)
    fig.tight_layout()
    return fig


def bode_figure(results, names=None, title=None):
    """Bode plots of several unbalance responses (e.g. methods A and J) in one figure.

    Parameters
    ----------
    results : sequence of UnbalanceResponse
        Drawn with the line styles :data:`RESULT_STYLES`, colours per location.
    names : sequence of str, optional
        Locations (default: the discs of the first result).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> rs = [frb.unbalance_response(tc, m, [20e3, 40e3], critical=False) for m in "AJ"]
    >>> len(bode_figure(rs).axes)
    2
    """
    import matplotlib.pyplot as plt

    names = list(names or _disc_names(results[0]))
    fig, (ax_a, ax_p) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    amps = []
    for k, ur in enumerate(results):
        amps += _bode_lines(ax_a, ax_p, ur, names, RESULT_STYLES[k % len(RESULT_STYLES)], prefix=f"{ur.method}: ")
    log_ticks_mpl(ax_a, amps)
    for ax in (ax_a, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    ax_a.set_ylabel("semi-major axis [µm]")
    ax_a.legend(fontsize=8, ncol=len(results))
    ax_p.set_ylabel("phase of x [deg]")
    ax_p.set_xlabel("rotor speed [krpm]")
    unb = ", ".join(f"{readable(u['disc'])} {u['m e [kg m]'] * 1e6:g} g mm" for u in results[0].unbalance)
    fig.suptitle(title or f"Unbalance response, methods {', '.join(r.method for r in results)} ({unb})")
    fig.tight_layout()
    return fig


def response_plotly(ur, names=None, films=None):
    """Interactive version of :func:`response_figure` (plotly): log axes labelled by decades, polar radius in µm
    (no polar plot for a real, undamped response: a note says why), at most a screen tall.

    Parameters
    ----------
    ur : UnbalanceResponse
    names, films : sequence of str, optional

    Returns
    -------
    plotly.graph_objects.Figure
    """
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    names = list(names or _disc_names(ur))
    films = default_films(ur) if films is None else list(films)
    rows = 3 if films else 2
    real = is_real_response(ur, names)
    rmax, clipped = _polar_rmax(ur, names)
    if real:
        fig = make_subplots(rows=rows, cols=1, shared_xaxes=True, vertical_spacing=0.06)
    else:
        specs = [[{}, {"type": "polar", "rowspan": rows}]] + [[{}, None] for _ in range(rows - 1)]
        polar = f"polar: x amplitude [µm]{' (clipped)' if clipped else ''}, phase [deg]"
        fig = make_subplots(rows=rows, cols=2, specs=specs, column_widths=[0.62, 0.38], shared_xaxes=True,
                            vertical_spacing=0.06, subplot_titles=("", polar))
    x = ur.speeds_rpm / 1e3
    amps = []
    for c, name in enumerate(names):
        X = ur.orbit(name)[0]
        amp, (xp, ph) = ur.major_axis(name) * 1e6, phase_curve(ur, name)
        amps.append(amp)
        color, label = f"hsl({(c * 137) % 360}, 65%, 40%)", readable(name)
        fig.add_trace(go.Scatter(x=x, y=amp, name=label, legendgroup=name, line={"color": color},
                                 hovertemplate="%{x:.1f} krpm: %{y:.4g} µm<extra>" + label + "</extra>"), 1, 1)
        fig.add_trace(go.Scatter(x=xp, y=ph, name=label, legendgroup=name, showlegend=False, line={"color": color},
                                 hovertemplate="%{x:.1f} krpm: %{y:.1f} deg<extra>" + label + "</extra>"), 2, 1)
        if not real:
            fig.add_trace(go.Scatterpolar(r=np.abs(X) * 1e6, theta=np.degrees(np.angle(X)), name=label,
                                          legendgroup=name, showlegend=False, line={"color": color},
                                          text=[f"{s:.1f} krpm" for s in x],
                                          hovertemplate="%{text}: %{r:.4g} µm, %{theta:.1f} deg<extra>" + label
                                                        + "</extra>"), 1, 2)
    for f in films:
        fig.add_trace(go.Scatter(x=x, y=ur.clearance_fraction(f), name=f,
                                 hovertemplate="%{x:.1f} krpm: %{y:.4g}<extra>" + f + "</extra>"), 3, 1)
    fig.update_yaxes(**log_axis("semi-major axis [µm]", amps), row=1, col=1)
    fig.update_yaxes(title_text="phase of x [deg]", tickvals=[-270, -180, -90, 0, 90], row=2, col=1)
    if films:
        fig.update_yaxes(**log_axis("film orbit / clearance [-]", [ur.clearance_fraction(f) for f in films]),
                         row=3, col=1)
    fig.update_xaxes(title_text="rotor speed [krpm]", row=rows, col=1)
    unb = ", ".join(f"{readable(u['disc'])} {u['m e [kg m]'] * 1e6:g} g mm" for u in ur.unbalance)
    note = f"<br><sup>{REAL_RESPONSE_NOTE.format(m=ur.method)}</sup>".replace("\n", " ") if real else ""
    fig.update_layout(title=f"Unbalance response, method {ur.method} ({unb}){note}", **html_layout(legend_below=False))
    if not real:
        fig.update_polars(radialaxis=dict(range=[0, rmax]), angularaxis=dict(ticksuffix="°"))
    return fig
