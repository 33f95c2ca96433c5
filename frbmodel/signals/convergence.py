"""Is a reported onset a property of the model or of the integration error? Compare the spectral components of a
run with those of the same run at tightened tolerances (``frb runup --check-convergence``).

A component that grows out of the equilibrium (or out of a physical excitation such as unbalance) has an onset
that converges with the tolerances. A component born inside a developed whirl often grows from the integration
error itself: its onset moves when the tolerances change, and it is reported as *seeded by round-off*.

>>> from frbmodel.signals.tracking import Component
>>> import numpy as np
>>> a = Component("sub1", np.array([2e3, 3e3]), np.array([20.0, 30.0]), np.array([1e-6, 2e-6]), "forward")
>>> a.onset_interp_rpm = 2000.0
>>> b = Component("sub1", np.array([2e3, 3e3]), np.array([20.0, 30.0]), np.array([1e-6, 2e-6]), "forward")
>>> b.onset_interp_rpm = 2010.0
>>> convergence_table([a], [b])[["component", "onset moved [%]", "converged"]].to_dict("records")
[{'component': 'sub1', 'onset moved [%]': 0.5, 'converged': True}]
"""
from __future__ import annotations

import math

import numpy as np

#: an onset or onset frequency that moves by more than this (relative) under tightened tolerances is not converged
CONVERGED_REL = 0.01
#: components of two runs are the same if their first-detection f/f_rot and onset speed agree within this (log)
MATCH_LOG_TOL = 0.3


def _ratio(c):
    return float(c.freqs_hz[0] / (c.speeds_rpm[0] / 60.0))


def _onset(c):
    s = c.onset_rpm
    return s if math.isfinite(s) else float(c.speeds_rpm[0])


def match_components(ref, tight):
    """Pair each sub-synchronous component of ``ref`` with the same-direction component of ``tight`` that is closest
    in onset speed and first-detection frequency ratio (log distance, at most :data:`MATCH_LOG_TOL`); each component
    of ``tight`` is used once.

    Parameters
    ----------
    ref : list of Component
        Components of the run (``SpectrogramResult.components()``); only the ``"sub..."`` ones are paired.
    tight : list of Component
        Components of the same run at tightened tolerances.

    Returns
    -------
    list of tuple
        One ``(ref component, tight component or None)`` per sub-synchronous component of ``ref``, in its order.

    Examples
    --------
    >>> from frbmodel.signals.tracking import Component
    >>> def sub(onset_rpm, f_hz, direction="forward"):
    ...     c = Component("sub1", np.array([onset_rpm]), np.array([f_hz]), np.array([1e-6]), direction)
    ...     c.onset_interp_rpm = onset_rpm
    ...     return c
    >>> a = sub(60e3, 400.0)
    >>> [b is not None for _, b in match_components([a], [sub(61e3, 405.0)])]
    [True]
    >>> [b is not None for _, b in match_components([a], [sub(61e3, 405.0, "backward")])]
    [False]
    """
    cands = [c for c in tight if c.label.startswith("sub")]
    pairs = []
    for a in (c for c in ref if c.label.startswith("sub")):
        best, dist = None, MATCH_LOG_TOL
        for b in cands:
            if b.direction != a.direction:
                continue
            d = abs(math.log(_onset(b) / _onset(a))) + abs(math.log(_ratio(b) / _ratio(a)))
            if d <= dist:
                best, dist = b, d
        if best is not None:
            cands.remove(best)
        pairs.append((a, best))
    return pairs


def convergence_table(ref, tight, rel=CONVERGED_REL):
    """One row per sub-synchronous component of ``ref``: its onset speed and frequency, the same in the run at
    tightened tolerances, how far they moved [%], and ``converged`` (both moved by less than ``rel``; a component
    present from the start converges if it is present from the start in both runs).

    Parameters
    ----------
    ref, tight : list of Component
        ``SpectrogramResult.components()`` of the run and of its rerun at tightened tolerances.
    rel : float
        Relative change [-] above which an onset is reported as seeded by round-off (default 1 %).

    Returns
    -------
    pandas.DataFrame
        Columns ``component``, ``whirl direction``, ``onset [rpm]``, ``onset tightened [rpm]``, ``f at onset [Hz]``,
        ``f at onset tightened [Hz]``, ``onset moved [%]``, ``f moved [%]``, ``converged`` and ``note``.

    Examples
    --------
    See the module docstring.
    """
    import pandas as pd

    rows = []
    for a, b in match_components(ref, tight):
        row = {"component": a.label, "whirl direction": a.direction, "onset [rpm]": a.onset_rpm,
               "onset tightened [rpm]": b.onset_rpm if b else math.nan,
               "f at onset [Hz]": a.onset_hz, "f at onset tightened [Hz]": b.onset_hz if b else math.nan}
        if b is None:
            row.update({"onset moved [%]": math.nan, "f moved [%]": math.nan, "converged": False,
                        "note": "not found in the run at tightened tolerances: seeded by round-off"})
        elif not math.isfinite(a.onset_rpm) or not math.isfinite(b.onset_rpm):
            same = not math.isfinite(a.onset_rpm) and not math.isfinite(b.onset_rpm)
            row.update({"onset moved [%]": math.nan, "f moved [%]": math.nan, "converged": same,
                        "note": "present from the start in both runs" if same else "onset found in one run only"})
        else:
            ds = 100 * (b.onset_rpm / a.onset_rpm - 1)
            df = 100 * (b.onset_hz / a.onset_hz - 1)
            ok = abs(ds) < 100 * rel and abs(df) < 100 * rel
            row.update({"onset moved [%]": round(ds, 3), "f moved [%]": round(df, 3), "converged": bool(ok),
                        "note": "" if ok else f"seeded by round-off: moves by {ds:+.1f} % / {df:+.1f} % when the "
                                              "tolerances are tightened tenfold"})
        rows.append(row)
    return pd.DataFrame(rows)


def unconverged_summary(table):
    """One line naming the components whose onset is not converged (or saying that all are).

    Parameters
    ----------
    table : pandas.DataFrame
        A :func:`convergence_table`.

    Returns
    -------
    str

    Examples
    --------
    >>> import pandas as pd
    >>> unconverged_summary(pd.DataFrame({"component": ["sub1"], "onset moved [%]": [4.0], "converged": [False],
    ...                                   "note": [""]}))
    'onsets seeded by round-off (not a property of the model): sub1 (+4.0 %)'
    """
    bad = table[~table["converged"]] if len(table) else table
    if not len(bad):
        return "every reported onset is converged (moves < 1 % when the tolerances are tightened tenfold)"
    items = ", ".join(f"{r['component']} ({r['onset moved [%]']:+.1f} %)" if np.isfinite(r["onset moved [%]"])
                      else f"{r['component']} ({r['note']})" for _, r in bad.iterrows())
    return f"onsets seeded by round-off (not a property of the model): {items}"
