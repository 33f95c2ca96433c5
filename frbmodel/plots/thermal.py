"""Figures of the thermal model: the operating points over speed (the table of
:func:`frbmodel.linear.thermal.thermal_losses`: ring-speed ratio, film temperatures and power loss per bearing for each
supply temperature) and the whirl onset speeds versus the supply temperature (the tables of
:func:`frbmodel.studies.thermal.onsets_vs_supply`)."""
from __future__ import annotations

__all__ = ["plot_onsets_vs_supply", "plot_thermal_losses"]

#: the offset between K and °C [K]
_ZERO_C_K = 273.15


def plot_thermal_losses(table, title=None):
    """RSR [-], film temperatures [K] (°C on the right axis) and the bearing's power loss [W] versus rotor speed, one
    column per bearing, one colour per supply temperature; inner film solid, outer film dashed, supply dotted.

    Parameters
    ----------
    table : pandas.DataFrame
        A :func:`thermal_losses` table (columns ``bearing``, ``speed [rpm]``, ``supply temperature [K]``,
        ``RSR [-]``, ``inner film temperature [K]``, ``outer film temperature [K]``, ``power loss [W]``, ``oil``,
        ``supply pressure [Pa]``).
    title : str, optional
        Figure title (default: the oil and the supply pressure).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (the backend is left to the caller; matplotlib is imported only here).
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    bearings = list(dict.fromkeys(table["bearing"]))
    supplies = sorted(set(table["supply temperature [K]"]))
    fig, axes = plt.subplots(3, len(bearings), figsize=(5.2 * len(bearings), 9.0), sharex=True, squeeze=False)
    for j, name in enumerate(bearings):
        ax_rsr, ax_t, ax_p = axes[:, j]
        for k, t_s in enumerate(supplies):
            grp = table[(table["bearing"] == name) & (table["supply temperature [K]"] == t_s)].sort_values(
                "speed [rpm]")
            krpm, color = grp["speed [rpm]"] / 1e3, f"C{k}"
            ax_rsr.plot(krpm, grp["RSR [-]"], "-", color=color, lw=1.6)
            ax_t.plot(krpm, grp["inner film temperature [K]"], "-", color=color, lw=1.6)
            ax_t.plot(krpm, grp["outer film temperature [K]"], "--", color=color, lw=1.6)
            ax_t.axhline(t_s, color=color, ls=":", lw=1.0)
            ax_p.plot(krpm, grp["power loss [W]"], "-", color=color, lw=1.6)
        ax_rsr.set_title(f"{name} bearing")
        ax_rsr.set_ylabel("ring-speed ratio RSR [-]")
        ax_t.set_ylabel("film temperature [K]")
        celsius = ax_t.secondary_yaxis("right", functions=(lambda k: k - _ZERO_C_K, lambda c: c + _ZERO_C_K))
        celsius.set_ylabel("[°C]")
        ax_p.set_ylabel("power loss [W]")
        ax_p.set_xlabel("rotor speed [krpm]")
        for ax in (ax_rsr, ax_t, ax_p):
            ax.grid(True, alpha=0.3)
    supply = [Line2D([], [], color=f"C{k}", lw=1.6, label=f"supply {t:.2f} K ({t - _ZERO_C_K:.0f} °C)")
              for k, t in enumerate(supplies)]
    styles = [Line2D([], [], color="0.3", ls="-", label="inner film temperature; RSR; bearing power loss"),
              Line2D([], [], color="0.3", ls="--", label="outer film temperature"),
              Line2D([], [], color="0.3", ls=":", label="supply temperature")]
    fig.legend(handles=supply + styles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    if title is None:
        oil = table["oil"].iloc[0] if "oil" in table else "oil"
        title = f"Thermal operating point: {oil}, supply {table['supply pressure [Pa]'].iloc[0] / 1e5:g} bar (gauge)"
    fig.suptitle(title)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def plot_onsets_vs_supply(films, modes=None, title=None, runups=None):
    """Whirl onset speed [krpm] versus oil supply temperature [K] (°C on the top axis): each film's exact onset with
    the thermal model (inner films solid, outer dashed, one colour per bearing), its constant-viscosity onset
    (dotted) and, if given, the speeds where the Campbell diagram's modes lose stability inside its grid (crosses).

    Parameters
    ----------
    films : pandas.DataFrame
        Columns ``supply temperature [K]``, ``film``, ``onset [rpm]``, ``constant-viscosity onset [rpm]``, ``oil``.
    modes : pandas.DataFrame, optional
        Columns ``supply temperature [K]``, ``onset [rpm]``, ``unstable at grid start`` (rows unstable at the grid's
        first speed are not drawn: their onset lies below the grid).
    title : str, optional
    runups : pandas.DataFrame, optional
        Run-up onsets (:func:`frbmodel.studies.thermal.runup_onsets_vs_supply`): columns ``supply temperature [K]``,
        ``onset [rpm]``, ``ramp start [rpm]``, ``ramp end [rpm]``, ``ramp time [s]``; components without an onset
        inside the run (present from its start) are not drawn.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    names = list(dict.fromkeys(films["film"]))
    bearings = list(dict.fromkeys(n.rsplit(" ", 1)[0] for n in names))
    for name in names:
        grp = films[films["film"] == name].sort_values("supply temperature [K]")
        color = f"C{bearings.index(name.rsplit(' ', 1)[0])}"
        ls = "-" if name.endswith("inner") else "--"
        ax.plot(grp["supply temperature [K]"], grp["onset [rpm]"] / 1e3, ls, marker="o", color=color, lw=1.6,
                label=f"{name} film (thermal model)")
        ax.axhline(grp["constant-viscosity onset [rpm]"].iloc[0] / 1e3, color=color, ls=":", lw=1.0)
    if modes is not None and len(modes):
        inside = modes[~modes["unstable at grid start"].astype(bool)]
        ax.plot(inside["supply temperature [K]"], inside["onset [rpm]"] / 1e3, "x", color="k", ms=7,
                label="a Campbell mode loses stability (grid-interpolated)")
    if runups is not None and len(runups):
        r = runups[runups["onset [rpm]"].notna()]
        ramp = runups.iloc[0]
        ax.plot(r["supply temperature [K]"], r["onset [rpm]"] / 1e3, "s", mfc="none", color="C3", ms=7,
                label=f"run-up sub-synchronous onset ({ramp['ramp start [rpm]'] / 1e3:g} -> "
                      f"{ramp['ramp end [rpm]'] / 1e3:g} krpm in {ramp['ramp time [s]']:g} s)")
    ax.plot([], [], ":", color="0.3", label="constant viscosities (system file)")
    ax.set_xlabel("oil supply temperature [K]")
    ax.set_ylabel("whirl onset speed [krpm]")
    ax.secondary_xaxis("top", functions=(lambda k: k - _ZERO_C_K, lambda c: c + _ZERO_C_K)).set_xlabel("[°C]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title is None:
        title = f"Whirl onsets vs supply temperature: {films['oil'].iloc[0]}"
    ax.set_title(title)
    fig.tight_layout()
    return fig
