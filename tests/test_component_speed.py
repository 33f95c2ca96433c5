"""The co-simulation's fused per-step paths (issue #13 item 2) compute what the former step sequences computed.

- ``BearingComponent.exchange`` (one compiled call) = force, interface Jacobian and losses evaluated one by one with
  the public kernels, bit for bit;
- ``BearingComponent.step`` (one compiled ring step, LU factors of the Newton matrix reused) = the former ring
  integration written out here (the same SDIRK stages and modified Newton with ``np.linalg.solve`` per iteration);
- ``RotorComponent.step_coupled`` (packed bearing inputs, one compiled step) = the former trapezoidal step written
  out here with numpy, and = ``RotorComponent.step`` with the same inputs as lists, bit for bit;
- the FMU slaves' array fast paths (inputs set by one index array, outputs read from per-step blocks) give what
  their per-variable paths give, bit for bit (slaves instantiated in this process, no FMU build).
"""
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from pythonfmu import Real

import frbmodel as frb
from frbmodel.nonlinear.components import (
    COUPLING_COLUMNS,
    EXCHANGE_OUTPUTS,
    SDIRK_GAMMA,
    BearingComponent,
    RotorComponent,
    ramp_speed,
)
from frbmodel.physics.bearing import ring_rhs_kernel
from frbmodel.physics.dynamics import add_unbalance_forces
from frbmodel.physics.losses import bearing_loss_kernel

EPS = np.finfo(float).eps
FMU_SRC = Path(__file__).resolve().parents[1] / "fmu_src"


def _whirl(rpm=150e3, radius=10e-6, hz=400.0):
    """The turbine bearing at its method-J equilibrium and a journal whirling around it (a developed whirl)."""
    tc = frb.turbocharger(36e-6)
    eq = frb.equilibrium(tc, "J", rpm).bearings[0]
    bc = BearingComponent(tc.bearings[0], tc.film_model)
    bc.ring[:] = [eq.ring[0], eq.ring[1], 0.0, 0.0, eq.ring_speed]
    w = 2 * math.pi * hz

    def journal(t):
        return np.array([eq.journal[0] + radius * math.cos(w * t), eq.journal[1] + radius * math.sin(w * t),
                         -radius * w * math.sin(w * t), radius * w * math.cos(w * t)])

    return bc, journal, rpm * math.pi / 30


def _exchange_one_by_one(bc, j, w):
    """Force and ε (uncapped), K and C by central differences (ε capped at 0.999, steps 1e-7 of the inner clearance,
    times |ω| for the velocities) and the losses, each from the public kernels."""
    geom, polys, m, inertia, g = bc._args()
    d = np.empty(5)

    def force(jj, cap):
        return ring_rhs_kernel(geom, polys, m, inertia, g, jj[0], jj[1], jj[2], jj[3], bc.ring, w, cap, d)

    fx, fy, ei, eo = force(j, math.inf)
    jac = np.zeros((2, 4))
    for k in range(4):
        h = 1e-7 * geom[0, 2] * (1.0 if k < 2 else max(abs(w), 1.0))
        jp, jm = j.copy(), j.copy()
        jp[k] += h
        jm[k] -= h
        fp, fm = force(jp, 0.999), force(jm, 0.999)
        jac[:, k] = -(np.array(fp[:2]) - np.array(fm[:2])) / (2 * h)
    tj, p_in, p_out = bearing_loss_kernel(geom, polys, j[0], j[1], j[2], j[3], bc.ring, w, math.inf)
    return np.r_[fx, fy, jac[:, :2].ravel(), jac[:, 2:].ravel(), ei, eo, tj, p_in + p_out]


def test_bearing_exchange_is_force_jacobian_and_losses_bit_for_bit():
    bc, journal, w = _whirl()
    for t in (0.0, 3e-4, 7e-4):
        j = journal(t)
        out = bc.exchange(j, w)
        assert out.shape == (len(EXCHANGE_OUTPUTS),)
        # the same kernels with the same arguments and the same arithmetic: equal to the last bit
        np.testing.assert_array_equal(out, _exchange_one_by_one(bc, j, w))
        assert bc.eps == (out[10], out[11])
        force, K, C, eps = bc.outputs(j, w)
        np.testing.assert_array_equal(np.r_[force, K.ravel(), C.ravel()], out[:10])
        assert bc.losses(j, w) == (out[12], out[13])


def _former_ring_step(bc, j, a, w, H):
    """The ring step written out in Python (as before the fused kernel): SDIRK substeps, each stage by modified
    Newton with the FD Jacobian of the step's first stage (refreshed from the 5th iteration on) and a dense solve per
    iteration, started from the predictors (stage 1: y + γh f at the last substep's end; stage 2: y + h k1)."""
    args = bc._args()
    c_o = bc.bearing.outer.clearance
    g = SDIRK_GAMMA
    n_sub = max(1, math.ceil(H / bc.substep - 1e-9))
    h = H / n_sub
    f = np.empty(5)
    jac = [None]

    def path(t):
        return (j[0] + j[2] * t + 0.5 * a[0] * t * t, j[1] + j[3] * t + 0.5 * a[1] * t * t, j[2] + a[0] * t,
                j[3] + a[1] * t)

    def rhs(jj, y, out):
        return ring_rhs_kernel(*args, *jj, y, w, 0.999, out)

    def stage(jj, base, yn, refresh):
        for it in range(12):
            _, _, ei, eo = rhs(jj, yn, f)
            r = yn - base - g * h * f
            if refresh or it >= 4:
                jac[0] = np.empty((5, 5))
                for k in range(5):
                    d = 1e-7 * max(abs(yn[k]), c_o if k < 2 else (c_o * 1e3 if k < 4 else 10.0))
                    yp, fp = yn.copy(), np.empty(5)
                    yp[k] += d
                    rhs(jj, yp, fp)
                    jac[0][:, k] = np.eye(5)[:, k] - g * h * (fp - f) / d
                refresh = False
            dy = np.linalg.solve(jac[0], -r)
            yn += dy
            if abs(dy[0]) + abs(dy[1]) < 1e-10 * c_o and abs(dy[4]) < 1e-9 * max(abs(yn[4]), 1.0):
                return max(ei, eo)
        raise AssertionError("the former Newton iteration did not converge")

    y, eps, k_end = bc.ring.copy(), 0.0, np.zeros(5)
    for s in range(n_sub):
        y1 = y + g * h * k_end  # predictor: the last substep's end derivative (zero in the first substep)
        eps = max(eps, stage(path((s + g) * h), y, y1, s == 0))
        base = y + (1.0 - g) / g * (y1 - y)
        y2 = y + (y1 - y) / g  # predictor: y + h k1, k1 the first stage's slope
        eps = max(eps, stage(path((s + 1) * h), base, y2, False))
        k_end = (y2 - base) / (g * h)  # stiffly accurate: f(Y2)
        y = y2
    fx, fy, _, _ = rhs(path(H), y, f)
    return y, np.array([fx, fy]), eps


def test_bearing_step_is_the_former_ring_integration():
    """Five macro steps of 10 µs along the whirl (journal path from the history after the first): each from the
    same ring state as the written-out former integration. Tolerance 1e-12 of the scales (outer clearance c_o,
    c_o ω, ω_FR): the two differ only in how the Newton matrix is solved (LU factors kept over the iterations vs
    LAPACK's solve each time), i.e. in round-off of the corrections, which modified Newton contracts (measured
    <= 3e-16 over 3000 steps of the main job); any change of stages, iterations or Jacobian would show at the
    Newton tolerance, 1e-10 c_o, a hundred times above."""
    bc, journal, w = _whirl()
    H = 1e-5
    c_o = bc.bearing.outer.clearance
    scale = np.array([c_o, c_o, c_o * w, c_o * w, abs(bc.ring[4])])
    for k in range(5):
        t = k * H
        j = journal(t)
        a = bc.history.acceleration(t, j, H)
        ring, force_end, eps = _former_ring_step(bc, j, a, w, H)
        assert bc.step(j, w, 0.0, H, t=t) == pytest.approx(eps, rel=1e-12)
        np.testing.assert_array_less(np.abs(bc.ring - ring), 1e-12 * scale)
        np.testing.assert_allclose(bc.force_end, force_end, rtol=0, atol=1e-12 * np.abs(force_end).max())
        np.testing.assert_array_equal(bc.path_accel, a)
    assert k == 4 and np.abs(a).max() > 0  # the later steps ran on a curved path


def _former_rotor_step(rot, H, coupling, w0, wd):
    """The trapezoidal rotor step as it was before the fused kernel, with numpy: bearing force model
    f_b = fb + fbr τ − K x − C v, supports added to M⁻¹K and M⁻¹C, the velocity at the step end by a dense solve.
    Returns the new state, the angle and the condition numbers of the solved matrices."""
    minv, minv_k, minv_g = rot.eom
    n, nb = rot.n, coupling.shape[0]
    f0, f1, acc = coupling[:, 0:2], coupling[:, 14:16], coupling[:, 16:18]
    K, C = coupling[:, 2:6].reshape(nb, 2, 2), coupling[:, 6:10].reshape(nb, 2, 2)
    ref = coupling[:, 10:14]
    fb = f0 + np.einsum("bik,bk->bi", K, ref[:, :2]) + np.einsum("bik,bk->bi", C, ref[:, 2:])
    fbr = (f1 - f0) / H + np.einsum("bik,bk->bi", K, ref[:, 2:] + 0.5 * H * acc) + np.einsum("bik,bk->bi", C, acc)
    mk, mc = minv_k.copy(), np.zeros((n, n))
    for b, dofs in enumerate(rot.jdofs):
        for i in range(2):
            for k in range(2):
                mk[:, dofs[k]] += minv[:, dofs[i]] * K[b, i, k]
                mc[:, dofs[k]] += minv[:, dofs[i]] * C[b, i, k]

    def forcing(tau, phi, w):
        f = rot.f_grav.copy()
        for b, dofs in enumerate(rot.jdofs):
            f[dofs] += fb[b] + fbr[b] * tau
        add_unbalance_forces(f, phi, w, wd, rot.unb_node, rot.unb_me, rot.unb_phase)
        return f

    n_sub = max(1, math.ceil(H / rot.substep - 1e-9))
    h = H / n_sub
    q, v, ph, conds = rot.y[:n].copy(), rot.y[n:].copy(), rot.phi, []
    for s in range(n_sub):
        wa, wb = w0 + wd * s * h, w0 + wd * (s + 1) * h
        phb = ph + 0.5 * h * (wa + wb)
        a0 = minv @ forcing(s * h, ph, wa) - (mk + wd * minv_g) @ q - (wa * minv_g + mc) @ v
        stiff, damp = mk + wd * minv_g, mc + wb * minv_g
        rhs = v + 0.5 * h * a0 + 0.5 * h * (minv @ forcing((s + 1) * h, phb, wb) - stiff @ (q + 0.5 * h * v))
        lhs = np.eye(n) + 0.5 * h * damp + 0.25 * h * h * stiff
        conds.append(np.linalg.cond(lhs))
        v1 = np.linalg.solve(lhs, rhs)
        q, v, ph = q + 0.5 * h * (v + v1), v1, phb
    return np.r_[q, v], ph, max(conds)


def _coupling(tc, rng, journals):
    """Bearing inputs of the size of the main job's (film stiffness ~1e6 N/m, damping ~1e2 N s/m, forces ~1 N,
    path accelerations ~1e2 m/s²), at the journal states ``journals``."""
    nb = len(tc.bearings)
    c = np.empty((nb, len(COUPLING_COLUMNS)))
    c[:, 0:2] = rng.normal(0.0, 1.0, (nb, 2))
    c[:, 2:6] = 1e6 * (np.eye(2).ravel() + 0.3 * rng.normal(size=(nb, 4)))
    c[:, 6:10] = 1e2 * (np.eye(2).ravel() + 0.3 * rng.normal(size=(nb, 4)))
    c[:, 10:14] = journals
    c[:, 14:16] = c[:, 0:2] + 0.1 * rng.normal(size=(nb, 2))
    c[:, 16:18] = 1e2 * rng.normal(size=(nb, 2))
    return c


def test_rotor_step_is_the_former_trapezoidal_step():
    """Ten 10 µs steps of the ramp-driven rotor with an unbalance and a whirl-sized initial state, each from the
    same state as the written-out former step. Tolerance 100 cond(A) eps of the largest displacement and velocity:
    the two solve the same step matrix A = I + h/2 D + h²/4 S by different LU codes, whose solutions differ by round-off
    times its condition number (both use partial pivoting)."""
    tc = frb.turbocharger(36e-6)
    unbalance = [frb.Unbalance("turbine_wheel", 1e-7, 0.3)]
    rot = RotorComponent(tc, ramp_speed(50e3, 250e3, 1.0), unbalance)
    rng = np.random.default_rng(1)
    rot.y[:] = 1e-6 * rng.normal(size=rot.y.size)
    rot.y[rot.n:] *= 1e4  # velocities of a few-kHz whirl
    H = 1e-5
    for _ in range(10):
        coupling = _coupling(tc, rng, np.array([rot.journal(b) for b in range(len(tc.bearings))]))
        w0, wd = rot.current_speed()
        want, phi, cond = _former_rotor_step(rot, H, coupling, w0, wd)
        twin = RotorComponent(tc, rot.speed, unbalance)
        twin.set_state(rot.state())
        rot.step_coupled(H, coupling)
        tol = 100 * cond * EPS
        n = rot.n
        assert np.abs(rot.y[:n] - want[:n]).max() <= tol * np.abs(want[:n]).max()
        assert np.abs(rot.y[n:] - want[n:]).max() <= tol * np.abs(want[n:]).max()
        assert rot.phi == pytest.approx(phi, rel=1e-15)  # the same sums of the same speeds
        # the list API packs the same inputs: the same kernel, bit for bit
        nb = coupling.shape[0]
        twin.step(H, coupling[:, 0:2], coupling[:, 2:6].reshape(nb, 2, 2), coupling[:, 6:10].reshape(nb, 2, 2),
                  coupling[:, 10:14], path=(coupling[:, 14:16], coupling[:, 16:18]))
        np.testing.assert_array_equal(twin.y, rot.y)
        assert twin.phi == rot.phi
    assert cond > 1.0


# ----------------------------------------------------------------------------------------- FMU slaves in-process
def _slave_classes():
    """The slave classes of fmu_src/, imported under private module names (the helper module ``_fmu_common`` is
    taken out of sys.modules again, so FMUs loaded later in this process import their own bundled copy)."""
    sys.path.insert(0, str(FMU_SRC))
    had = "_fmu_common" in sys.modules
    try:
        classes = []
        for name in ("FloatingRingBearing", "TurbochargerRotor"):
            spec = importlib.util.spec_from_file_location(f"_frb_test_slave_{name}", FMU_SRC / f"{name}.py")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            classes.append(getattr(module, name))
        return classes
    finally:
        sys.path.remove(str(FMU_SRC))
        if not had:
            sys.modules.pop("_fmu_common", None)


def _start(slave, params, inputs):
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave._set_each([vr[k] for k in params], list(params.values()), Real)
    slave.set_real([vr[k] for k in inputs], list(inputs.values()))
    slave.exit_initialization_mode()
    assert slave._mode == "step mode"
    return vr


def _real_outputs(slave):
    """Value references of the Real outputs but the linearization matrices A_i_j, B_i_j, C_i_j, D_i_j."""
    return [v.value_reference for v in slave.vars.values() if v.causality.name == "output" and isinstance(v, Real)
            and not (v.name[0] in "ABCD" and v.name[1] == "_")]


def test_slave_fast_paths_read_what_the_per_variable_paths_read():
    bearing_cls, rotor_cls = _slave_classes()
    tc = frb.turbocharger(36e-6)
    eq = frb.equilibrium(tc, "J", 60e3).bearings[0]
    w = 60e3 * math.pi / 30
    b = bearing_cls(instance_name="turbine", resources=None)
    vr = _start(b, {"ring.x0": eq.ring[0], "ring.y0": eq.ring[1], "ring.speed0": eq.ring_speed},
                {"journal.x": eq.journal[0], "journal.y": eq.journal[1], "rotor_speed": w})
    outs = _real_outputs(b)
    assert len(outs) == 29  # every Real output but the linearization (26 + the 3 thermal outputs of #25)
    names = {v: k for k, v in vr.items()}
    for k in range(3):
        j = [eq.journal[0] + 1e-6 * k, eq.journal[1], 1e-3, -2e-3 * k]
        b.set_real([vr[f"journal.{q}"] for q in ("x", "y", "vx", "vy")] + [vr["rotor_speed"]], j + [w])
        fast = b.get_real(outs)
        np.testing.assert_array_equal(fast, b._get_each(outs, Real, math.nan))
        for one in outs:  # each alone, through its own one-value plan
            assert b.get_real([one]) == [fast[outs.index(one)]], names[one]
        assert b.do_step(k * 1e-5, 1e-5)
        np.testing.assert_array_equal(b.get_real(outs[::-1]), b._get_each(outs[::-1], Real,
                                                                           math.nan))
    rot = rotor_cls(instance_name="rotor", resources=None)
    vr = _start(rot, {"speed_start": w}, {f"{n}_bearing.stiffness.{i}{i}": 1e6 for n in ("turbine", "compressor")
                                          for i in "xy"})
    outs = _real_outputs(rot)
    inputs = [v for k, v in vr.items() if rot.vars[v].causality.name == "input"]
    rng = np.random.default_rng(2)
    for k in range(3):
        values = list(rng.normal(size=len(inputs)) * 1e-3)
        for n in ("turbine", "compressor"):  # supported by springs and dampers, so that the steps stay bounded
            for i in "xy":
                values[inputs.index(vr[f"{n}_bearing.stiffness.{i}{i}"])] = 1e6
                values[inputs.index(vr[f"{n}_bearing.damping.{i}{i}"])] = 1e2
        values[inputs.index(vr["speed_in"])] = abs(values[inputs.index(vr["speed_in"])])  # its range: >= 0
        rot.set_real(inputs, values)
        assert [rot.vars[v].getter() for v in inputs] == values  # the array assignment stored every value
        assert rot.do_step(k * 1e-5, 1e-5)
        np.testing.assert_array_equal(rot.get_real(outs), rot._get_each(outs, Real, math.nan))
