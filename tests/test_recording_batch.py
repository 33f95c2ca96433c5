"""Run-up recording a solver call's worth of samples at a time (issue 13 item 1): the rows built in one compiled
pass (:func:`frbmodel.nonlinear.runup.sample_rows`) and appended in one call (:meth:`Recorder.extend`) are the rows the
per-sample path (:func:`frbmodel.nonlinear.runup.sample_row` + :meth:`Recorder.append`) records, bit for bit.

The reference is the per-sample code itself, applied to the same states: both evaluate the same compiled kernels
(the monolithic RHS for the film eccentricities, ``bearing_loss_kernel`` for torques and powers) on the same
inputs with the same floating-point operations, so equality is exact (no tolerance).
"""
import importlib
import json

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.core.errors import RunupStopped
from frbmodel.nonlinear.recorder import Recorder, RunupSchema
from frbmodel.nonlinear.runup import (
    MAX_SPEED_RPM,
    SpeedProfile,
    Unbalance,
    build_problem,
    initial_state,
    runup,
    sample_row,
)

RUNUP = importlib.import_module("frbmodel.nonlinear.runup")  # the module (frbmodel.nonlinear.runup is also the
# function's name)
UNBALANCE = [Unbalance("turbine_wheel", 2e-6, 0.3), Unbalance("compressor_wheel", 1e-6, 1.0)]


@pytest.fixture(scope="module")
def tc():
    return frb.turbocharger()


def per_sample_rows(problem, schema, ts, ys):
    """The former recording: one :func:`sample_row` (RHS call + losses from Python) per state."""
    buf = np.empty(problem.n_states)
    rows = [sample_row(problem, schema, float(t), y, buf) for t, y in zip(ts, ys)]
    return np.array(rows).reshape(len(rows), len(schema.columns))


def both_paths(monkeypatch, *args, **kw):
    """The result of ``runup(*args, **kw)`` recorded in batches, then per sample (and the stop message, or "")."""
    out = []
    for patch in (False, True):
        with monkeypatch.context() as m:
            if patch:
                m.setattr(RUNUP, "sample_rows", per_sample_rows)
            try:
                res, msg = runup(*args, **kw), ""
            except RunupStopped as exc:
                res, msg = exc.result, str(exc)
        out.append((res, msg))
    return out


def assert_same(a, b):
    assert a.status == b.status and a.message == b.message
    np.testing.assert_array_equal(a.to_dataframe().to_numpy(), b.to_dataframe().to_numpy())  # NaN == NaN here


def states_near(problem, n, seed):
    """n states scattered around the start state (positions within the films, any velocities)."""
    rng = np.random.default_rng(seed)
    y0 = initial_state(problem)
    return y0 + rng.normal(scale=np.maximum(np.abs(y0), 1e-6) * 0.2, size=(n, y0.size))


@pytest.mark.parametrize("profile, springs", [(SpeedProfile.ramp(20e3, 60e3, 0.01), None),
                                              (SpeedProfile.torque(3e-3, 40e3, 0.01), None),
                                              (SpeedProfile.ramp(20e3, 60e3, 0.01), 1e6)])
def test_sample_rows_equal_sample_row_bit_for_bit(tc, profile, springs):
    problem = build_problem(tc, profile, "short", UNBALANCE, springs)
    schema = RunupSchema.from_system(tc)
    ts = np.linspace(0.0, 0.01, 37)
    ys = states_near(problem, ts.size, 1)
    got = RUNUP.sample_rows(problem, schema, ts, ys)
    np.testing.assert_array_equal(got, per_sample_rows(problem, schema, ts, ys))
    assert np.isfinite(got).all() if springs is None else np.isnan(got[:, -4:]).all()
    assert RUNUP.sample_rows(problem, schema, ts[:0], ys[:0]).shape == (0, len(schema.columns))


@pytest.mark.parametrize("profile, integrator", [(SpeedProfile.ramp(20e3, 40e3, 0.02), "radau"),
                                                 (SpeedProfile.torque(3e-3, 30e3, 0.02), "radau"),
                                                 (SpeedProfile.ramp(20e3, 40e3, 0.004), "lsoda")])
def test_runup_records_the_same_rows_as_sample_by_sample(tc, monkeypatch, profile, integrator):
    duration = float(profile.t[-1])
    (a, _), (b, _) = both_paths(monkeypatch, tc, profile=profile, duration=duration, unbalance=UNBALANCE,
                                integrator=integrator)
    assert a.status == "finished" and a.time.size == round(duration * 20e3) + 1
    assert_same(a, b)


def test_contact_stops_at_the_first_offending_row_inside_a_chunk(tc, monkeypatch):
    kw = dict(profile=SpeedProfile.ramp(20e3, 40e3, 0.02), duration=0.02, unbalance=UNBALANCE)
    worst = runup(tc, **kw).eccentricity.max(axis=1)
    # contact_eps between a new record of the largest ε and the record before, at a row inside a solver call
    i = next(i for i in range(150, worst.size) if i % RUNUP.CHUNK_SAMPLES > 1 and worst[i] > worst[:i].max())
    contact_eps = 0.5 * (worst[i] + worst[:i].max())
    (a, msg), (b, msg_b) = both_paths(monkeypatch, tc, contact_eps=contact_eps, **kw)
    assert a.status == "stopped" and msg == msg_b and "eccentricity ratio" in msg
    assert a.time.size == i + 1  # rows up to and including the first with ε > contact_eps
    assert_same(a, b)


def test_torque_driven_speed_check_stops_at_the_first_row_out_of_range(tc, monkeypatch):
    # -5 N m on J_p = 1.26e-4 kg m^2 stops 3000 rpm (314 rad/s) in ~8 ms: the speed crosses 0 inside a solver call
    kw = dict(profile=SpeedProfile.torque(-5.0, 3000, 0.012), duration=0.012)
    (a, msg), (b, msg_b) = both_paths(monkeypatch, tc, **kw)
    speed = a.speed_rpm
    assert a.status == "stopped" and msg == msg_b and "left the valid range" in msg
    assert not 0.0 < speed[-1] <= MAX_SPEED_RPM and np.all((speed[:-1] > 0) & (speed[:-1] <= MAX_SPEED_RPM))
    assert (speed.size - 1) % RUNUP.CHUNK_SAMPLES != 0
    assert_same(a, b)


def test_schema_rows_place_every_value_in_its_named_column():
    schema = RunupSchema(("front", "rear"), ("wheel",))
    n = 3
    rng = np.random.default_rng(2)
    t, rpm = np.arange(n) * 0.1, np.array([0.0, 1e3, 2e3])
    ring_speed, journal, ring = rng.random((n, 2)), rng.random((n, 2, 2)), rng.random((n, 2, 2))
    eps, discs, torque, power = rng.random((n, 2, 2)), rng.random((n, 1, 2)), rng.random((n, 2)), rng.random((n, 2))
    rows = schema.rows(t, rpm, ring_speed, journal, ring, eps, discs, torque, power)
    col = {c: rows[:, i] for i, c in enumerate(schema.columns)}
    np.testing.assert_array_equal(col["time [s]"], t)
    for b, name in enumerate(schema.bearings):
        np.testing.assert_array_equal(col[f"ring speed {name} [rad/s]"], ring_speed[:, b])
        rsr = col[f"RSR {name} [-]"]
        assert np.isnan(rsr[0])  # zero rotor speed
        np.testing.assert_array_equal(rsr[1:], ring_speed[1:, b] / (rpm[1:] * 2 * np.pi / 60))
        for q, axis in enumerate("xy"):
            np.testing.assert_array_equal(col[f"journal {name} {axis} [m]"], journal[:, b, q])
            np.testing.assert_array_equal(col[f"ring {name} {axis} [m]"], ring[:, b, q])
        for f, film in enumerate(("inner", "outer")):
            np.testing.assert_array_equal(col[f"eps {name} {film} [-]"], eps[:, b, f])
        np.testing.assert_array_equal(col[f"journal torque {name} [N m]"], torque[:, b])
        np.testing.assert_array_equal(col[f"power loss {name} [W]"], power[:, b])
    np.testing.assert_array_equal(col["wheel y [m]"], discs[:, 0, 1])
    one = schema.row(t[1], rpm[1], ring_speed[1], journal[1], ring[1], eps[1], discs[1])
    np.testing.assert_array_equal(one[:-4], rows[1, :-4])
    assert np.isnan(one[-4:]).all()


def test_extend_streams_exactly_as_append(tmp_path):
    schema = RunupSchema(("b",), ("d",))
    rows = np.arange(18 * len(schema.columns), dtype=float).reshape(18, -1) / 7.0
    one, many = Recorder(schema, 2, tmp_path / "one", flush_rows=3), Recorder(schema, 2, tmp_path / "many",
                                                                               flush_rows=3)
    start = 0
    for size in (1, 5, 0, 7, 2, 3):
        for r in rows[start:start + size]:
            one.append(r)
        many.extend(rows[start:start + size])
        start += size
        # the same rows on disk after every call (the flush points are those of append)
        assert many.flushed == one.flushed and many.n == one.n
        assert (tmp_path / "many" / "runup.csv").read_text() == (tmp_path / "one" / "runup.csv").read_text()
    np.testing.assert_array_equal(many.result().time, rows[:, 0])
    with pytest.raises(KeyboardInterrupt), many:
        raise KeyboardInterrupt
    meta = json.loads((tmp_path / "many" / "runup.json").read_text())
    assert meta["status"] == "interrupted" and meta["samples"] == 18
