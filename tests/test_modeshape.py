"""Mode shapes (issue 12 item 3): eigenvector components, wheel phases of conical/cylindrical modes, Hermite lines."""

import math

import numpy as np
import pytest
import scipy.linalg as sla

import frbmodel as frb
from frbmodel.linear.modeshape import ModeShape, save_mode_shapes

SPEED = 100e3  # [rpm], below the outer films' onsets and past the inner ones': a few unstable J modes


@pytest.fixture(scope="module")
def tc():
    return frb.turbocharger()


@pytest.fixture(scope="module")
def cd_j(tc):
    return frb.campbell(tc, "J", [SPEED], whirl=False)


@pytest.fixture(scope="module")
def cd_a(tc):
    return frb.campbell(tc, "A", [30e3], whirl=False)


def _reference_modes(M, C, K):
    """Independent eigen-solve: the generalized first-order problem [[I,0],[0,M]] s' = [[0,I],[-K,-C]] s."""
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
    lam, vec = sla.eig(A, B)
    return lam, vec[:n]


def _major(a, b):
    """Semi-major axis of x = Re(a e^{iφ}), y = Re(b e^{iφ}): sqrt of the largest eigenvalue of Re(q q^H)."""
    q = np.array([a, b])
    return math.sqrt(np.linalg.eigvalsh(np.real(np.outer(q, np.conj(q))))[-1])


def test_node_amplitudes_equal_eigenvector_components(tc, cd_j):
    ls = frb.linear_system(tc, "J", SPEED)
    lam_ref, vec_ref = _reference_modes(ls.M, ls.C, ls.K)
    nn = tc.rotor.n_nodes
    for mode in range(4):
        ms = cd_j.mode_shape(SPEED, mode)
        k = int(np.argmin(np.abs(lam_ref - ms.eigenvalue)))
        # same system, two eigen-solvers: eigenvalues agree to round-off (|λ| ~ 1e3..1e4 1/s, κ modest)
        assert abs(lam_ref[k] - ms.eigenvalue) < 1e-7 * abs(lam_ref[k])
        ref = vec_ref[:, k]
        orbits = [(ref[4 * i], ref[4 * i + 1]) for i in range(nn)] + [(ref[a], ref[b]) for a, b in ls.ring_dofs]
        ref = ref / max(_major(a, b) for a, b in orbits)       # normalised: largest orbit semi-major axis 1
        c = np.vdot(ref, ms.shape) / np.vdot(ref, ref)         # the remaining freedom: a unit phase factor
        # two eigen-solvers on a non-normal (damped, gyroscopic) system: measured eigenvector differences ~1e-8 of
        # the largest component (eigenvalues ~3e-9 apart); 1e-6 leaves margin and still catches any wrong component
        tol = 1e-6 * np.abs(ms.shape).max()
        assert abs(abs(c) - 1.0) < 1e-6
        assert np.allclose(ms.shape, c * ref, atol=tol, rtol=0)
        df = ms.to_dataframe()
        nodes = df[df["item"].str.startswith("node")]
        u = c * ref
        # the table (and the plotted node deflection, below) are the eigenvector's components
        assert np.allclose(nodes["|x| [-]"], np.abs(u[0:4 * nn:4]), atol=tol)
        assert np.allclose(nodes["|y| [-]"], np.abs(u[1:4 * nn:4]), atol=tol)
        dphi = np.angle(np.exp(1j * (np.radians(nodes["phase x [deg]"]) - np.angle(u[0:4 * nn:4]))))
        big = np.abs(u[0:4 * nn:4]) > 1e-3                      # phase of a vanishing component is noise
        assert np.all(np.abs(dphi[big]) < tol / 1e-3)           # angle error <= abs error / amplitude (>= 1e-3)
        for phi in (0.0, 1.0, 2.5):
            x, y = ms.deflection(tc.rotor.node_z, phi)
            assert np.allclose(x, np.real(u[0:4 * nn:4] * np.exp(1j * phi)), atol=tol)
            assert np.allclose(y, np.real(u[1:4 * nn:4] * np.exp(1j * phi)), atol=tol)
        assert ms.to_dataframe()["major [-]"].max() == pytest.approx(1.0, abs=1e-12)


def _wheel_phase_deg(ms):
    """Phase of the compressor wheel's dominant whirl component relative to the turbine wheel's [deg]."""
    v, w, _, _ = ms.node_dofs()
    a, b = ms.discs["turbine_wheel"], ms.discs["compressor_wheel"]
    rf = 0.5 * (v + 1j * w)
    return math.degrees(abs(np.angle(rf[b] * np.conj(rf[a]))))


def test_conical_counter_phase_cylindrical_in_phase(cd_a):
    kinds = list(zip(cd_a.precession[0], cd_a.mode_kind[0]))
    conical = kinds.index(("forward", "conical"))
    cylindrical = kinds.index(("forward", "cylindrical"))
    # method A has no damping: the isotropic modes are planar-real times a circle, phases exact to round-off
    assert _wheel_phase_deg(cd_a.mode_shape(30e3, conical)) == pytest.approx(180.0, abs=1e-6)
    assert _wheel_phase_deg(cd_a.mode_shape(30e3, cylindrical)) == pytest.approx(0.0, abs=1e-6)


def test_damped_conical_wheels_roughly_counter_phase(cd_j):
    """Method J: damping makes the shapes complex, but a conical forward mode keeps the wheels > 90° apart."""
    j = [i for i in range(cd_j.n_modes)
         if (cd_j.precession[0, i], cd_j.mode_kind[0, i]) == ("forward", "conical")][0]
    assert _wheel_phase_deg(cd_j.mode_shape(SPEED, j)) > 90.0


def _synthetic(node_z, fx, dfx, fy, dfy):
    nn = len(node_z)
    u = np.zeros(4 * nn, dtype=complex)
    u[0::4], u[1::4] = fx(node_z), fy(node_z)
    u[3::4], u[2::4] = dfx(node_z), -dfy(node_z)              # θy = +∂v/∂z, θx = −∂w/∂z (frbmodel.system.rotor)
    return ModeShape("A", 0.0, 0, 1j, u, np.asarray(node_z, dtype=float), {}, {})


def test_hermite_reproduces_cubics_values_and_slopes():
    z = np.array([0.0, 0.02, 0.05, 0.11])                      # unequal elements
    fx = lambda s: 1 + 40 * s - 900 * s**2 + 5e3 * s**3       # noqa: E731
    dfx = lambda s: 40 - 1800 * s + 1.5e4 * s**2              # noqa: E731
    fy = lambda s: (2 - 30 * s + 1e4 * s**3) * 1j             # noqa: E731  (y a quarter period later)
    dfy = lambda s: (-30 + 3e4 * s**2) * 1j                   # noqa: E731
    ms = _synthetic(z, fx, dfx, fy, dfy)
    zz = np.linspace(0.0, z[-1], 301)
    xc, yc = ms.complex_deflection(zz)
    # Hermite cubics are exact for cubic fields: equality to round-off everywhere, nodes included
    assert np.allclose(xc, fx(zz), atol=1e-12) and np.allclose(yc, fy(zz), atol=1e-12)
    h = 1e-7                                                   # central difference: error ~ h² f''' ~ 1e-10
    for zi in z[1:-1]:
        sx = (ms.complex_deflection(zi + h)[0] - ms.complex_deflection(zi - h)[0]) / (2 * h)
        sy = (ms.complex_deflection(zi + h)[1] - ms.complex_deflection(zi - h)[1]) / (2 * h)
        assert abs(sx[0] - dfx(zi)) < 1e-5 and abs(sy[0] - dfy(zi)) < 1e-5


def test_save_mode_shapes_files(cd_a, tmp_path):
    import pandas as pd

    paths = save_mode_shapes(cd_a, 30e3, tmp_path, fmax_hz=400.0)
    assert [p.name for p in paths] == [f"mode_shapes_A_30000{s}" for s in (".png", ".html", ".csv")]
    df = pd.read_csv(paths[2])
    assert sorted(df["mode"].unique()) == [j for j in range(cd_a.n_modes) if cd_a.frequencies_hz[0, j] <= 400.0]


def test_cli_campbell_mode_shapes(tmp_path):
    from frbmodel.cli import main

    main(["campbell", "--method", "A", "--speeds", "20000,30000", "--no-whirl", "--fmax", "400", "--mode-shapes",
          "30000", "--out", str(tmp_path)])
    for suffix in (".png", ".html", ".csv"):
        assert (tmp_path / f"mode_shapes_A_30000{suffix}").stat().st_size > 0
