"""Holistic Campbell diagram: frequencies, modal damping and precession of all modes vs rotor speed."""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .equilibrium import bearing_equilibrium
from .errors import ParameterError
from .linear import linear_system
from .methods import get_method
from .modal import (
    batch_modes,
    classify_precession,
    precession_index,
    ring_energy_fraction,
    shape_class,
    speed_modes,
    track,
)
from .presets import PAPER_SPEED_RANGE_RPM
from .units import rpm_to_rad_s
from .whirl import FILM_NAMES, bearing_whirl

#: a mode is called a ring mode when the rings carry more than this share of its kinetic energy
RING_MODE_FRACTION = 0.5


@dataclass
class CampbellResult:
    """Result of :func:`campbell`. Arrays are per speed (rows) and tracked mode (columns, NaN = absent).

    Attributes
    ----------
    speeds_rpm : (n,)
    frequencies_hz : (n, m) damped natural frequencies [Hz]
    damping : (n, m) modal damping D = −Re λ / |λ| [-]; D < 0 is unstable
    precession : (n, m) "forward" | "backward" | "mixed" ("" where the mode is absent)
    mode_kind : (n, m) "cylindrical" | "conical" | "bending" (rotor modes, from the shaft's displacement
        pattern) or "ring" (the rings carry > 50 % of the kinetic energy)
    ring_fraction : (n, m) ring share of the modal kinetic energy [-]
    eigenvalues : (n, m) complex [1/s]
    ring_speed_ratio : (n, 2) RSR of turbine / compressor bearing (NaN for methods without film equilibrium)
    eccentricity : (n, 4) ε of the four films from the whirl equilibrium (order of FILM_NAMES)
    whirl_hz : (n, 4) film whirl frequencies γ ω_s / 2π [Hz] (from method J equilibria, physics.md §8)
    whirl_margin : (n, 4) > 0 where the film is past its whirl onset
    """

    method: str
    speeds_rpm: np.ndarray
    frequencies_hz: np.ndarray
    damping: np.ndarray
    precession: np.ndarray
    mode_kind: np.ndarray
    ring_fraction: np.ndarray
    eigenvalues: np.ndarray
    ring_speed_ratio: np.ndarray
    eccentricity: np.ndarray
    whirl_hz: np.ndarray
    whirl_margin: np.ndarray
    meta: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ derived
    @property
    def n_modes(self) -> int:
        return self.frequencies_hz.shape[1]

    @property
    def whirl_onset_rpm(self) -> np.ndarray:
        """First speed of the sweep (linearly interpolated) where each film passes its onset (NaN: none)."""
        out = np.full(4, np.nan)
        s = self.speeds_rpm
        for k in range(4):
            m = self.whirl_margin[:, k]
            idx = np.flatnonzero((m[:-1] <= 0) & (m[1:] > 0))
            if idx.size:
                j = idx[0]
                out[k] = s[j] + (s[j + 1] - s[j]) * (-m[j]) / (m[j + 1] - m[j])
            elif m.size and m[0] > 0:
                out[k] = s[0]
        return out

    def unstable_ranges(self):
        """Table (pandas DataFrame) of each mode's speed ranges with D < 0.

        Columns: mode, kind, precession, from [rpm], to [rpm], frequency at start/end [Hz], min damping.
        """
        import pandas as pd

        rows = []
        for j in range(self.n_modes):
            d = self.damping[:, j]
            uns = np.nan_to_num(d, nan=1.0) < 0
            if not uns.any():
                continue
            edges = np.diff(np.concatenate([[0], uns.astype(int), [0]]))
            starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
            for a, b in zip(starts, ends):
                prec = self.precession[a:b + 1, j]
                vals, counts = np.unique(prec, return_counts=True)
                kinds = self.mode_kind[a:b + 1, j]
                kv, kc = np.unique(kinds, return_counts=True)
                rows.append({"mode": j, "kind": kv[np.argmax(kc)], "precession": vals[np.argmax(counts)],
                             "from [rpm]": self.speeds_rpm[a], "to [rpm]": self.speeds_rpm[b],
                             "f at start [Hz]": self.frequencies_hz[a, j], "f at end [Hz]": self.frequencies_hz[b, j],
                             "min damping [-]": np.nanmin(d[a:b + 1])})
        df = pd.DataFrame(rows, columns=["mode", "kind", "precession", "from [rpm]", "to [rpm]", "f at start [Hz]",
                                         "f at end [Hz]", "min damping [-]"])
        return df.sort_values("from [rpm]").reset_index(drop=True)

    @property
    def n_unstable(self) -> np.ndarray:
        """Number of unstable modes per speed (n,)."""
        return np.sum(np.nan_to_num(self.damping, nan=1.0) < 0, axis=1)

    def to_dataframe(self):
        """Long-format table: one row per speed and mode, units in the column names."""
        import pandas as pd

        n, m = self.frequencies_hz.shape
        present = np.isfinite(self.frequencies_hz)
        ii, jj = np.nonzero(present)
        return pd.DataFrame({
            "speed [rpm]": self.speeds_rpm[ii],
            "mode [-]": jj,
            "frequency [Hz]": self.frequencies_hz[ii, jj],
            "damping [-]": self.damping[ii, jj],
            "growth rate Re(lambda) [1/s]": self.eigenvalues[ii, jj].real,
            "precession": self.precession[ii, jj],
            "kind": self.mode_kind[ii, jj],
            "ring energy fraction [-]": self.ring_fraction[ii, jj],
            "stable": self.damping[ii, jj] >= 0,
        })

    def films_dataframe(self):
        """Per-speed film data: RSR, eccentricities, whirl frequencies and margins (units in names)."""
        import pandas as pd

        d = {"speed [rpm]": self.speeds_rpm,
             "RSR turbine [-]": self.ring_speed_ratio[:, 0], "RSR compressor [-]": self.ring_speed_ratio[:, 1]}
        for k, name in enumerate(FILM_NAMES):
            d[f"eps {name} [-]"] = self.eccentricity[:, k]
            d[f"whirl {name} [Hz]"] = self.whirl_hz[:, k]
            d[f"whirl margin {name} [-]"] = self.whirl_margin[:, k]
        return pd.DataFrame(d)

    # ------------------------------------------------------------------ output
    def plot(self, fmax_hz=None, whirl=True, one_x=True, ax=None, title=None):
        """Holistic Campbell diagram (matplotlib Figure); see :func:`frbmodel.plots.campbell_figure`."""
        from .plots import campbell_figure

        return campbell_figure(self, fmax_hz=fmax_hz, whirl=whirl, one_x=one_x, ax=ax, title=title)

    def plot_html(self, path=None, fmax_hz=None, whirl=True, one_x=True):
        """Interactive plotly figure (hover: speed, frequency, D, precession); written to ``path`` if given."""
        from .plots import campbell_plotly

        fig = campbell_plotly(self, fmax_hz=fmax_hz, whirl=whirl, one_x=one_x)
        if path is not None:
            fig.write_html(str(path), include_plotlyjs="cdn" if self.meta.get("html_cdn") else True)
        return fig

    def save(self, out_dir, stem=None, fmax_hz=None, png=True, html=True):
        """Write ``<stem>_modes.csv``, ``<stem>_films.csv``, ``<stem>_unstable.csv``, ``<stem>.json``
        (metadata with units), and the PNG / HTML figures into ``out_dir``. Returns the list of paths."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stem = stem or f"campbell_{self.method}"
        paths = []
        p = out / f"{stem}_modes.csv"
        self.to_dataframe().to_csv(p, index=False)
        paths.append(p)
        p = out / f"{stem}_films.csv"
        self.films_dataframe().to_csv(p, index=False)
        paths.append(p)
        p = out / f"{stem}_unstable.csv"
        self.unstable_ranges().to_csv(p, index=False)
        paths.append(p)
        p = out / f"{stem}.json"
        meta = dict(self.meta)
        meta.update({"method": self.method, "whirl_onset_rpm": [None if not np.isfinite(x) else float(x)
                                                                 for x in self.whirl_onset_rpm],
                     "films": list(FILM_NAMES),
                     "units": {"speed": "rpm", "frequency": "Hz", "damping": "-", "eccentricity": "-"}})
        p.write_text(json.dumps(meta, indent=2, default=str))
        paths.append(p)
        if png:
            import matplotlib.pyplot as plt

            fig = self.plot(fmax_hz=fmax_hz)
            p = out / f"{stem}.png"
            fig.savefig(p, dpi=130, bbox_inches="tight")
            plt.close(fig)
            paths.append(p)
        if html:
            p = out / f"{stem}.html"
            self.plot_html(p, fmax_hz=fmax_hz)
            paths.append(p)
        return paths


def campbell(system, method="J", speeds_rpm=None, whirl=True, progress=None, **kw) -> CampbellResult:
    """Holistic Campbell diagram of ``system`` for bearing-modelling ``method``.

    Parameters
    ----------
    system : Turbocharger
    method : {"A", "B", "C", "D", "E", "F", "G", "I", "J"}
    speeds_rpm : array_like, optional
        Rotor speeds [rpm] (default 10 000 ... 250 000, 100 points). Must be > 0 for film methods.
    whirl : bool
        Also compute the four film whirl curves and their onsets (method-J equilibria).
    progress : callable, optional
        Called as ``progress(i, n)`` after each speed.
    **kw
        Spring stiffnesses of A, B, E: ``k``, ``kx``, ``ky`` [N/m].

    Returns
    -------
    CampbellResult

    Examples
    --------
    >>> import numpy as np, frbmodel as frb
    >>> cd = frb.campbell(frb.turbocharger(), "A", np.array([1.0, 100e3]), whirl=False)
    >>> [round(float(f), 1) for f in cd.frequencies_hz[1, :3]]     # physics.md §11
    [60.2, 192.5, 297.3]
    """
    m = get_method(method)
    if speeds_rpm is None:
        speeds_rpm = np.linspace(*PAPER_SPEED_RANGE_RPM, 100)
    speeds = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    if speeds.ndim != 1 or speeds.size == 0 or not np.all(np.isfinite(speeds)):
        raise ParameterError(f"speeds_rpm = {speeds_rpm!r} is invalid: a non-empty 1-D list of finite speeds [rpm]")
    if m.needs_films and np.any(speeds <= 0):
        raise ParameterError(f"speeds_rpm contains {speeds[speeds <= 0][0]!r} rpm, invalid for method {m.letter}: "
                             "linearized films need speeds > 0")
    m.options(**kw)  # validate early
    t0 = time.perf_counter()
    rotor = system.rotor
    loads = system.bearing_loads
    rsr = np.full((speeds.size, 2), np.nan)
    ecc = np.full((speeds.size, 4), np.nan)
    whirl_hz = np.full((speeds.size, 4), np.nan)
    margin = np.full((speeds.size, 4), np.nan)
    t_eq = 0.0
    systems = []
    for i, s in enumerate(speeds):
        omega = rpm_to_rad_s(s)
        eqs = None
        if m.needs_films:
            te = time.perf_counter()
            eqs = tuple(bearing_equilibrium(b, loads[k], omega, m.letter, system.film_model, system.gravity)
                        for k, b in enumerate(system.bearings))
            t_eq += time.perf_counter() - te
            rsr[i] = [e.ring_speed_ratio for e in eqs]
            systems.append(linear_system(system, m.letter, s, equilibria=eqs, **kw))
        if whirl and omega > 0:
            weqs = eqs if m.letter == "J" else tuple(
                bearing_equilibrium(b, loads[k], omega, "J", system.film_model, system.gravity)
                for k, b in enumerate(system.bearings))
            whirl_hz[i], margin[i], ecc[i] = film_whirl_rows(system, weqs)
        if progress is not None and (m.needs_films or whirl):
            progress(i + 1, speeds.size)
    if m.needs_films:
        mode_sets = batch_modes(systems)
        mass = systems[0].M
        ring_dofs = systems[0].ring_dofs
    else:  # speed-independent M, K, bearing damping: assemble once, all speeds in one stacked solve
        ls0 = linear_system(system, m.letter, 0.0, **kw)
        G = np.zeros_like(ls0.M)
        G[:rotor.n_dof, :rotor.n_dof] = rotor.G
        mode_sets = speed_modes(ls0.M, ls0.K, ls0.C, G, rpm_to_rad_s(speeds), ls0.planes())
        mass, ring_dofs = ls0.M, ls0.ring_dofs
    meta = {"system": system.name, "film_model": system.film_model, "method_title": m.title,
            "method_options": m.options(**kw), "cpu_time_s": None, "equilibrium_time_s": t_eq,
            "outer_clearance_m": [b.outer.clearance for b in system.bearings]}
    res = campbell_from_modes(m.letter, speeds, mode_sets, rotor, mass, ring_dofs, rsr, ecc, whirl_hz, margin, meta)
    res.meta["cpu_time_s"] = time.perf_counter() - t0
    return res


def film_whirl_rows(system, equilibria):
    """Per-film whirl data at one speed from the bearings' equilibria (physics.md §8).

    Parameters
    ----------
    system : Turbocharger
    equilibria : sequence of BearingEquilibrium
        One per bearing of ``system``.

    Returns
    -------
    whirl_hz, margin, eps : ndarray (2 · n_bearings,)
        Whirl frequency [Hz], instability margin [-] (> 0: past onset) and eccentricity ratio of each film, in
        the order (bearing 0 inner, outer, bearing 1 inner, outer).
    """
    whirl_hz, margin, eps = (np.empty(2 * len(system.bearings)) for _ in range(3))
    for k, (b, e) in enumerate(zip(system.bearings, equilibria)):
        wi, wo, mi, mo = bearing_whirl(b, e, system.film_model, system.gravity)
        whirl_hz[2 * k:2 * k + 2] = np.array([wi, wo]) / (2 * math.pi)
        margin[2 * k:2 * k + 2] = [mi, mo]
        eps[2 * k:2 * k + 2] = [e.eps_inner, e.eps_outer]
    return whirl_hz, margin, eps


def campbell_from_modes(letter, speeds, mode_sets, rotor, mass, ring_dofs, rsr, ecc, whirl_hz, margin, meta):
    """Campbell post-processing (precession, mode kind, tracking) of per-speed :class:`Modes` whose displacement
    DoFs are the rotor's followed by the rings' (x, y). Used by :func:`campbell` and by the FMU linearization."""
    nn = rotor.n_nodes
    lam_list = [md.eigenvalues for md in mode_sets]
    shape_list = [md.shapes for md in mode_sets]
    v_idx, w_idx = np.arange(nn) * 4, np.arange(nn) * 4 + 1
    if len({sh.shape for sh in shape_list}) == 1:  # same mode count at all speeds: one vectorised pass
        stack = np.stack(shape_list)
        prec_list = list(classify_precession(*precession_index(stack, v_idx, w_idx)))
        ring_list = list(ring_energy_fraction(stack, mass, ring_dofs))
        form_list = list(shape_class(stack, v_idx, w_idx, rotor.node_z))
    else:
        prec_list = [classify_precession(*precession_index(sh, v_idx, w_idx)) for sh in shape_list]
        ring_list = [ring_energy_fraction(sh, mass, ring_dofs) for sh in shape_list]
        form_list = [shape_class(sh, v_idx, w_idx, rotor.node_z) for sh in shape_list]
    perm = track(lam_list, shape_list)
    n_tr = perm[0].size if perm else 0
    lam = np.full((speeds.size, n_tr), np.nan + 0j)
    prec = np.full((speeds.size, n_tr), "", dtype=object)
    form = np.full((speeds.size, n_tr), "", dtype=object)
    ringf = np.full((speeds.size, n_tr), np.nan)
    P = np.array(perm)
    if np.all(P >= 0) and len({x.size for x in lam_list}) == 1:  # full tracks: gather all speeds at once
        lam = np.take_along_axis(np.stack(lam_list), P, axis=1)
        prec = np.take_along_axis(np.stack(prec_list), P, axis=1)
        ringf = np.take_along_axis(np.stack(ring_list), P, axis=1)
        form = np.take_along_axis(np.stack(form_list), P, axis=1)
    else:
        for i, p in enumerate(perm):
            ok = p >= 0
            lam[i, ok] = lam_list[i][p[ok]]
            prec[i, ok] = prec_list[i][p[ok]]
            ringf[i, ok] = ring_list[i][p[ok]]
            form[i, ok] = form_list[i][p[ok]]
    kind = np.where(np.isfinite(ringf), np.where(ringf > RING_MODE_FRACTION, "ring", form), "").astype(object)
    # order tracks by their mean frequency
    order = np.argsort(np.nanmean(np.where(np.isfinite(lam.imag), lam.imag, np.nan), axis=0))
    lam, prec, kind, ringf = lam[:, order], prec[:, order], kind[:, order], ringf[:, order]
    freq = lam.imag / (2 * math.pi)
    damp = -lam.real / np.abs(lam)
    return CampbellResult(letter, speeds, freq, damp, prec, kind, ringf, lam, rsr, ecc, whirl_hz, margin, meta)
