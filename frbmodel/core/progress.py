"""The one progress protocol of frbmodel: ``progress: bool`` in the API (off by default, on in the CLI), shown as
tqdm bars on stderr; messages go through :func:`note` so they do not break a bar.

>>> with simulation_bar(1.0, "run-up", enabled=False) as bar:
...     bar.update(0.5)
"""
from __future__ import annotations

import warnings


def simulation_bar(total_s, desc, enabled):
    """A tqdm bar over simulated time [s] (postfix: e.g. the rotor speed); a no-op bar when not ``enabled``.

    Parameters
    ----------
    total_s : float
        Simulated time the bar runs to [s].
    desc : str
        Label in front of the bar (e.g. ``"run-up"``).
    enabled : bool
        Show the bar; when False the bar is disabled and prints nothing.

    Returns
    -------
    tqdm.tqdm
        The bar; advance it with ``bar.update(dt_s)`` and close it (or use it as a context manager).

    Examples
    --------
    >>> with simulation_bar(0.5, "run-up", enabled=False) as bar:
    ...     bar.update(0.25)
    ...     print(bar.disable)
    True
    """
    from tqdm.auto import tqdm

    return tqdm(total=float(total_s), disable=not enabled, desc=desc, leave=False,
                bar_format="{desc}: {n:.4f}/{total:g} s simulated |{bar}| {elapsed}<{remaining} {postfix}")


def counter_bar(total, desc, enabled, unit="item"):
    """A tqdm bar over ``total`` items (speeds, cases, ...).

    Parameters
    ----------
    total : int
        Number of items.
    desc : str
        Label in front of the bar.
    enabled : bool
        Show the bar; when False the bar is disabled and prints nothing.
    unit : str
        Name of one item, shown in the rate (e.g. ``"speed"``, ``"case"``).

    Returns
    -------
    tqdm.tqdm
        The bar; advance it with ``bar.update()``.

    Examples
    --------
    >>> with counter_bar(3, "cases", enabled=False, unit="case") as bar:
    ...     for _ in range(3):
    ...         _ = bar.update()
    ...     print(bar.total, bar.disable)
    3 True
    """
    from tqdm.auto import tqdm

    return tqdm(total=int(total), disable=not enabled, desc=desc, unit=unit, leave=False)


def note(message, enabled=True):
    """Print a status line on stderr without breaking an active bar.

    Parameters
    ----------
    message : object
        The line to print (converted with ``str``).
    enabled : bool
        Print only if True, so callers can pass their ``progress`` flag through.

    Examples
    --------
    >>> note("not shown", enabled=False)
    """
    if enabled:
        from tqdm.auto import tqdm

        tqdm.write(str(message))


def progress_enabled(progress) -> bool:
    """``bool(progress)`` for a ``progress: bool`` argument, with a DeprecationWarning for the old callbacks.

    Parameters
    ----------
    progress : bool
        (A callable is accepted for one release and shows the bar; it is no longer called.)

    Returns
    -------
    bool

    Examples
    --------
    >>> progress_enabled(False), progress_enabled(True)
    (False, True)
    """
    if callable(progress) and not isinstance(progress, bool):
        warnings.warn("progress callbacks are no longer called: pass progress=True for a progress bar (tqdm)",
                      DeprecationWarning, stacklevel=3)
    return bool(progress)
