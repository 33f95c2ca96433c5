"""What the figures of the package share: readable names, the modal-damping colours, the size of interactive pages
and their log axes.

Nothing here draws or computes physics; matplotlib and plotly are imported only where a function needs them.
"""
from __future__ import annotations

import numpy as np

#: colour range of modal damping, as in the paper's figures
D_MIN, D_MAX = -1.0, 0.7
#: the damping colours [(D [-], RGB 0..255)]: unstable modes (D < 0) dark red → orange, so that every unstable
#: mode is clearly coloured (D = −0.3 is a strong red, not the near-white of a diverging map centred at 0); stable
#: ones light → dark blue. The colour jumps at D = 0.
DAMPING_STOPS = ((D_MIN, (103, 0, 31)), (0.0, (244, 109, 67)), (0.0, (198, 219, 239)), (D_MAX, (8, 48, 107)))
#: the largest height of an interactive page's figure [px]: it fits a laptop screen without scrolling
HTML_HEIGHT_PX = 760


def readable(name):
    """A name of the model (``"turbine_wheel"``) as a figure writes it (``"turbine wheel"``).

    Parameters
    ----------
    name : str

    Returns
    -------
    str

    Examples
    --------
    >>> readable("compressor_wheel")
    'compressor wheel'
    """
    return str(name).replace("_", " ")


def damping_rgb(d):
    """Colour of modal damping ``d`` (:data:`DAMPING_STOPS`, clipped to [:data:`D_MIN`, :data:`D_MAX`]).

    Parameters
    ----------
    d : float or ndarray
        Modal damping [-].

    Returns
    -------
    ndarray
        RGB in 0..1, shape ``d.shape + (3,)``.

    Examples
    --------
    >>> damping_rgb(-0.3).round(2).tolist()
    [0.79, 0.3, 0.22]
    """
    d = np.clip(np.asarray(d, dtype=float), D_MIN, D_MAX)
    (d0, c0), (dz, cn), (_, cp), (d1, c1) = DAMPING_STOPS
    neg = [np.interp(d, [d0, dz], [c0[i], cn[i]]) for i in range(3)]
    pos = [np.interp(d, [dz, d1], [cp[i], c1[i]]) for i in range(3)]
    return np.stack([np.where(d < 0.0, n, p) for n, p in zip(neg, pos)], axis=-1) / 255.0


def damping_cmap():
    """The damping colours as a matplotlib colormap over [:data:`D_MIN`, :data:`D_MAX`] (use with
    ``Normalize(D_MIN, D_MAX)``).

    Returns
    -------
    matplotlib.colors.ListedColormap
    """
    from matplotlib.colors import ListedColormap

    return ListedColormap(damping_rgb(np.linspace(D_MIN, D_MAX, 1024)), name="frb_damping")


def damping_colorscale():
    """The damping colours as a plotly colour scale (positions over [:data:`D_MIN`, :data:`D_MAX`]; use with
    ``cmin=D_MIN, cmax=D_MAX``).

    Returns
    -------
    list of [float, str]
    """
    return [[(d - D_MIN) / (D_MAX - D_MIN), "rgb({}, {}, {})".format(*c)] for d, c in DAMPING_STOPS]


def log_ticks(values):
    """Ticks of a log axis over the positive finite ``values``: the decades (1e-3, 0.01, 0.1, ...), with 2 and 5
    times them when fewer than two decades fall inside; labels as plain numbers (``"0.01"``, ``"20"``; powers of
    ten beyond 1e-4 … 1e5).

    Parameters
    ----------
    values : array_like
        The data of the axis.

    Returns
    -------
    ticks : list of float
    labels : list of str

    Examples
    --------
    >>> log_ticks([0.0012, 0.35])
    ([0.01, 0.1], ['0.01', '0.1'])
    >>> log_ticks([0.4, 3.7])
    ([0.5, 1.0, 2.0], ['0.5', '1', '2'])
    """
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v) & (v > 0)]
    if not v.size:
        return [], []
    lo, hi = float(v.min()), float(v.max())
    decades = range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
    ticks = [10.0 ** k for k in decades if lo <= 10.0 ** k <= hi]
    if len(ticks) < 2:
        ticks = [m * 10.0 ** k for k in decades for m in (1, 2, 5) if lo <= m * 10.0 ** k <= hi]
    ticks = [float(f"{t:.12g}") for t in ticks]
    return ticks, [f"{t:g}" if 1e-4 <= t < 1e5 else f"1e{int(round(np.log10(t)))}" for t in ticks]


def log_axis(title, values):
    """A plotly log axis labelled by :func:`log_ticks` (decades with plain numbers, not plotly's digit ticks
    "4 3 2 1 9 8 ...").

    Parameters
    ----------
    title : str
    values : array_like
        The data of the axis.

    Returns
    -------
    dict
        Keyword arguments of ``fig.update_yaxes`` / ``update_xaxes``.
    """
    ticks, labels = log_ticks(values)
    return dict(type="log", tickmode="array", tickvals=ticks, ticktext=labels, title_text=title)


def log_ticks_mpl(ax, values, axis="y"):
    """Label a matplotlib log axis as :func:`log_ticks` does (no minor labels).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    values : array_like
        The data of the axis.
    axis : {"x", "y"}
    """
    from matplotlib.ticker import FixedFormatter, FixedLocator, NullFormatter

    ticks, labels = log_ticks(values)
    target = ax.yaxis if axis == "y" else ax.xaxis
    target.set_major_locator(FixedLocator(ticks))
    target.set_major_formatter(FixedFormatter(labels))
    target.set_minor_formatter(NullFormatter())


def html_layout(legend_below=True, height=HTML_HEIGHT_PX):
    """Layout of an interactive page's figure: at most :data:`HTML_HEIGHT_PX` tall (a laptop screen), as wide as
    the window, the legend below the plot (clear of a colour bar's title and ticks) or right of it.

    Parameters
    ----------
    legend_below : bool
        Legend horizontal below the plot (else a column right of the plot, for figures without a colour bar).
    height : int
        Figure height [px] (at most :data:`HTML_HEIGHT_PX`).

    Returns
    -------
    dict
        Keyword arguments of ``fig.update_layout``.
    """
    legend = (dict(orientation="h", x=0.0, xanchor="left", y=-0.14, yanchor="top") if legend_below
              else dict(x=1.02, xanchor="left", y=1.0, yanchor="top"))
    return dict(height=min(int(height), HTML_HEIGHT_PX), autosize=True, legend=legend,
                margin=dict(l=70, r=30, t=80, b=150 if legend_below else 60))
