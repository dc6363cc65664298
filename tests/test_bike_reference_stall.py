"""The bike's ODE reference gets through, or says where it cannot, in bounded time (issue 54):

* the muscles' power limit (``rider_control.power_factors``, ``muscle_torques``) is continuous in
  every joint's speed: one shared scale on the torques doing positive work jumped where a joint's
  speed changed sign (the shoulder between -140 and -93 N m at rest), a sliding mode that held the
  reference's RK45 at 1.0402 s off the 1 m drop for ever (the cross-check ran 36 min unfinished);
* a solver that stalls anyway is stopped with one ``RunError`` naming the time and the coordinate
  (``reference.Stall``), here on equations with a sliding mode written in the test.

The inputs are the test's: torques, speeds and limits written here, the closed-form root of the
power limit for one and two working joints, and a Coulomb-like force sign(v) that sticks."""
from __future__ import annotations

import math
import time

import numpy as np
import pytest

from mtbmj.bike import rider_control as rc
from mtbmj.errors import RunError


def _torques(speed_shoulder: float):
    """Like the stall's state: hip, knee and elbow asked for 1734, 69 and 280 W (2083 W together),
    the shoulder asked -140.4 N m as its speed passes 0 (its stiffness 1 N m/rad, no damping, so the
    torque asked is the angle's distance from its target)."""
    strength = dict.fromkeys(rc.JOINTS, (1e4, 1e4))
    want = dict.fromkeys(rc.JOINTS, 0.0)
    asked = {"hip": -450.0, "knee": -60.0, "ankle": -10.5, "shoulder": -140.4, "elbow": -40.0}
    speed = {"hip": -3.853, "knee": -1.158, "ankle": 0.99, "shoulder": speed_shoulder, "elbow": -7.0}
    gains = {k: (1.0, 0.0) for k in rc.JOINTS}
    now = {k: -asked[k] for k in rc.JOINTS}  # kp (want - now) = asked
    return rc.muscle_torques(want, now, speed, gains, strength)


def test_a_joint_at_rest_keeps_its_torque_while_the_power_limit_binds():
    """The shoulder's torque either side of rest: equal within what its own (vanishing) power cuts
    (it jumped by 48 N m between 1e-9 rad/s and -1e-9 rad/s); the others' power at the limit."""
    (below, _, p_below), (above, _, p_above) = _torques(-1e-9), _torques(1e-9)
    assert abs(below["shoulder"] - above["shoulder"]) < 1e-6
    assert below["shoulder"] == pytest.approx(-140.4, rel=1e-6)  # no work, no cut
    worked = 450.0 * 3.853 + 60.0 * 1.158 + 40.0 * 7.0  # 2083 W asked of hip, knee and elbow
    assert worked > 1.3 * rc.POWER_W
    assert p_below == pytest.approx(rc.POWER_W, rel=1e-12) and p_above == pytest.approx(rc.POWER_W, rel=1e-12)
    assert below["ankle"] == -10.5  # absorbing (negative work): not cut


def test_power_factors_closed_forms():
    """One working joint: cut to the limit exactly, p / (1 + c p) = L, c = (p - L) / (p L), as the
    old shared scale did. Two: each p_k / (1 + c p_k), the sum L, the harder-working one cut
    more (its share of the power falls). Within the limit: nothing cut. Continuous at the limit."""
    one = rc.power_factors({"a": 3000.0, "b": -500.0, "c": 0.0}, 1500.0)
    assert one == {"a": pytest.approx(0.5, rel=1e-14), "b": 1.0, "c": 1.0}
    p = {"a": 2000.0, "b": 500.0}
    f = rc.power_factors(p, 1500.0)
    kept = {k: p[k] * f[k] for k in p}
    assert sum(kept.values()) == pytest.approx(1500.0, rel=1e-13)
    c = (1.0 / f["a"] - 1.0) / p["a"]  # the common c of both, read from the one...
    assert f["b"] == pytest.approx(1.0 / (1.0 + c * p["b"]), rel=1e-13)  # ...gives the other's factor
    assert f["a"] < f["b"] and kept["a"] / kept["b"] < p["a"] / p["b"]
    assert rc.power_factors({"a": 1000.0, "b": 500.0}, 1500.0) == {"a": 1.0, "b": 1.0}
    just = rc.power_factors({"a": 1000.0, "b": 500.0 + 1e-9}, 1500.0)
    assert all(abs(v - 1.0) < 1e-11 for v in just.values())


def test_power_factors_are_continuous_in_the_speeds():
    """Sampled across a sign change of one joint's power with the others over the limit: the
    factors and the cut torque change by no more than the step times a slope bounded here."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        others = {k: float(v) for k, v in zip("abc", rng.uniform(200.0, 1500.0, 3))}
        last = None
        for x in np.linspace(-1e-3, 1e-3, 41):  # the joint's power, W, through 0
            f = rc.power_factors({**others, "z": float(x)}, 1500.0)
            if last is not None:
                assert abs(f["z"] - last["z"]) < 1e-5 and all(abs(f[k] - last[k]) < 1e-5 for k in "abc")
            last = f


def _sliding(t, y):
    """x'' = -sign(x') 10 + 5: a force that jumps where the speed is 0 and holds it there (its
    pull, 5, inside the jump, 10); x' starts at 1, reaches 0 at t = 0.2 and sticks."""
    return np.array([y[1], -10.0 * math.copysign(1.0, y[1]) + 5.0 if y[1] != 0.0 else 5.0])


def test_a_stalled_reference_solver_is_stopped_in_one_line():
    from scipy.integrate import solve_ivp

    from mtbmj.bike.reference import STALL_CALLS, Stall

    watched = Stall(_sliding, ("slide",))
    start = time.perf_counter()
    with pytest.raises(RunError) as err:
        solve_ivp(watched, (0.0, 1.0), [0.0, 1.0], method="RK45", rtol=1e-8, atol=1e-10, max_step=1e-3)
    assert time.perf_counter() - start < 60.0
    msg = str(err.value)
    assert "\n" not in msg and "stalled" in msg and "slide" in msg
    t = float(msg.split("t = ")[1].split(" s")[0])
    assert t == pytest.approx(0.2, abs=1e-5)  # where the speed reached 0 (x' = 1 - 5 t)
    assert watched.count == STALL_CALLS


def test_a_stiff_stop_is_not_a_stall():
    """A stiff spring (1e9 N/m on 1 kg, 5 kHz) is stepped short but advances: no RunError, and the
    rebound's speed as it left (closed form: -v for an elastic stop)."""
    from scipy.integrate import solve_ivp

    from mtbmj.bike.reference import Stall

    def stop(t, y):
        return np.array([y[1], -1e9 * y[0] if y[0] > 0.0 else 0.0])

    sol = solve_ivp(Stall(stop, ("x",)), (-0.01, 0.01), [-0.01, 1.0], method="RK45", rtol=1e-8, atol=1e-10,
                    max_step=1e-3)
    assert sol.success and sol.y[1, -1] == pytest.approx(-1.0, rel=1e-3)
