"""Linearization mode: collect the FMUs' local state-space matrices at an operating point and interconnect them
along the SSP connections into the global A matrix; modal analysis as in :func:`frbmodel.campbell`.

Bearing FMU b: ẋ_b = A_b x_b + B_b u_b, F_b = C_b x_b + D_b u_b with x_b = ring (x, y, vx, vy), u_b = journal
(x, y, vx, vy). Rotor FMU: ẋ_r = A_r x_r + B_r F, y_r = C_r x_r with F the bearing forces and y_r the journals.
With u_b = C_r,b x_r:  ẋ_r = (A_r + Σ B_r,b D_b C_r,b) x_r + Σ B_r,b C_b x_b,  ẋ_b = A_b x_b + B_b C_r,b x_r.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .master import CosimStopped, Master, operating_point_overrides, system_from_parameters


def _matrix(fmu, name, nr, nc):
    names = [f"{name}[{i + 1},{k + 1}]" for i in range(nr) for k in range(nc)]
    return np.array(fmu.call("getReal", fmu.vr(names))).reshape(nr, nc)


def _dims(fmu):
    return fmu.call("getInteger", fmu.vr(["nx", "nu", "ny"]))


def linearize(ssp, speed_rpm, method="J", parameter_set="co36"):
    """Global state matrix of the SSP system at the ``method`` equilibrium at ``speed_rpm``, from the FMUs.

    Returns ``(A, system)``: A in the state order [rotor q, ring_t (x, y), ring_c (x, y), rotor q̇,
    ring_t (vx, vy), ring_c (vx, vy)] — the DoF order of :func:`frbmodel.linear_system` — and the frbmodel
    system of the parameter set.
    """
    from ..methods import get_method

    m = get_method(method)
    if m.letter not in "FGIJ":
        raise ParameterError(f"method = {method!r}: the FMU linearization covers the film methods with ring DoFs "
                             "(F, G, I, J)")
    master = Master(ssp, parameter_set)
    system = master.system
    ov = operating_point_overrides(system, speed_rpm, method=m.letter)
    for comp in master.ssp.components:
        master.params.setdefault(comp, {}).update(ov.get(comp, {}))
        master.params[comp]["linearization"] = ("Boolean", True)
    with master:
        master.initialize()  # parameters, then the journals and speed to the bearings (the operating point)
        rotor = master.rotor
        nx_r, nu_r, ny_r = _dims(rotor)
        Ar, Br, Cr = _matrix(rotor, "A", nx_r, nx_r), _matrix(rotor, "B", nx_r, nu_r), _matrix(rotor, "C", ny_r, nx_r)
        n_r = nx_r // 2
        blocks = []
        for k, f in enumerate(master.bearings):  # the rotor's input/output blocks follow the system's bearings
            nx, nu, ny = _dims(f)
            blocks.append((k, _matrix(f, "A", nx, nx), _matrix(f, "B", nx, nu), _matrix(f, "C", ny, nx),
                           _matrix(f, "D", ny, nu)))
    nb = 4 * len(blocks)
    N = nx_r + nb
    A = np.zeros((N, N))
    A[:nx_r, :nx_r] = Ar
    for i, (k, Ab, Bb, Cb, Db) in enumerate(blocks):
        sl = slice(nx_r + 4 * i, nx_r + 4 * i + 4)
        Crb = Cr[4 * k:4 * k + 4]
        Brb = Br[:, 2 * k:2 * k + 2]
        A[:nx_r, :nx_r] += Brb @ Db @ Crb
        A[:nx_r, sl] += Brb @ Cb
        A[sl, :nx_r] += Bb @ Crb
        A[sl, sl] += Ab
    # reorder to [q_r, ring positions, q̇_r, ring velocities]
    ring_pos = [nx_r + 4 * i + j for i in range(len(blocks)) for j in (0, 1)]
    ring_vel = [nx_r + 4 * i + j for i in range(len(blocks)) for j in (2, 3)]
    perm = list(range(n_r)) + ring_pos + list(range(n_r, nx_r)) + ring_vel
    return A[np.ix_(perm, perm)], system


def campbell_from_fmu(ssp, speeds_rpm, method="J", parameter_set="co36", progress=None):
    """Holistic Campbell diagram from the FMUs alone (same result type as :func:`frbmodel.campbell`)."""
    from ..campbell import campbell_from_modes, film_whirl_rows
    from ..equilibrium import bearing_equilibrium
    from ..linear import mass_matrix
    from ..modal import modes_from_state
    from ..units import rpm_to_rad_s

    speeds = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    mode_sets = []
    system = None
    rsr = np.full((speeds.size, 2), np.nan)
    ecc = np.full((speeds.size, 4), np.nan)
    whirl_hz = np.full((speeds.size, 4), np.nan)
    margin = np.full((speeds.size, 4), np.nan)
    for i, s in enumerate(speeds):
        A, system = linearize(ssp, s, method, parameter_set)
        mode_sets.append(modes_from_state(A, A.shape[0] // 2))
        loads = system.bearing_loads
        eqs = [bearing_equilibrium(b, loads[k], rpm_to_rad_s(s), method, system.film_model, system.gravity)
               for k, b in enumerate(system.bearings)]
        rsr[i] = [e.ring_speed_ratio for e in eqs]
        whirl_hz[i], margin[i], ecc[i] = film_whirl_rows(system, eqs)
        if progress:
            progress(i + 1, speeds.size)
    M, ring_dofs = mass_matrix(system, method)
    meta = {"system": f"{system.name} (from FMUs: {ssp}, set {parameter_set})", "film_model": system.film_model,
            "source": "FMU linearization"}
    return campbell_from_modes(method.upper(), speeds, mode_sets, system.rotor, M, ring_dofs, rsr, ecc, whirl_hz,
                               margin, meta)


__all__ = ["linearize", "campbell_from_fmu", "system_from_parameters", "CosimStopped"]
