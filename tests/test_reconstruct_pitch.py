"""The reconstruction's whole bike pitches carrying the bike's masses fore and aft
(``mtbmj.ride.reconstruct_bike.carried_inertia``, issue 51's reconstruct-then-ride loop).

Without it the reconstruction's frame pitched about its own body's inertia alone (3.2 kg m^2 for the
tests' bike where carrying the rider 0.72 m above the frame body's centre adds 12.0): over the
MuJoCo bike's own ride (ISO 8608 class C at 6 m/s) it answered the ground at 2-9 Hz with 0.4-0.6
times the engine's fork travel, so the terrain it found had 2-3 times the true one's amplitude
there and the engine riding it doubled the ride's velocities (tests/test_reconstruct_loop.py).

Checked here: the inertia against the kinetic energy of a pitch with the bike's horizontal momentum
free, found by minimising over the frame's fore-aft speed (not the closed form the module uses);
and the whole bike's fork over a washboard against the MuJoCo bike's (its own planar multibody,
the rider on a slide along the frame's z), beside the bike without the carried inertia."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from mtbmj.bike import run as bike_run, spec as spec_mod
from mtbmj.bike.model import frame_body
from mtbmj.ride import reconstruct_bike as rb

from helpers import bike_text


@pytest.fixture(scope="module")
def spec(tmp_path_factory):
    file = tmp_path_factory.mktemp("pitch") / "bike.toml"
    file.write_text(bike_text(12.0))
    return spec_mod.load(str(file)), str(file)


def bodies(spec, rider=True):
    """(mass kg, height m in the frame) of what the frame carries fore and aft, listed here: the frame
    body, the rider, the fork's lower and front wheel, the rear wheel, the swingarm at its middle."""
    M, (_, cz), _ = frame_body(spec)
    out = [(M, cz), (spec.fork_lower_mass + spec.front_wheel_mass, spec.front_axle[1]),
           (spec.rear_wheel_mass, spec.rear_axle[1]), (spec.swingarm_mass, 0.5 * (spec.pivot[1] + spec.rear_axle[1]))]
    return out + ([(spec.rider.mass, spec.rider.com[1])] if rider else [])


def inertia_by_energy(parts, rate=1.0):
    """The pitch inertia the fore-aft motion adds: 2 T / rate^2, T the least kinetic energy of the
    bodies' fore-aft speeds (u - z rate) over the frame's fore-aft speed u (a free coordinate
    settles where its momentum is zero, which is where T is least)."""
    def energy(u):
        return sum(0.5 * m * (u - z * rate) ** 2 for m, z in parts)
    best = minimize_scalar(energy, bracket=(-5.0, 5.0), tol=1e-12)
    return 2.0 * best.fun / rate ** 2


def test_the_carried_inertia_is_the_energy_of_a_pitch_with_the_momentum_free(spec):
    s, _ = spec
    M, (_, cz), I = frame_body(s)
    got = rb.carried_inertia(s, M, cz)
    assert got == pytest.approx(inertia_by_energy(bodies(s)), rel=1e-6)
    assert got > 3.0 * I  # the naive bike (the frame body's inertia alone) is far from it
    assert inertia_by_energy(bodies(s, rider=False)) < 0.2 * got  # a rider left out is told apart
    b = rb.whole_bike(s, *bike_run.setups(s))
    assert b.I == pytest.approx(I + got, rel=1e-12)


@pytest.mark.slow  # a 14 s engine run: about 15 s
def test_the_whole_bike_answers_a_washboard_as_the_engine_does(spec):
    """A 2 m washboard of 10 mm at 6 m/s (3 Hz: the frame's pitch): the fork's amplitude of the
    reconstruction's whole bike (point contact on the profile under each of the engine's axles)
    within 25 % of the MuJoCo bike's (measured 3.57 mm for the engine's 4.28); the bike without the
    carried inertia (1.57) is not."""
    from mtbmj.bike.run import run_bike
    from mtbmj.rolling import terrain as terrain_mod

    s, file = spec
    T = terrain_mod.make("washboard:height_mm=10,wavelength_mm=2000,length_m=120,at_m=15")
    raw = run_bike(file, T, 6.0, duration=14.0).raw
    te, dt = raw["time_s"], 1e-3
    t = np.arange(0.0, te[-1], dt)
    ground = [T.height(np.interp(t, te, raw[c])) for c in ("front_axle_x_m", "rear_axle_x_m")]
    on = (t > 8.0) & (t < 13.0)  # settled, whole periods at 3 Hz

    def amplitude(y):
        y = y[on] - y[on].mean()
        return 2.0 * abs(np.mean(y * np.exp(-2j * np.pi * 3.0 * t[on])))
    engine = amplitude(np.interp(t, te, raw["front_travel_mm"]))
    b = rb.whole_bike(s, *bike_run.setups(s))
    M, _, I = frame_body(s)
    fork = {}
    for name, bike in (("carried", b), ("frame alone", dataclasses.replace(b, I=I))):
        fork[name] = amplitude(rb.ride(t, bike, ground[1], front_ground=ground[0])["front_rise"] / b.sin_a * 1e3)
    assert engine > 3.0  # the engine's fork moves (a check of the reading)
    assert fork["carried"] == pytest.approx(engine, rel=0.25)
    assert fork["frame alone"] != pytest.approx(engine, rel=0.25)
