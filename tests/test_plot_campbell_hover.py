"""Campbell HTML: the hover text of every point lists its mode shape (orbit semi-major axis, phase of x, whirl
direction per disc, journal and ring) — checked against an independent eigen-solve of the same linear system."""
import dataclasses
import re

import numpy as np
import pytest
import scipy.linalg as sla

import frbmodel as frb
from frbmodel.linear.assembly import linear_system

LINE = re.compile(r"^(.+): (-?[\d.]+) ∠ (-?\d+)° (fwd|bwd)$")
PHI = np.linspace(0.0, 2 * np.pi, 721)  # orbit sampled every 0.5°


def _hover_points(fig):
    """(speed [rpm], mode, {label: (amplitude, phase x [deg], direction)}) of every marker of the figure."""
    out = []
    for tr in fig.data:
        if tr.mode != "markers" or tr.text is None:
            continue
        for x, cdata, text in zip(tr.x, tr.customdata, tr.text):
            lines = [LINE.match(s) for s in text.split("<br>")]
            assert all(lines), text
            out.append((float(x), int(cdata[1]), {m[1]: (float(m[2]), float(m[3]), m[4]) for m in lines}))
    return out


def _reference_orbits(ls, lam):
    """Independent: eigenvector of λ from scipy's generalized first-order problem; each place's orbit
    x = Re(a e^{iφ}), y = Re(b e^{iφ}) sampled: semi-major axis (largest radius), turning sense (signed area)."""
    n = ls.M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-ls.K, -ls.C]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), ls.M]])
    w, v = sla.eig(A, B)
    u = v[:n, np.argmin(np.abs(w - lam))]

    def orbit(ix, iy):
        x, y = np.real(u[ix] * np.exp(1j * PHI)), np.real(u[iy] * np.exp(1j * PHI))
        area = np.sum(x[:-1] * np.diff(y) - y[:-1] * np.diff(x))
        return np.hypot(x, y).max(), u[ix], area > 0

    n_nodes = (n - 2 * len(ls.ring_dofs or [])) // 4
    places = [(4 * i, 4 * i + 1) for i in range(n_nodes)] + list(ls.ring_dofs or [])
    largest = max(orbit(ix, iy)[0] for ix, iy in places)  # the mode's largest orbit (rotor nodes and rings)
    return orbit, largest


def _places(tc, ring_dofs):
    out = {d.name: (4 * d.node, 4 * d.node + 1) for d in tc.rotor.discs}
    for k, b in enumerate(tc.bearings):
        out[f"{b.name} journal"] = (4 * b.node, 4 * b.node + 1)
        if ring_dofs:
            out[f"{b.name} ring"] = tuple(ring_dofs[k])
    return out


@pytest.mark.parametrize("method,speeds", [("A", [30e3, 60e3]), ("J", [50e3, 150e3])])
def test_hover_shape_equals_an_independent_eigenvector(method, speeds):
    tc = frb.turbocharger()
    cd = frb.campbell(tc, method, speeds, whirl=False)
    points = _hover_points(cd.plot_html(fmax_hz=3000.0, whirl=False))
    assert len(points) == np.sum(np.isfinite(cd.frequencies_hz) & (cd.frequencies_hz <= 3000.0))
    for speed, j, shape in points:
        i = int(np.argmin(np.abs(cd.speeds_rpm - speed)))
        ls = linear_system(tc, method, speed)
        orbit, largest = _reference_orbits(ls, cd.eigenvalues[i, j])
        places = _places(tc, ls.ring_dofs)
        # along the shaft of the Table 2 rotor: turbine wheel (node 0), bearings (nodes 1, 2), compressor wheel
        rings = ls.ring_dofs is not None and len(ls.ring_dofs) > 0
        assert list(shape) == ["turbine_wheel", "turbine journal"] + ["turbine ring"] * rings + \
            ["compressor journal"] + ["compressor ring"] * rings + ["compressor_wheel"]
        ref = {p: orbit(*places[p]) for p in places}
        for p, (amp, _, direction) in shape.items():
            # printed with 2 decimals; the sampled maximum lies within cos(0.25°) of the true one
            assert amp == pytest.approx(ref[p][0] / largest, abs=0.005 + 1e-5)
            if amp >= 0.05:  # a visible orbit: its turning sense is well defined
                assert direction == ("fwd" if ref[p][2] else "bwd")
        # phases relative to the turbine wheel: integer degrees, each rounded by <= 0.5°
        ref_tw = ref["turbine_wheel"][1]
        for p, (amp, phase, _) in shape.items():
            if amp >= 0.05 and shape["turbine_wheel"][0] >= 0.05:
                want = np.degrees(np.angle(ref[p][1] / ref_tw))
                got = phase - shape["turbine_wheel"][1]
                assert abs((got - want + 180.0) % 360.0 - 180.0) <= 1.0 + 1e-6, (p, got, want)
        if method == "J":
            assert {"turbine ring", "compressor ring"} <= set(shape)


def test_conical_and_cylindrical_wheel_phases_in_the_hover():
    # method A at 30 krpm: a conical mode has the wheels in counter-phase, a cylindrical one in phase (rigid rotor)
    cd = frb.campbell(frb.turbocharger(), "A", [30e3], whirl=False)
    seen = set()
    for _, j, shape in _hover_points(cd.plot_html(fmax_hz=1000.0)):
        kind = cd.mode_kind[0, j]
        dphi = (shape["turbine_wheel"][1] - shape["compressor_wheel"][1]) % 360.0
        if kind == "conical":
            assert abs(dphi - 180.0) <= 1.0
        elif kind == "cylindrical":
            assert min(dphi, 360.0 - dphi) <= 1.0
        seen.add(kind)
    assert {"conical", "cylindrical"} <= seen


def test_no_system_no_shape_in_the_hover():
    cd = frb.campbell(frb.turbocharger(), "A", [30e3], whirl=False)
    fig = dataclasses.replace(cd, meta={}).plot_html()
    assert all(tr.text is None and "%{text}" not in (tr.hovertemplate or "") for tr in fig.data)
    fig = cd.plot_html(shapes=False)
    assert all(tr.text is None for tr in fig.data)
