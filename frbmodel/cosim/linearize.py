"""Linearization mode: collect the FMUs' local state-space matrices at an operating point and interconnect them
along the SSP connections into the global A matrix; modal analysis as in :func:`frbmodel.linear.campbell`.

Bearing FMU b: ẋ_b = A_b x_b + B_b u_b, F_b = C_b x_b + D_b u_b with x_b = ring (x, y, vx, vy), u_b = journal
(x, y, vx, vy). Rotor FMU: ẋ_r = A_r x_r + B_r F, y_r = C_r x_r with F the bearing forces and y_r the journals.
With u_b = C_r,b x_r:  ẋ_r = (A_r + Σ B_r,b D_b C_r,b) x_r + Σ B_r,b C_b x_b,  ẋ_b = A_b x_b + B_b C_r,b x_r.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, check_speed
from ..core.progress import counter_bar, progress_enabled
from ..core.units import rpm_to_rad_s
from ..linear.assembly import mass_matrix
from ..linear.campbell import campbell_from_modes, exact_onsets, film_whirl_rows, speed_grid_order
from ..linear.equilibrium import bearing_equilibrium
from ..linear.modal import modes_from_state
from ..linear.whirl import film_names
from ..system.methods import get_method
from .build import build_fmus
from .fmu_system import rotor_system_of_fmu
from .loader import model_identifier
from .master import CosimStopped, Master, operating_point_overrides, system_from_parameters
from .ssp import read_ssp
from .system_master import is_system_ssp


def _matrix(fmu, name, nr, nc):
    names = [f"{name}_{i + 1}_{k + 1}" for i in range(nr) for k in range(nc)]
    return np.array(fmu.call("getReal", fmu.vr(names))).reshape(nr, nc)


def has_linearization(fmu) -> bool:
    """True if the FMU (``.fmu`` file) was built with the linearization outputs (``frb build-fmus
    --linearization``)."""
    import xml.etree.ElementTree as ET
    import zipfile

    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    return any(sv.get("name") == "nx" for sv in root.iter("ScalarVariable"))


_VARIANTS = {}  # (SSP path, modification time) -> folder of its linearization variant (this process)


def linearization_ssp(ssp, progress=None):
    """The SSP ``ssp`` with FMUs that have the linearization outputs: ``ssp`` itself if its FMUs have them, else a
    copy (in a temporary folder, made once per process and SSP) whose bearing and rotor FMUs are rebuilt with them
    for the system its rotor FMU was built for; its SSDs and parameter sets are those of ``ssp``.

    Parameters
    ----------
    ssp : str or Path
        The SSP archive or folder.
    progress : callable, optional
        Called with one message per written file of the rebuild.

    Returns
    -------
    Path
    """
    import atexit
    import shutil
    import tempfile


    key = (str(Path(ssp).resolve()), Path(ssp).stat().st_mtime if Path(ssp).exists() else None)
    if key in _VARIANTS and _VARIANTS[key].is_dir():
        return _VARIANTS[key]
    with read_ssp(ssp) as s:
        fmus = sorted(set(s.components.values()))
        if all(has_linearization(f) for f in fmus):
            return Path(ssp)
        tmp = Path(tempfile.mkdtemp(prefix="frb_linearization_"))
        atexit.register(shutil.rmtree, str(tmp), ignore_errors=True)
        shutil.copytree(s.root, tmp / "ssp")
        rotor = [f for f in fmus if model_identifier(f) == "TurbochargerRotor"]
        system = rotor_system_of_fmu(rotor[0]) if rotor else None
        built = {p.stem: p for p in build_fmus(tmp / "build", rotor_file=system, linearization=True,
                                               progress=progress or (lambda m: None)) if p.suffix == ".fmu"}
        for f in fmus:
            target = tmp / "ssp" / f.relative_to(s.root)
            shutil.copyfile(built[model_identifier(f)], target)
    _VARIANTS[key] = tmp / "ssp"
    return _VARIANTS[key]


def _dims(fmu):
    return fmu.call("getInteger", fmu.vr(["nx", "nu", "ny"]))


def linearize(ssp, speed_rpm, method="J", parameter_set="co36"):
    """Global state matrix of the SSP system at the ``method`` equilibrium at ``speed_rpm``, from the FMUs.

    Parameters
    ----------
    ssp : str or Path
        The SSP archive (``frb build-fmus``).
    speed_rpm : float
        Rotor speed of the operating point [rpm].
    method : {"F", "G", "I", "J"}
        Operating-point method (one with ring degrees of freedom).
    parameter_set : str
        SSP parameter set, e.g. ``"co36"``.

    Returns
    -------
    A : ndarray, shape (N, N)
        Global state matrix (SI units) in the state order [rotor q, ring_t (x, y), ring_c (x, y), rotor q̇,
        ring_t (vx, vy), ring_c (vx, vy)] — the DoF order of :func:`frbmodel.linear_system`.
    system : Turbocharger
        The frbmodel system of the parameter set.

    Raises
    ------
    ParameterError
        For a method without ring degrees of freedom.
    CosimStopped
        If an FMU fails (an :class:`~frbmodel.cosim.fmu.FmiCallFailed`).
    """

    m = get_method(method)
    if m.letter not in "FGIJ":
        raise ParameterError(f"method = {method!r}: the FMU linearization covers the film methods with ring DoFs "
                             "(F, G, I, J)")
    check_speed("speed_rpm", speed_rpm)
    if Path(ssp).exists() and is_system_ssp(ssp):  # (it was refused for its 1 ms step, naming --unvalidated-step)
        raise ParameterError(f"SSP {str(ssp)!r} runs the whole-turbocharger FMU (a system SSP such as "
                             "engine_turbocharger.ssp); the linearization interconnects the rotor and bearing FMUs: "
                             "give their SSP (turbocharger.ssp of frb build-fmus)")
    master = Master(linearization_ssp(ssp), parameter_set)
    master.ssp_path = ssp  # (its messages name the user's SSP, not the linearization copy in a temporary folder)
    system = master.system
    ov = operating_point_overrides(system, speed_rpm, method=m.letter)
    for comp in master.ssp.components:
        master.params.setdefault(comp, {}).update(ov.get(comp, {}))
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


def campbell_from_fmu(ssp, speeds_rpm, method="J", parameter_set="co36", progress: bool = False):
    """Holistic Campbell diagram from the FMUs alone (same result type as :func:`frbmodel.linear.campbell`).

    The global state matrix at each speed comes from :func:`linearize` (the FMUs' local matrices, interconnected
    along the SSP's connections); the film whirl data and the exact whirl onsets are those of the library for the
    system read from the parameter set (:func:`frbmodel.film_onset_speeds`).

    Parameters
    ----------
    ssp : str or Path
        The SSP archive (``frb build-fmus``).
    speeds_rpm : array_like
        Rotor speeds [rpm], > 0, in any order (the result is sorted ascending).
    method : {"F", "G", "I", "J"}
        Operating-point method.
    parameter_set : str
        SSP parameter set, e.g. ``"co36"``.
    progress : bool
        Show a progress bar over the speeds (tqdm, on stderr).

    Returns
    -------
    CampbellResult
        Its ``meta`` records the SSP, the parameter set, the system read from it (``system.to_dict()``), the
        method and the film model.
    """

    m = get_method(method)
    given = m.check_speeds(speeds_rpm)
    if np.any(given <= 0):  # (the FMUs linearize their films whatever the method)
        raise ParameterError(f"speeds_rpm contains {float(given[given <= 0][0])!r} rpm: the FMUs' films need speeds "
                             "> 0")
    speeds = np.sort(given)
    mode_sets, system, rows = [], None, []
    with counter_bar(speeds.size, f"campbell {m.letter} from FMUs", progress_enabled(progress), unit="speed") as bar:
        for s in speeds:
            A, system = linearize(ssp, s, m.letter, parameter_set)
            mode_sets.append(modes_from_state(A, A.shape[0] // 2))
            omega = rpm_to_rad_s(s)

            def equilibria(letter, system=system, omega=omega):
                return [bearing_equilibrium(b, w, omega, letter, system.film_model, system.gravity)
                        for b, w in zip(system.bearings, system.bearing_loads)]

            eqs = equilibria(m.letter)
            # RSR from the method's equilibria, film whirl from the method-J equilibria (as frbmodel.linear.campbell)
            rows.append(([e.ring_speed_ratio for e in eqs],
                         *film_whirl_rows(system, eqs if m.letter == "J" else equilibria("J"))))
            bar.update(1)
    rsr = np.array([r[0] for r in rows])
    whirl_hz, margin, ecc = (np.array([r[k] for r in rows]) for k in (1, 2, 3))
    M, ring_dofs = mass_matrix(system, m.letter)
    onsets, onset_source = exact_onsets(system, speeds)
    meta = {"system_name": f"{system.name} (from FMUs: {ssp}, set {parameter_set})", "system": system.to_dict(),
            "film_model": system.film_model, "method_title": m.title, "method_options": m.options(),
            "outer_clearance_m": [b.outer.clearance for b in system.bearings],
            "films": list(film_names(system)), "bearings": [b.name for b in system.bearings],
            "source": "FMU linearization", "ssp": str(Path(ssp).resolve()), "parameter_set": parameter_set,
            "whirl": True, "whirl_onset_source": f"{onset_source}, on the system of the parameter set",
            "speed_grid_order": speed_grid_order(given)}
    return campbell_from_modes(m.letter, speeds, mode_sets, system.rotor, M, ring_dofs, rsr, ecc, whirl_hz, margin,
                               meta, whirl_onset_rpm=onsets)


__all__ = ["linearize", "campbell_from_fmu", "system_from_parameters", "CosimStopped"]
