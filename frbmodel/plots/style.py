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


def log_axis(title):
    """A plotly log axis with one labelled tick per decade (1e-3, 0.01, ...), not plotly's digit ticks.

    Parameters
    ----------
    title : str

    Returns
    -------
    dict
        Keyword arguments of ``fig.update_yaxes`` / ``update_xaxes``.
    """
    return dict(type="log", dtick=1, exponentformat="power", showexponent="all", minor=dict(ticks="inside",
                showgrid=True), title_text=title)
