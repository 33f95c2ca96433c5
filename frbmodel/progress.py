"""The one progress protocol of frbmodel: ``progress: bool`` in the API (off by default, on in the CLI), shown as
tqdm bars on stderr; messages go through :func:`note` so they do not break a bar.

>>> with simulation_bar(1.0, "run-up", enabled=False) as bar:
...     bar.update(0.5)
"""
from __future__ import annotations


def simulation_bar(total_s, desc, enabled):
    """A tqdm bar over simulated time [s] (postfix: e.g. the rotor speed); a no-op bar when not ``enabled``."""
    from tqdm.auto import tqdm

    return tqdm(total=float(total_s), disable=not enabled, desc=desc, leave=False,
                bar_format="{desc}: {n:.4f}/{total:g} s simulated |{bar}| {elapsed}<{remaining} {postfix}")


def counter_bar(total, desc, enabled, unit="item"):
    """A tqdm bar over ``total`` items (speeds, cases, ...)."""
    from tqdm.auto import tqdm

    return tqdm(total=int(total), disable=not enabled, desc=desc, unit=unit, leave=False)


def note(message, enabled=True):
    """Print a status line on stderr without breaking an active bar."""
    if enabled:
        from tqdm.auto import tqdm

        tqdm.write(str(message))
