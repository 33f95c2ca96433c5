"""Figure of the bearing losses over speed (the table of :func:`frbmodel.linear.losses.bearing_losses`, optionally a
run's recorded power loss)."""
from __future__ import annotations

__all__ = ["plot_bearing_losses"]


def plot_bearing_losses(table, run=None, title=None):
    """Power loss vs rotor speed per bearing: the equilibrium curve of :func:`bearing_losses` and, optionally,
    the recorded power loss of a run-up or co-simulation (:class:`~frbmodel.nonlinear.recorder.RunupResult`).

    Parameters
    ----------
    table : pandas.DataFrame
        A :func:`bearing_losses` table (columns ``bearing``, ``speed [rpm]``, ``power loss [W]``, ``method``).
    run : RunupResult, optional
        A run whose ``power_loss[bearing]`` [W] is drawn over its ``speed_rpm`` [rpm]; bearings it does not
        record are skipped.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (the backend is left to the caller; matplotlib is imported only here).
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    for k, (name, grp) in enumerate(table.groupby("bearing", sort=False)):
        color = f"C{k}"
        method = grp["method"].iloc[0] if "method" in grp else "?"
        ax.plot(grp["speed [rpm]"] / 1e3, grp["power loss [W]"], "o-", color=color, ms=3, lw=1.5,
                label=f"{name}: method-{method} static equilibrium")
        if run is not None and name in run.power_loss:
            ax.plot(run.speed_rpm / 1e3, run.power_loss[name], color=color, lw=0.6, alpha=0.6,
                    label=f"{name}: {run.meta.get('profile', 'run-up')}")
    ax.set_xlabel("rotor speed [krpm]")
    ax.set_ylabel("bearing power loss [W]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig
