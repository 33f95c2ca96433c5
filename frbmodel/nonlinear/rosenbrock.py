"""Compiled Rosenbrock integrator (RODAS, order 4(3), stiffly accurate, L-stable) for the monolithic model.

A Rosenbrock method solves linear systems with the matrix W = I/(hγ) − J instead of iterating Newton to
convergence: one Jacobian and one LU factorization per step, six right-hand sides, no convergence failures when the
film forces are strongly nonlinear (the implicit Radau solver's Newton iteration limits its step there and makes it
refresh its Jacobian on most steps). The coefficients are those of Hairer & Wanner's RODAS (Solving ODEs II,
Sect. VI.4), with its embedded third-order error estimate and its continuous output of order 3, so that output
times do not cut the steps. The Jacobian is the rotor's constant block exactly plus forward differences only in the
columns the films depend on (journal and ring displacements and velocities, ring speeds, and the rotor speed of a
torque-driven rotor), each bearing's columns by differences of that bearing's kernel alone: :func:`jacobian`. The
linear systems are solved reduced to the states after the rotor displacements, whose rows of the Jacobian are
q' = q̇ exactly (:func:`_factor`).

Everything runs in numba-compiled code; one call integrates through a chunk of output times. Three methods share
the code (``method`` of :func:`rodas_chunk`): the default :data:`RODAS4_FAST` (RODAS with its Jacobian's film
columns and its linear systems formed with less work: each film differenced alone, the ring blocks eliminated before
the LU; the same method, 0.84 of the cost per step), plain RODAS (:data:`RODAS4`, the reference of its test) and
Rodas5P (Steinebach 2023, order 5(4)). Measured cost of a
RODAS step of the main job inside the whirl (43 states, 2-core machine): 7 right-hand sides 9.9 µs, Jacobian 7.4 µs
(of which the bearings' columns 6.4), LU 4.4 µs, 6 solves 4.0 µs, error norm 0.4 µs; 27.7 µs a step in all
(docs/validation/nonlinear.md, "Cost of the integrator").
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.errors import MAX_SPEED_RPM
from ..core.linalg import SUM_FLAGS, lu_factor, lu_solve
from ..physics.bearing import ring_rhs_kernel, ring_torque_kernel
from ..physics.dynamics import add_unbalance_forces, film_data_at_speed, interp_uniform, monolithic_rhs
from ..physics.film import film_force_kernel
from ..physics.losses import journal_torque_kernel

#: typical displacement [m] (about a film clearance) that sets the difference steps of the film columns: step
#: 1.5e-8 x max(|y_k|, typical_k), the other states' typical sizes scaled from it as their tolerances are
#: (:func:`frbmodel.nonlinear.runup.atol_vector`); smaller steps drown in round-off (measured: 1 % error in a
# journal-velocity
#: column at 1e-12 m/s steps, 2e-6 at 1e-9 m/s)
FD_TYPICAL_M = 1e-5
#: failure reasons by status code of :func:`rodas_chunk`
STATUS = {1: "step budget exhausted", 2: "step size underflow", 3: "singular iteration matrix",
          4: f"torque-driven rotor speed left 0 < speed <= {MAX_SPEED_RPM:.0e} rpm"}
#: largest rotor speed [rad/s] of a torque-driven run, checked at every step (not only at the output samples: a
#: huge drive torque drives the speed far beyond it between two samples, in millions of ever shorter steps)
OMEGA_MAX = MAX_SPEED_RPM * math.pi / 30.0

#: no modal error norm (:func:`rodas_chunk`'s default)
NO_MODAL = np.zeros((0, 0))

# RODAS (Hairer & Wanner), gamma = 1/4
GAMMA = 0.25
A21, A31, A32 = 1.544, 0.9466785280815826, 0.2557011698983284
A41, A42, A43 = 3.314825187068521, 2.896124015972201, 0.9986419139977817
A51, A52, A53, A54 = 1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950
C21, C31, C32 = -5.6688, -2.430093356833875, -0.2063599157091915
C41, C42, C43 = -0.1073529058151375, -9.594562251023355, -20.47028614809616
C51, C52, C53, C54 = 7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160
C61, C62, C63, C64, C65 = 8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, \
    -6.058818238834054
CC2, CC3, CC4 = 0.386, 0.21, 0.63
D1, D2, D3, D4 = 0.25, -0.1043, 0.1035, -0.03620000000000023
H21, H22, H23, H24, H25 = 10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823, \
    1.025137723295662
H31, H32, H33, H34, H35 = -0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386, \
    -6.594389125716872

#: the methods of :func:`rodas_chunk` by code: RODAS 4(3) (Hairer & Wanner) and Rodas5P 5(4) (Steinebach 2023)
METHODS = {"rodas4": 0, "rodas5p": 1, "rodas4-fast": 2}
RODAS4, RODAS5P, RODAS4_FAST = 0, 1, 2

# Rodas5P (G. Steinebach, "Construction of Rosenbrock-Wanner method Rodas5P and numerical benchmarks within the Julia
# Differential Equations package", BIT Numer. Math. 63, 27 (2023), doi:10.1007/s10543-023-00967-x): 8 stages,
# order 5, embedded order 4 (the last stage increment is the error estimate), stiffly accurate, in the same
# transformed form as RODAS above (a = α Γ⁻¹, C = diag(1/γ) − Γ⁻¹, c_i = Σ_j α_ij, d_i = Σ_j γ_ij, rows 2...8), with
# its continuous output of order 4 (H, three rows). The 16-digit values as published with the paper's Julia
# implementation (OrdinaryDiffEq.jl, Rodas5PTableau); tests/test_rosenbrock.py checks every order condition of
# orders 1-5 (embedded: 1-4) on them.
GAMMA5 = 0.21193756319429014
A5 = np.array([  # rows: stages 2-6 (stages 7, 8 at the stage-6 point + k6, + k7)
    [3.0, 0.0, 0.0, 0.0, 0.0],
    [2.849394379747939, 0.45842242204463923, 0.0, 0.0, 0.0],
    [-6.954028509809101, 2.489845061869568, -10.358996098473584, 0.0, 0.0],
    [2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256, 0.030198172008377946]])
C5 = np.array([  # rows: stages 2-8
    [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-17.97296035885952, -2.859693295451294, 0.0, 0.0, 0.0, 0.0, 0.0],
    [147.12150275711716, -1.41221402718213, 71.68940251302358, 0.0, 0.0, 0.0, 0.0],
    [165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306, 0.0, 0.0, 0.0],
    [24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125, -0.6610691825249471, 0.0,
     0.0],
    [30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783, -19.097331116725623,
     -28.087943162872662, 0.0],
    [37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047, -40.06618937091002,
     -54.66780262877968, -9.48861652309627]])
CC5 = np.array([0.0, 0.6358126895828704, 0.4095798393397535, 0.9769306725060716, 0.4288403609558664, 1.0, 1.0, 1.0])
D5 = np.array([0.21193756319429014, -0.42387512638858027, -0.3384627126235924, 1.8046452872882734,
               2.325825639765069, 0.0, 0.0, 0.0])
H5 = np.array([  # continuous output: y(θ) = (1 − θ) y0 + θ (y1 + (1 − θ) (K1 + θ (K2 + θ K3))), K_r = Σ_j H5[r, j] k_j
    [25.948786856663858, -2.5579724845846235, 10.433815404888879, -2.3679251022685204, 0.524948541321073,
     1.1241088310450404, 0.4272876194431874, -0.17202221070155493],
    [-9.91568850695171, -0.9689944594115154, 3.0438037242978453, -24.495224566215796, 20.176138334709044,
     15.98066361424651, -6.789040303419874, -6.710236069923372],
    [11.419903575922262, 2.8879645146136994, 72.92137995996029, 80.12511834622643, -52.072871366152654,
     -59.78993625266729, -0.15582684282751913, 4.883087185713722]])


@njit(cache=True)
def film_columns(n_r, jn, torque, unbalance):
    """State indices whose Jacobian columns are taken by differences: the journals' x, y and their velocities, both
    rings' x, y, vx, vy, the ring speeds, the rotation angle (with unbalance) and the rotor speed (torque-driven);
    every other column is the rotor's constant block."""
    cols = []
    for b in range(2):
        cols.append(4 * jn[b])
        cols.append(4 * jn[b] + 1)
        cols.append(n_r + 4 * jn[b])
        cols.append(n_r + 4 * jn[b] + 1)
    for k in range(2 * n_r, 2 * n_r + 10):
        cols.append(k)
    if unbalance:
        cols.append(2 * n_r + 10)
    if torque:
        cols.append(2 * n_r + 11)
    return np.array(cols, dtype=np.int64)


@njit(cache=True)
def _bearing_eval(b, y, n_r, jn, geom, polys, ring_m, ring_i, grav, w, eps_cap, ax, ay, torque, dring, ring):
    """Bearing ``b``'s kernel at the state ``y``: journal force (fx, fy) [N], the ring's derivatives into ``dring``
    and, for a torque-driven rotor, the film torque on the journal [N m] (the terms of
    :func:`frbmodel.physics.dynamics.monolithic_rhs` that depend on this bearing's journal, ring and ring speed)."""
    j = 4 * jn[b]
    r0 = 2 * n_r + 4 * b
    for k in range(4):
        ring[k] = y[r0 + k]
    ring[4] = y[2 * n_r + 8 + b]
    fx, fy, _, _ = ring_rhs_kernel(geom[b], polys[b], ring_m[b], ring_i[b], grav, y[j], y[j + 1], y[n_r + j],
                                   y[n_r + j + 1], ring, w, eps_cap, dring, ax, ay)
    tj = 0.0
    if torque:
        tj = journal_torque_kernel(geom[b, 0], y[j] - ring[0], y[j + 1] - ring[1], fx, fy, w, ring[4], eps_cap)
    return fx, fy, tj


@njit(cache=True)
def _bearing_columns(y, jac, yp, scale, omega, omega_dot, args):
    """The Jacobian columns of both bearings' journal (x, y, vx, vy), ring (x, y, vx, vy) and ring-speed states,
    added to ``jac``: forward differences of each bearing's kernel alone (:func:`_bearing_eval`, step 1.5e-8 ·
    max(|y_k|, scale_k)), carried to the rotor's acceleration rows exactly through M⁻¹ (the journal force enters
    q̈ = M⁻¹ f − ... linearly), and, torque-driven, through Ω̇ = (T + Σ T_J) / J_p into the spin row, the rotor's
    Ω̇ M⁻¹G q term and the unbalance's Ω̇ term. The same derivatives as differencing the whole right-hand side, at a
    tenth of its cost and without its cancellation in q̈ (which holds the large M⁻¹K q)."""
    n_r = args[2]
    minv, minv_g = args[0][0], args[0][2]
    jn, polys, ring_m, ring_i, grav = args[3], args[5], args[6], args[7], args[8]
    geom = film_data_at_speed(args[4], omega, args[22], args[23])  # quasi-static viscosities (None: args[4] itself)
    unb_node, unb_me, unb_phase, eps_cap, housing = args[9], args[10], args[11], args[16], args[18]
    torque = y.size > 2 * n_r + 11
    jp = args[20] if torque else 1.0
    dring0, dring, ring = np.empty(5), np.empty(5), np.empty(5)
    # torque-driven: d(q̈)/d(Ω̇) = M⁻¹ (∂f_unbalance/∂Ω̇) − M⁻¹G q
    sens = np.zeros(n_r)
    if torque:
        fu = np.zeros(n_r)  # ∂f_unbalance/∂Ω̇: the load of add_unbalance_forces at Ω = 0, Ω̇ = 1
        add_unbalance_forces(fu, y[2 * n_r + 10], 0.0, 1.0, unb_node, unb_me, unb_phase)
        for i in range(n_r):
            acc = 0.0
            for k in range(n_r):
                acc += minv[i, k] * fu[k] - minv_g[i, k] * y[k]
            sens[i] = acc
    for b in range(2):
        j = 4 * jn[b]
        r0 = 2 * n_r + 4 * b
        local = (j, j + 1, n_r + j, n_r + j + 1, r0, r0 + 1, r0 + 2, r0 + 3, 2 * n_r + 8 + b)
        fx0, fy0, tj0 = _bearing_eval(b, y, n_r, jn, geom, polys, ring_m, ring_i, grav, omega, eps_cap,
                                      housing[0], housing[1], torque, dring0, ring)
        for c in local:
            for i in range(y.size):
                yp[i] = y[i]
            h = 1.5e-8 * max(abs(y[c]), scale[c])
            yp[c] = y[c] + h
            fx, fy, tj = _bearing_eval(b, yp, n_r, jn, geom, polys, ring_m, ring_i, grav, omega, eps_cap,
                                       housing[0], housing[1], torque, dring, ring)
            dfx, dfy, dwd = (fx - fx0) / h, (fy - fy0) / h, (tj - tj0) / (h * jp)
            for i in range(n_r):
                jac[n_r + i, c] += minv[i, j] * dfx + minv[i, j + 1] * dfy + dwd * sens[i]
            for k in range(5):
                jac[r0 + k if k < 4 else 2 * n_r + 8 + b, c] += (dring[k] - dring0[k]) / h
            if torque:
                jac[2 * n_r + 11, c] += dwd


@njit(cache=True)
def _film_fd(g, poly, u, hs, eps_cap, f):
    """One film's force at its inputs ``u`` = (e_x, e_y, ė_x, ė_y, ω_sum) into ``f[0]`` and at u + hs[k] e_k into
    ``f[k + 1]`` (k = 0 ... 4)."""
    for k in range(6):
        d0, d1, d2 = (hs[0] if k == 1 else 0.0), (hs[1] if k == 2 else 0.0), (hs[2] if k == 3 else 0.0)
        d3, d4 = (hs[3] if k == 4 else 0.0), (hs[4] if k == 5 else 0.0)
        fx, fy, _ = film_force_kernel(g[0], g[1], g[2], g[3], poly[0], poly[1], u[0] + d0, u[1] + d1, u[2] + d2,
                                      u[3] + d3, u[4] + d4, eps_cap)
        f[k, 0], f[k, 1] = fx, fy


@njit(cache=True)
def _ring_torque_at(geom, rix, riy, fix, fiy, rox, roy, fox, foy, omega, wfr, eps_cap):
    """The ring's torque [N m] as :func:`frbmodel.physics.bearing.ring_rhs_kernel` forms it (positions capped at
    ``eps_cap`` like the forces) from both films' relative positions and forces."""
    ei = math.sqrt(rix * rix + riy * riy) / geom[0, 2]
    eo = math.sqrt(rox * rox + roy * roy) / geom[1, 2]
    si = min(1.0, eps_cap / ei) if ei > 0 else 1.0
    so = min(1.0, eps_cap / eo) if eo > 0 else 1.0
    return ring_torque_kernel(geom[0], geom[1], rix * si, riy * si, fix, fiy, rox * so, roy * so, fox, foy, omega, wfr)


@njit(cache=True)
def _bearing_columns_films(y, jac, scale, omega, args):
    """:func:`_bearing_columns` of a prescribed-speed rotor by differences of each film alone in its own inputs:
    the inner film's force depends on the journal and ring states only through their differences (and on
    Ω + ω_FR), the outer film's on the ring's, so five differences of each film give all nine columns of a bearing
    (12 film evaluations instead of 20), the ring's torque formed at the perturbed positions and forces."""
    n_r = args[2]
    minv = args[0][0]
    jn, polys, ring_m, ring_i, eps_cap = args[3], args[5], args[6], args[7], args[16]
    geom = film_data_at_speed(args[4], omega, args[22], args[23])
    fi, fo, ui, uo, hs = np.empty((6, 2)), np.empty((6, 2)), np.empty(5), np.empty(5), np.empty(5)
    for b in range(2):
        j, r0, sw = 4 * jn[b], 2 * n_r + 4 * b, 2 * n_r + 8 + b
        jc = (j, j + 1, n_r + j, n_r + j + 1)
        for k in range(4):
            ui[k], uo[k] = y[jc[k]] - y[r0 + k], y[r0 + k]
            hs[k] = 1.5e-8 * max(abs(y[jc[k]]), abs(y[r0 + k]), scale[r0 + k])
        ui[4], uo[4] = omega + y[sw], y[sw]
        hs[4] = 1.5e-8 * max(abs(ui[4]), scale[sw])
        _film_fd(geom[b, 0], polys[b, 0], ui, hs, eps_cap, fi)
        _film_fd(geom[b, 1], polys[b, 1], uo, hs, eps_cap, fo)
        t0 = _ring_torque_at(geom[b], ui[0], ui[1], fi[0, 0], fi[0, 1], uo[0], uo[1], fo[0, 0], fo[0, 1], omega,
                             uo[4], eps_cap)
        for q in range(9):  # journal x, y, vx, vy; ring x, y, vx, vy; ring speed
            k = q if q < 4 else (q - 4 if q < 8 else 4)
            c = jc[q] if q < 4 else (r0 + q - 4 if q < 8 else sw)
            si, so = (1.0, 0.0) if q < 4 else ((-1.0, 1.0) if q < 8 else (1.0, 1.0))
            h = hs[k]
            dfix, dfiy = si * (fi[k + 1, 0] - fi[0, 0]) / h, si * (fi[k + 1, 1] - fi[0, 1]) / h
            dfox, dfoy = so * (fo[k + 1, 0] - fo[0, 0]) / h, so * (fo[k + 1, 1] - fo[0, 1]) / h
            dx, dy = (h if k == 0 else 0.0), (h if k == 1 else 0.0)
            tq = _ring_torque_at(geom[b], ui[0] + si * dx, ui[1] + si * dy, fi[0, 0] + h * dfix, fi[0, 1] + h * dfiy,
                                 uo[0] + so * dx, uo[1] + so * dy, fo[0, 0] + h * dfox, fo[0, 1] + h * dfoy, omega,
                                 uo[4] + (h if k == 4 else 0.0), eps_cap)
            for i in range(n_r):
                jac[n_r + i, c] += minv[i, j] * dfix + minv[i, j + 1] * dfiy
            jac[r0 + 2, c] += (dfox - dfix) / ring_m[b]
            jac[r0 + 3, c] += (dfoy - dfiy) / ring_m[b]
            jac[sw, c] += (tq - t0) / (h * ring_i[b])
        jac[r0, r0 + 2] += 1.0
        jac[r0 + 1, r0 + 3] += 1.0


@njit(cache=True)
def _rotor_columns(jac, whole, n_r, minv_k, minv_g, omega, omega_dot):
    """The rotor's exact block of :func:`jacobian` in every column not ``whole``, the rest of those columns zero."""
    n = jac.shape[0]
    for k in range(n):
        if whole[k]:
            continue
        for i in range(n):
            jac[i, k] = 0.0
        if k < n_r:  # displacement column: the stiffness operator
            for i in range(n_r):
                jac[n_r + i, k] = -(minv_k[i, k] + omega_dot * minv_g[i, k])
        elif k < 2 * n_r:  # velocity column: q' = q̇ and the gyroscopic operator
            jac[k - n_r, k] = 1.0
            for i in range(n_r):
                jac[n_r + i, k] = -omega * minv_g[i, k - n_r]


@njit(cache=True)
def _angle_column(jac, y, omega, omega_dot, args):
    """The rotation angle's column of :func:`jacobian`, exact: φ enters only the unbalance loads, whose derivative
    ∂f/∂φ is the load at φ + π/2 (d/dφ (cos θ, sin θ) = (cos(θ + π/2), sin(θ + π/2))), so the column is
    M⁻¹ ∂f/∂φ in the rotor's acceleration rows and zero elsewhere: no difference of the whole right-hand side (whose
    q̈ rows cancel the large M⁻¹K q)."""
    n_r = args[2]
    minv = args[0][0]
    c = 2 * n_r + 10
    df = np.zeros(n_r)
    add_unbalance_forces(df, y[c] + 0.5 * math.pi, omega, omega_dot, args[9], args[10], args[11])
    for i in range(y.size):
        jac[i, c] = 0.0
    for i in range(n_r):
        acc = 0.0
        for k in range(n_r):
            acc += minv[i, k] * df[k]
        jac[n_r + i, c] = acc


@njit(cache=True)
def jacobian(t, y, f0, jac, work, yp, cols, scale, omega, omega_dot, args, films=False):
    """∂(dy/dt)/∂y of :func:`frbmodel.physics.dynamics.monolithic_rhs` into ``jac``: the rotor rows exactly (q' = q̇,
    q̇' = −(M⁻¹K + Ω̇ M⁻¹G) q − Ω M⁻¹G q̇ + ...) in every column, the bearings' journal, ring and ring-speed columns
    added by differences of the bearing kernels (:func:`_bearing_columns`), the rotation angle's column (with
    unbalance) exactly (:func:`_angle_column`), a torque-driven rotor speed's by forward differences of the whole
    right-hand side (step 1.5e-8 · max(|y_k|, scale_k)). Journals on linear springs: the other ``cols`` by whole
    differences. ``f0`` = dy/dt at (t, y). ``films`` (the fast RODAS variant, prescribed speed): the bearings'
    columns by differences of each film alone (:func:`_bearing_columns_films`), the same entries otherwise."""
    n = y.size
    n_r = args[2]
    minv_k, minv_g = args[0][1], args[0][2]
    springs = args[15] > 0.0
    whole = np.zeros(n, dtype=np.bool_)
    for c in cols:
        whole[c] = springs or c >= 2 * n_r + 10
    if films and not springs and y.size == 2 * n_r + 11:  # the same entries, written row by row
        jac[:] = 0.0
        for i in range(n_r):
            jac[i, n_r + i] = 1.0
            for k in range(n_r):
                jac[n_r + i, k] = -(minv_k[i, k] + omega_dot * minv_g[i, k])
                jac[n_r + i, n_r + k] = -omega * minv_g[i, k]
        _bearing_columns_films(y, jac, scale, omega, args)
    else:
        _rotor_columns(jac, whole, n_r, minv_k, minv_g, omega, omega_dot)
    if not springs and not (films and y.size == 2 * n_r + 11):
        _bearing_columns(y, jac, yp, scale, omega, omega_dot, args)
    for c in cols:
        if c == 2 * n_r + 10:
            _angle_column(jac, y, omega, omega_dot, args)
            continue
        if not whole[c]:
            continue
        for i in range(n):
            yp[i] = y[i]
        h = 1.5e-8 * max(abs(y[c]), scale[c])
        yp[c] = y[c] + h
        monolithic_rhs(t, yp, work, *args)
        for i in range(n):
            jac[i, c] = (work[i] - f0[i]) / h


@njit(cache=True)
def _omegas(t, y, f0, n_r, args):
    """Rotor speed Ω [rad/s] (= dφ/dt) and acceleration Ω̇ [rad/s²] at (t, y)."""
    omega = f0[2 * n_r + 10]
    if y.size > 2 * n_r + 11:  # torque-driven: Ω̇ is the last derivative
        return omega, f0[2 * n_r + 11]
    return omega, interp_uniform(t, args[12], args[14])


@njit(cache=True, fastmath=SUM_FLAGS)
def _error_norm(err, y0, y1, rtol, atol, modal):
    """RMS of err / (atol + rtol max(|y0|, |y1|)); with ``modal`` (m x m, m > 0) the first 2 m entries (the rotor's
    displacements and velocities) are taken in the coordinates ``modal @ q`` and ``modal @ q̇`` first."""
    s = 0.0
    m = modal.shape[0]
    for blk in range(2 if m > 0 else 0):
        off = blk * m
        for k in range(m):
            e, a, b = 0.0, 0.0, 0.0
            for i in range(m):
                e += modal[k, i] * err[off + i]
                a += modal[k, i] * y0[off + i]
                b += modal[k, i] * y1[off + i]
            sc = atol[off + k] + rtol * max(abs(a), abs(b))
            s += (e / sc) ** 2
    for i in range(2 * m, err.size):
        sc = atol[i] + rtol * max(abs(y0[i]), abs(y1[i]))
        s += (err[i] / sc) ** 2
    return math.sqrt(s / err.size)


@njit(cache=True, fastmath=SUM_FLAGS)
def _stage(y, coef, ks, nk, out):
    """out = y + Σ_j coef[j] ks[j] over the first nk stages."""
    for i in range(y.size):
        s = y[i]
        for j in range(nk):
            s += coef[j] * ks[j, i]
        out[i] = s


@njit(cache=True)
def block_workspace(n, n_r, blocks):
    """Work arrays of :func:`_factor` and :func:`_solve`; ``blocks``: factor W whole (False, the former path) or by
    eliminating the two bearings' ring blocks first (True, :func:`_factor_blocks`)."""
    m = n - n_r
    d = m - 10
    dense = np.empty(d, dtype=np.int64)
    dense[:n_r] = np.arange(n_r)
    dense[n_r:] = np.arange(n_r + 10, m)
    ring = np.empty((2, 5), dtype=np.int64)
    for b in range(2):
        ring[b, :4] = np.arange(n_r + 4 * b, n_r + 4 * b + 4)
        ring[b, 4] = n_r + 8 + b
    mode = np.array([1 if blocks else 0, 0], dtype=np.int64)
    return (mode, ring, dense, np.empty((2, 5, 5)), np.empty((2, 5), dtype=np.int64), np.empty((2, d, 5)),
            np.empty((2, d), dtype=np.int64), np.empty(2, dtype=np.int64), np.empty((d, d)),
            np.empty(d, dtype=np.int64), np.empty(m), np.empty((2, 5)), np.empty(d), np.empty((d, 10)),
            np.empty(n_r))


@njit(cache=True)
def _factor(jac, hg, n_r, w, piv, blk):
    """Factor the iteration matrix W = I/(hγ) − J reduced to the states after the n_r displacements: their rows of
    J are q' = q̇ exactly (:func:`jacobian`), so W x = b gives x_q = hγ (b_q + x_v) and, for the rest z = (q̇, rings,
    spins, angle), R x_z = b_z + hγ J_zq b_q with R = I/(hγ) − J_zz − hγ J_zq (in the q̇ columns): an LU of
    n − n_r instead of n unknowns (a quarter of the work for the Table 2 rotor). ``hg`` = hγ; R goes into
    ``w`` (m, m), m = n − n_r, and its LU into ``w`` (or, by blocks, :func:`_factor_blocks`, into ``blk``); returns
    False for a singular matrix."""
    m = w.shape[0]
    fac = 1.0 / hg
    for a in range(m):
        for b in range(m):
            w[a, b] = -jac[n_r + a, n_r + b]
        w[a, a] += fac
        for b in range(n_r):
            w[a, b] -= hg * jac[n_r + a, b]
    blk[0][1] = 0
    if blk[0][0] and _factor_blocks(w, blk):
        blk[0][1] = 1
        return True
    return lu_factor(w, piv)


@njit(cache=True, fastmath=SUM_FLAGS)
def _factor_blocks(w, blk):
    """Block elimination of R (``w``, kept): each bearing's ring block D_b (ring x, y, vx, vy and ring speed: 5 x 5,
    which no other ring's state enters) is factored alone, G_b = D_b⁻¹ R[ring_b, dense] in the dense columns it
    couples to (found here: the journal's velocities, a torque-driven speed), and the Schur complement
    S = R[dense, dense] − Σ_b R[dense, ring_b] G_b over the rotor velocities, the angle (and the speed): an LU of
    17 instead of 27 unknowns and a few small ones. Returns False (the caller factors R whole) if a ring block
    couples to the other ring or a block is singular."""
    _, ring, dense, dlu, dpiv, g, nz, nnz, s, spiv = blk[:10]
    d = dense.size
    for b in range(2):
        for i in range(5):
            for k in range(5):
                if w[ring[b, i], ring[1 - b, k]] != 0.0:
                    return False
                dlu[b, i, k] = w[ring[b, i], ring[b, k]]
        if not lu_factor(dlu[b], dpiv[b]):
            return False
        cnt = 0
        for jd in range(d):
            coupled = False
            for i in range(5):
                coupled = coupled or w[ring[b, i], dense[jd]] != 0.0
            if coupled:
                nz[b, cnt] = jd
                for i in range(5):
                    g[b, cnt, i] = w[ring[b, i], dense[jd]]
                lu_solve(dlu[b], dpiv[b], g[b, cnt])
                cnt += 1
        nnz[b] = cnt
    bmat = blk[13]
    for i in range(d):
        for k in range(d):
            s[i, k] = w[dense[i], dense[k]]
        for b in range(2):
            for k in range(5):
                bmat[i, 5 * b + k] = w[dense[i], ring[b, k]]
    for b in range(2):
        for c in range(nnz[b]):
            jd = nz[b, c]
            for i in range(d):
                acc = 0.0
                for k in range(5):
                    acc += bmat[i, 5 * b + k] * g[b, c, k]
                s[i, jd] -= acc
    return lu_factor(s, spiv)


@njit(cache=True, fastmath=SUM_FLAGS)
def _solve(w, piv, jac, hg, n_r, x, blk):
    """Solve W x = b in place (``x`` holds b) with the reduced factors of :func:`_factor`."""
    m = w.shape[0]
    z = blk[10]
    if blk[0][1]:
        hx = blk[14]
        for b in range(n_r):
            hx[b] = hg * x[b]
        for a in range(m):
            acc = x[n_r + a]
            for b in range(n_r):
                acc += jac[n_r + a, b] * hx[b]
            z[a] = acc
        _solve_blocks(blk, z)
    else:
        for a in range(m):
            acc = x[n_r + a]
            for b in range(n_r):
                acc += hg * jac[n_r + a, b] * x[b]
            z[a] = acc
        lu_solve(w, piv, z)
    for i in range(n_r):
        x[i] = hg * (x[i] + z[i])
    for a in range(m):
        x[n_r + a] = z[a]


@njit(cache=True, fastmath=SUM_FLAGS)
def _solve_blocks(blk, z):
    """R x = z in place with the block factors of :func:`_factor_blocks`: t_b = D_b⁻¹ z_b, S x_d = z_d − Σ_b
    R[dense, ring_b] t_b, x_b = t_b − G_b x_d."""
    _, ring, dense, dlu, dpiv, g, nz, nnz, s, spiv, _, tb, rd, bmat, _ = blk
    d = dense.size
    for b in range(2):
        for k in range(5):
            tb[b, k] = z[ring[b, k]]
        lu_solve(dlu[b], dpiv[b], tb[b])
    for i in range(d):
        acc = z[dense[i]]
        for k in range(5):
            acc -= bmat[i, k] * tb[0, k] + bmat[i, 5 + k] * tb[1, k]
        rd[i] = acc
    lu_solve(s, spiv, rd)
    for i in range(d):
        z[dense[i]] = rd[i]
    for b in range(2):
        for k in range(5):
            acc = tb[b, k]
            for c in range(nnz[b]):
                acc -= g[b, c, k] * rd[nz[b, c]]
            z[ring[b, k]] = acc


@njit(cache=True)
def _stages(t, h, y, f0, fx, w, piv, jac, ks, coef, ynew, rhs, args, blk):
    """The six stages of one RODAS step from (t, y) with the factored W = I/(hγ) − J (``w``, ``piv`` of
    :func:`_factor`, and ``jac``): the stage vectors into ``ks``, the new solution into ``ynew`` (``ks[5]`` is the
    embedded error estimate)."""
    n = y.size
    n_r = args[2]
    hg = h * GAMMA
    # stage 1
    for i in range(n):
        ks[0, i] = f0[i] + h * D1 * fx[i]
    _solve(w, piv, jac, hg, n_r, ks[0], blk)
    # stages 2-5: y + Σ a_ij k_j, f there, + Σ (C_ij / h) k_j (+ h d_i f_t)
    for s in range(1, 6):
        if s == 1:
            coef[0] = A21
            cs, ci, di = CC2, (C21, 0.0, 0.0, 0.0, 0.0), D2
        elif s == 2:
            coef[0], coef[1] = A31, A32
            cs, ci, di = CC3, (C31, C32, 0.0, 0.0, 0.0), D3
        elif s == 3:
            coef[0], coef[1], coef[2] = A41, A42, A43
            cs, ci, di = CC4, (C41, C42, C43, 0.0, 0.0), D4
        elif s == 4:
            coef[0], coef[1], coef[2], coef[3] = A51, A52, A53, A54
            cs, ci, di = 1.0, (C51, C52, C53, C54, 0.0), 0.0
        else:  # s == 5: the embedded stage on y_new = stage-5 point + k5
            cs, ci, di = 1.0, (C61, C62, C63, C64, C65), 0.0
        if s < 5:
            _stage(y, coef, ks, s, ynew)
        else:
            for i in range(n):
                ynew[i] += ks[4, i]
        monolithic_rhs(t + cs * h, ynew, rhs, *args)
        for i in range(n):
            acc = rhs[i] + h * di * fx[i]
            for j in range(s):
                acc += ci[j] / h * ks[j, i]
            ks[s, i] = acc
        _solve(w, piv, jac, hg, n_r, ks[s], blk)
    for i in range(n):
        ynew[i] += ks[5, i]


@njit(cache=True)
def _stages5(t, h, y, f0, fx, w, piv, jac, ks, ynew, rhs, args, blk):
    """The eight stages of one Rodas5P step (:data:`A5`, :data:`C5`, ...), as :func:`_stages` (``ks`` (8, n),
    ``ks[7]`` the embedded error estimate)."""
    n = y.size
    n_r = args[2]
    hg = h * GAMMA5
    for i in range(n):
        ks[0, i] = f0[i] + h * D5[0] * fx[i]
    _solve(w, piv, jac, hg, n_r, ks[0], blk)
    for s in range(1, 8):
        if s < 6:  # y + Σ a_sj k_j
            for i in range(n):
                acc = y[i]
                for j in range(s):
                    acc += A5[s - 1, j] * ks[j, i]
                ynew[i] = acc
        else:  # stages 7, 8: the previous stage's point + its increment
            for i in range(n):
                ynew[i] += ks[s - 1, i]
        monolithic_rhs(t + CC5[s] * h, ynew, rhs, *args)
        for i in range(n):
            acc = rhs[i] + h * D5[s] * fx[i]
            for j in range(s):
                acc += C5[s - 1, j] / h * ks[j, i]
            ks[s, i] = acc
        _solve(w, piv, jac, hg, n_r, ks[s], blk)
    for i in range(n):
        ynew[i] += ks[7, i]


@njit(cache=True, fastmath=SUM_FLAGS)
def _dense_output5(t, h, y, ynew, ks, t_eval, k_out, out):
    """Continuous output (order 4) of a Rodas5P step, as :func:`_dense_output`."""
    n = y.size
    while k_out < t_eval.size and t_eval[k_out] <= t + h * (1 + 1e-12):
        th = (t_eval[k_out] - t) / h
        for i in range(n):
            k1, k2, k3 = 0.0, 0.0, 0.0
            for j in range(8):
                k1 += H5[0, j] * ks[j, i]
                k2 += H5[1, j] * ks[j, i]
                k3 += H5[2, j] * ks[j, i]
            out[k_out, i] = y[i] + th * ((ynew[i] - y[i]) + (1 - th) * (k1 + th * (k2 + th * k3)))
        k_out += 1
    return k_out


@njit(cache=True, fastmath=SUM_FLAGS)
def _dense_output(t, h, y, ynew, ks, t_eval, k_out, out):
    """Continuous output (order 3) of the step (t, y) -> (t + h, ynew) at the output times inside (t, t + h], from
    ``t_eval[k_out]`` on, into ``out``; returns the next output index."""
    n = y.size
    while k_out < t_eval.size and t_eval[k_out] <= t + h * (1 + 1e-12):
        th = (t_eval[k_out] - t) / h
        for i in range(n):
            k2 = H21 * ks[0, i] + H22 * ks[1, i] + H23 * ks[2, i] + H24 * ks[3, i] + H25 * ks[4, i]
            k3 = H31 * ks[0, i] + H32 * ks[1, i] + H33 * ks[2, i] + H34 * ks[3, i] + H35 * ks[4, i]
            out[k_out, i] = y[i] + th * ((ynew[i] - y[i]) + (1 - th) * (k2 + th * k3))
        k_out += 1
    return k_out


@njit(cache=True, nogil=True)  # the shooting flows integrate monodromy columns in threads
def rodas_chunk(y0, t_eval, h, rtol, atol, scale, cols, max_steps, max_step, args, modal, method=RODAS4_FAST):
    """Integrate from t_eval[0] through the times t_eval with RODAS (see the module docstring); ``method``
    :data:`RODAS4_FAST` (default): RODAS with each film's Jacobian columns differenced alone
    (:func:`_bearing_columns_films`) and the ring blocks eliminated before the LU (:func:`_factor_blocks`), the same
    method at 0.84 of the cost per step (benchmarks/default_convergence.py); :data:`RODAS4`: plain RODAS;
    :data:`RODAS5P`: Rodas5P (8 stages, order 5(4): fewer steps at tight tolerances, as many at the run-up's
    defaults).

    Returns (states at t_eval (k, n), number of rows filled, next step size [s], steps, rejected steps, status:
    0 done, 1 step budget exhausted, 2 step size underflow, 3 singular matrix, 4 a torque-driven speed out of
    range, :data:`OMEGA_MAX`)."""
    n = y0.size
    n_r = args[2]
    out = np.empty((t_eval.size, n))
    out[0] = y0
    five = method == RODAS5P
    gamma, expo, last = (GAMMA5, -0.2, 7) if five else (GAMMA, -0.25, 5)
    ks = np.zeros((8 if five else 6, n))
    f0, fx, work, yp, ynew, rhs = (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n))
    jac = np.empty((n, n))
    w = np.empty((n - n_r, n - n_r))
    piv = np.empty(n - n_r, dtype=np.int64)
    blk = block_workspace(n, n_r, method == RODAS4_FAST)
    coef = np.zeros(5)
    y = y0.copy()
    t = t_eval[0]
    k_out, steps, rejected, status = 1, 0, 0, 0
    t_end = t_eval[-1]
    need_jac = True
    while k_out < t_eval.size:
        if steps >= max_steps:
            status = 1
            break
        h = min(h, t_end - t, max_step)
        if h < 1e-14 * max(abs(t), 1e-3):
            status = 2
            break
        if need_jac:
            monolithic_rhs(t, y, f0, *args)
            omega, omega_dot = _omegas(t, y, f0, n_r, args)
            jacobian(t, y, f0, jac, work, yp, cols, scale, omega, omega_dot, args, method == RODAS4_FAST)
            dt = 1e-7 * max(h, 1e-9)
            monolithic_rhs(t + dt, y, work, *args)
            for i in range(n):
                fx[i] = (work[i] - f0[i]) / dt
            need_jac = False
        if not _factor(jac, h * gamma, n_r, w, piv, blk):
            status = 3
            break
        if five:
            _stages5(t, h, y, f0, fx, w, piv, jac, ks, ynew, rhs, args, blk)
        else:
            _stages(t, h, y, f0, fx, w, piv, jac, ks, coef, ynew, rhs, args, blk)
        err = _error_norm(ks[last], y, ynew, rtol, atol, modal)
        steps += 1
        if not (err <= 1.0):  # rejected (also NaN)
            rejected += 1
            h *= max(0.2, 0.9 * err ** expo) if err == err else 0.25
            continue
        if five:
            k_out = _dense_output5(t, h, y, ynew, ks, t_eval, k_out, out)
        else:
            k_out = _dense_output(t, h, y, ynew, ks, t_eval, k_out, out)
        t += h
        for i in range(n):
            y[i] = ynew[i]
        if n > 2 * n_r + 11 and not 0.0 < y[n - 1] <= OMEGA_MAX:  # torque-driven: the speed is the last state
            status = 4
            break
        need_jac = True
        h *= min(5.0, max(0.2, 0.9 * max(err, 1e-10) ** expo))
    return out, k_out, h, steps, rejected, status
