"""A seat slam replayed through the MuJoCo bike with a compliant seated rider (``fit bounce --replay``).

The whole bike (``mtbmj.bike.run.prepare``, seated) stands still on flat ground. The seated rider's
body is made compliant: the rider's two coordinates (height and pitch at the hips) are let free, on
the legs (pedals) and arms (bars) the bike file already has, with a saddle spring and damper added on
each (MuJoCo joint stiffness and damping) so that each alone, the frame held, rings at ``rider_hz``
(5 Hz by default) with a damping ratio of 0.475: the seated body's apparent mass (``RIDER_SOURCE``,
the same saddle as ``fit bounce --rider-hz``, ``mtbmj.identify.bounce_bike``). The saddle's preload
is the force the seated rider puts on it at the seated static equilibrium, so the bike starts at
rest there (every acceleration below ``REST_ACC``).

The slam is made by a vertical force on the rider's body at its centre of mass (where its two
joints sit: no moment on the rider's pitch): the rider rises off the saddle and then slams onto it.
It is two smooth lobes (each ``A sin^2(pi (t - t0) / T)`` over ``T``): a lift (up) and a slam (down),
the slam lobe ending at the latest ``SLAM_END_S`` after the record's peak; then the force is zero and
the bike rings down freely (the shock and the fork may top out, the tyres may leave the ground: the
MuJoCo bike's own laws). **The start is the record's own state**: the rider at rest on the saddle and
the shock at the record's level at rest before the slam (its median over ``QUIET_BEFORE_S`` before
the peak): for every spring scale the shock's preload is set so the seated static equilibrium rests
there (version-2 files' millimetres are approximate, their calibration a placeholder: the preload
takes up the offset, and the spring's rate is read from the motion alone). The fork is not fitted:
it keeps the bike file's preload and rests where that puts it; its replayed travel is shown beside
the record's (``fork_rms_mm``).

Fitted by ``scipy.optimize.least_squares`` over whole simulated runs (``BEFORE_S + AFTER_S``, 1.9 s,
about 0.1 s of computing each) on the shock's stroke at every ``SAMPLE_S``, alternately (``ROUNDS``
times): the push's six values on the record up to its peak, the shock held; then the shock's three
and the slam's amplitude on the whole replay, the push's timing held. The shock's three: the spring
rate's scale on the bike file's, a linear damper (the same coefficient in compression and rebound,
N s/m at the shock, as the linear reading through the bike, ``bounce_bike``: a slam's compression is
driven by the fitted push, which takes up a compression coefficient fitted beside it) and its
Coulomb friction (N at the shock). 95 % intervals of all nine values together (the push's timing
trades with the spring; held, it made a heavily damped slam's spring interval too narrow): the
Jacobian's (forward differences at the fitted values) covariance with the residual's variance, inflated for its lag-1
autocorrelation (a replay's residual is model error, smooth in time: the effective number of
samples n (1 - rho) / (1 + rho)), Student's t; the shock's values' intervals cut at 0 below.

The rider's share of the mode is stated beside the spring's: the linear seated bike with the same
compliant rider (``bounce_bike.SeatedBike(rider_hz=...)``), its shock spring scaled by the fitted
scale, the strain-energy shares of its rear mode.

Refused (``BounceError``, one line) when the record leaves the shock's stroke (or sits past full
extension), when the replay cannot follow the record (its RMS residual above ``MAX_RELATIVE_RMS`` of
the slam's height above rest), when the spring scale or the damper ends at a bound, when no preload
rests the bike at the record's level, and when the simulated bike diverges.
"""
from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np

from mtbmj.bike import run as bike_run
from mtbmj.bike import spec as spec_mod
from mtbmj.bike.reference import NQ, Reference, static_equilibrium
from mtbmj.errors import MtbmjError
from mtbmj.identify.bounce import (QUIET_BEFORE_S, BounceError, find_slam, first_rebound, interval95,
                                   rebound_check, record_name)
from mtbmj.identify.bounce_bike import RIDER_SOURCE, RIDER_ZETA
from mtbmj.identify.bounce_ends import CORRELATION, correlations, covariance, friction_compression_correlation
from mtbmj.runpath import guard

RIDER_HZ = 5.0  # the seated body's vertical resonance (Fairley and Griffin 1989: 5 Hz; 4-6 Hz, Griffin 1990, ISO 2631-1)
BEFORE_S = 0.6  # the replay starts this long before the slam's peak (the rider at rest on the saddle, QUIET_BEFORE_S)
AFTER_S = 1.3  # ... and ends this long after it (about two cycles of the ring-down)
SAMPLE_S = 0.005  # the residual's spacing
PUSH_FIT_S = 0.0  # the push is first fitted alone on the record up to the slam's peak
SETTLE_S = 0.15  # the pooled replay's settling force rises over this after the slam lobe
SLAM_END_S = 0.05  # the slam lobe ends at the latest this long after the record's peak: then the bike is free
STILL_M_PER_S = 1e-3  # prepare() needs a speed; the bike then stands still (its speed set to 0)
REST_ACC = 1e-3  # m/s^2 (rad/s^2): the start is at rest when every acceleration is below this
MAX_RELATIVE_RMS = 0.12  # the replay follows the record: RMS residual within this share of the slam's rise
PRELOAD = "fork.spring.preload_N"
PRELOAD_ITERATIONS = 40
REST_TOL_MM = 5e-4  # the rest solved to this: noisy, but 1e-7's reproducible landing reads worse (identification.md)
MAX_PITCH_RAD = math.radians(10.0)  # a standing bike's frame is within this of level
SHOCK_KEYS = {"scale": "fork.spring.rate_N_per_mm", "rebound": "fork.damper.rebound_N_s_per_m",
              "compression": "fork.damper.compression_N_s_per_m", "friction": "fork.friction.coulomb_N"}
PRELOAD_FLOOR_N = 1.0  # the lowest preload a spring is given (config's range: 1-5000 N)
NAMES = ("lift_N", "lift_start_s", "lift_s", "slam_N", "slam_end_s", "slam_s",
         "spring_scale", "damper_N_s_per_m", "friction_N")
PUSH_NAMES = NAMES[:6]
SHOCK_NAMES = NAMES[6:]
PUSH_INDEX = np.arange(6)  # fitted on the record up to its peak
FREE_INDEX = np.array([3, 6, 7, 8])  # the slam's amplitude and the shock's three: on the whole replay
ROUNDS = 2
BOUNDS = {"lift_N": (0.0, 3000.0), "lift_start_s": (-BEFORE_S, 0.0), "lift_s": (0.05, BEFORE_S),
          "slam_N": (0.0, 8000.0), "slam_end_s": (-0.3, SLAM_END_S), "slam_s": (0.05, 0.45),
          "spring_scale": (0.2, 3.0), "damper_N_s_per_m": (50.0, 30000.0), "friction_N": (0.0, 400.0)}
METHOD = ("the whole MuJoCo bike standing on flat ground with the seated rider compliant (saddle spring and damper "
          "on the rider's two coordinates beside the legs and arms, each alone at rider_hz with a damping ratio of "
          "0.475), started at rest at its seated static equilibrium, pushed by a vertical force on the rider (a lift "
          "lobe and a slam lobe, sin^2 each, fitted), then free; the shock's spring-rate scale, rebound damping and "
          "Coulomb friction fitted with the push by least squares on the stroke less its rest level; 95 % "
          "intervals of all nine values from the Jacobian, inflated for the residual's lag-1 autocorrelation")


def pulse(t, amplitude, start, duration):
    """``amplitude sin^2(pi (t - start) / duration)`` within ``[start, start + duration]``, else 0."""
    t = np.asarray(t, float)
    u = (t - start) / duration
    return np.where((u > 0.0) & (u < 1.0), amplitude * np.sin(np.pi * np.clip(u, 0.0, 1.0)) ** 2, 0.0)


def push(t, p: dict):
    """The push on the rider (N, up positive) at times ``t`` (s from the slam's peak); with
    ``settle_N`` (the pooled replay's) the rider's weight shifted onto the saddle after the slam: a
    force down rising as sin^2 over ``SETTLE_S`` from the slam lobe's end, then held."""
    t = np.asarray(t, float)
    out = (pulse(t, p["lift_N"], p["lift_start_s"], p["lift_s"])
           - pulse(t, p["slam_N"], p["slam_end_s"] - p["slam_s"], p["slam_s"]))
    settle = p.get("settle_N", 0.0)
    if settle:
        u = np.clip((t - p["slam_end_s"]) / SETTLE_S, 0.0, 1.0)
        out = out - settle * np.sin(0.5 * np.pi * u) ** 2
    return out


class SeatedReplay:
    """The MuJoCo bike of ``bike`` standing still with the compliant seated rider; :meth:`run` replays a
    push with the shock's spring scale, rebound damping and friction set."""

    def __init__(self, bike="sst", rider_hz: float = RIDER_HZ, overrides=None, callback: str = "auto",
                 rest_tol_mm: float = REST_TOL_MM):
        spec = bike if isinstance(bike, spec_mod.BikeSpec) else spec_mod.load(str(bike), overrides)
        self.source_spec = spec
        self._linear = None
        self.p = bike_run.prepare(spec, "flat", STILL_M_PER_S, drive="coast", callback=callback, seated=True)
        self.spec = self.p.spec  # the seated spec (the rider's centre of mass on the saddle)
        self.kind = bike_run.callback_kind(self.p.callback)
        b = self.p.bike
        self.model = b.model
        self.rider_hz = float(rider_hz)
        self.rest_tol_mm = float(rest_tol_mm)
        self.dofs = [b.dof_index(n) for n in ("rider_z", "rider_pitch")]
        self.qadr = [b.qpos_index(n) for n in ("rider_z", "rider_pitch")]
        self.joints = [int(self.model.joint(n).id) for n in ("rider_z", "rider_pitch")]
        self.rider_body = int(self.model.body("rider").id)
        self.armature0 = {d: 0.0 for d in self.dofs}
        for d in self.dofs:  # the seated lock off: the rider free on the saddle, legs and arms
            self.model.dof_armature[d] = self.armature0[d]
        shock_over = dict(self.spec.shock_overrides)
        shock_over.setdefault("fork.travel_mm", self.spec.shock_stroke * 1e3)
        self.shock_over = shock_over
        self.shock_rate0 = float(self.p.shock_setup.config.get(SHOCK_KEYS["scale"]))
        self.rebound0 = float(self.p.shock_setup.config.get(SHOCK_KEYS["rebound"]))
        self.friction0 = float(self.p.shock_setup.config.get(SHOCK_KEYS["friction"]))
        self.saddle = None
        self.rest_mm = {"shock": None, "fork": None}
        self.preload = {"shock": None, "fork": None}
        self._key = None
        self._q = None
        from mtbmj.bike.model import JOINTS

        self._guess = np.array([self.p.initial_qpos[b.qpos_index(n)] for n in JOINTS])  # prepare's seated rest

    # the suspension and the saddle ---------------------------------------------------------------
    def set_rest(self, shock_mm: float | None, fork_mm: float | None) -> None:
        """The travel each end rests at before the slam (the record's own; None: the bike file's): the
        spring preloads are set so the seated static equilibrium rests there (``set_shock``)."""
        rest = {"shock": shock_mm, "fork": fork_mm}
        if rest != self.rest_mm:
            self.rest_mm = rest
            self._key = None

    def _laws(self, over_s: dict, over_f: dict) -> None:
        from mtbmj import compose
        from mtbmj.config import load

        p = self.p
        import warnings

        from mtbmj.errors import ConfigWarning

        with warnings.catch_warnings():  # the preloads are the replay's own rest-matching values (reported)
            warnings.simplefilter("ignore", ConfigWarning)
            shock = compose.setup(load(self.spec.shock_config, over_s))
            fork = compose.setup(load(self.spec.fork_config, over_f or None))
        p.shock_setup, p.shock_law, p.fork_setup, p.fork_law = shock, shock.fork, fork, fork.fork
        args = (self.kind, p.bike, fork.fork, shock.fork, p.front_tire, p.rear_tire, p.drive, p.speed, p.traction,
                p.callback.refresh)
        try:
            p.callback = bike_run.make_callback(*args)
        except RuntimeError:  # the compiled callbacks' slots full of ones not yet collected (several replays alive)
            import gc

            gc.collect()
            p.callback = bike_run.make_callback(*args)

    def _static(self):
        ref = Reference(self.p)

        def standing(q):  # both wheels on the ground, the frame near level (not a spurious root)
            y = np.concatenate((q, np.zeros(NQ), np.zeros(ref.nf + ref.ns)))
            _, out = ref.forces(0.0, y)
            return bool(out["front"][1] > 0.0 and out["rear"][1] > 0.0 and abs(q[2]) < MAX_PITCH_RAD)

        q = static_equilibrium(ref, guess=self._guess[1:], acceptable=standing, held=(5, 6))
        self._guess = q
        return ref, q

    def set_shock(self, scale: float, damper: float, friction: float, compression: float | None = None) -> None:
        """The shock law with the spring rate scaled, the rebound coefficient and the friction set, its
        callback, each end's preload so the seated static equilibrium rests at ``rest_mm`` (when set),
        that equilibrium, and the saddle (spring, damper, preload) there."""
        compression = damper if compression is None else float(compression)
        key = (float(scale), float(damper), float(friction), compression)
        if key == self._key:
            return
        over_s = {**self.shock_over, SHOCK_KEYS["scale"]: self.shock_rate0 * scale,
                  SHOCK_KEYS["rebound"]: damper, SHOCK_KEYS["compression"]: compression,
                  SHOCK_KEYS["friction"]: friction}
        over_f = dict(self.spec.fork_overrides)
        preload = {"shock": float(self.p.shock_setup.config.get(PRELOAD)) if self.preload["shock"] is None
                   else self.preload["shock"],
                   "fork": float(self.p.fork_setup.config.get(PRELOAD)) if self.preload["fork"] is None
                   else self.preload["fork"]}
        for _ in range(PRELOAD_ITERATIONS):
            for end, over in (("shock", over_s), ("fork", over_f)):
                if self.rest_mm[end] is not None:
                    over[PRELOAD] = preload[end]
            try:
                self._laws(over_s, over_f)
            except MtbmjError as e:
                raise BounceError(f"replay: no spring preload rests the seated bike at the record's travel ({e})") from None
            ref, q = self._static()
            at = {"shock": float(self.stroke_mm(q[4])), "fork": float(q[3] * 1e3)}
            off = {end: at[end] - self.rest_mm[end] for end in at if self.rest_mm[end] is not None}
            # an end whose preload is 0 and still rests above the record's travel is as low as it goes
            if all(abs(v) < self.rest_tol_mm or (v < 0 and preload[e] <= PRELOAD_FLOOR_N) for e, v in off.items()):
                break
            for end, miss in off.items():  # more preload per mm of sag: the main spring's rate (N/mm)
                rate = float((self.p.shock_setup if end == "shock" else self.p.fork_setup).config.get(SHOCK_KEYS["scale"]))
                preload[end] = max(preload[end] + rate * miss, PRELOAD_FLOOR_N)
        else:
            raise BounceError(f"replay: no spring preload rests the seated bike at the record's travel "
                              f"({', '.join(f'{e} {v:.1f} mm off' for e, v in off.items())})")
        self.preload = preload
        self.rest_at = at  # where the replay rests (mm): the record's, unless an end's preload reached 0
        y = np.concatenate((q, np.zeros(NQ), np.zeros(ref.nf + ref.ns)))
        Q, out = ref.forces(0.0, y)
        held = (Q + out["static"])[5:7]  # what the seat carries at the seated position
        M = ref.planar.mass_matrix(q)
        self.saddle = {"resonance_hz": self.rider_hz, "damping_ratio": RIDER_ZETA, "source": RIDER_SOURCE}
        w2 = (2 * math.pi * self.rider_hz) ** 2
        for k, (i, name) in enumerate(((5, "vertical"), (6, "pitch"))):
            limbs = -self._limb_stiffness(ref, q, i)
            rate = max(M[i, i] * w2 - limbs, 0.0)
            damping = 2 * RIDER_ZETA * math.sqrt((rate + limbs) * M[i, i])
            j, d = self.joints[k], self.dofs[k]
            self.model.jnt_stiffness[j] = rate
            self.model.dof_damping[d] = max(damping - self._limb_damping(ref, q, i), 0.0)
            # -rate (q - q_spring) = -held at the seated position q = 0
            self.model.qpos_spring[self.qadr[k]] = -held[k] / rate if rate > 0 else 0.0
            self.saddle[f"saddle_{name}_rate"] = float(rate)
            self.saddle[f"saddle_{name}_damping"] = float(self.model.dof_damping[d])
            self.saddle[f"saddle_{name}_preload"] = float(-held[k])
        self._q = q
        self._key = key

    @staticmethod
    def _limb_stiffness(ref, q, i, h=1e-7) -> float:
        def f(x):
            qq = q.copy()
            qq[i] += x
            y = np.concatenate((qq, np.zeros(NQ), np.zeros(ref.nf + ref.ns)))
            Q, out = ref.forces(0.0, y)
            return (Q + out["static"])[i]
        return (f(h) - f(-h)) / (2 * h)

    @staticmethod
    def _limb_damping(ref, q, i, h=1e-5) -> float:
        def f(v):
            qd = np.zeros(NQ)
            qd[i] = v
            y = np.concatenate((q, qd, np.zeros(ref.nf + ref.ns)))
            Q, _ = ref.forces(0.0, y)
            return Q[i]
        return -(f(h) - f(-h)) / (2 * h)

    def start(self) -> None:
        """The data at the seated static equilibrium, at rest."""
        from mtbmj.bike.model import JOINTS

        b, d = self.p.bike, self.p.data
        mujoco.mj_resetData(self.model, d)
        for name, value in zip(JOINTS, self._q):
            d.qpos[b.qpos_index(name)] = value
        d.qvel[:] = 0.0
        d.act[:] = 0.0
        self.p.callback.reset()

    def rest_acceleration(self) -> float:
        """The largest acceleration at the start (m/s^2 or rad/s^2): ~0 when it is a rest."""
        from mtbmj.controllers import installed

        self.start()
        with installed(self.p.callback):
            mujoco.mj_forward(self.model, self.p.data)
        return float(np.max(np.abs(self.p.data.qacc)))

    def stroke_mm(self, phi) -> np.ndarray:
        return self.p.stepping.stroke(np.asarray(phi, float)) * 1e3

    def run(self, p: dict, before_s: float = BEFORE_S, after_s: float = AFTER_S, substeps: int = 1) -> dict:
        """The replay of push ``p`` (``NAMES``' first six) with the shock's (spring_scale,
        rebound_N_s_per_m, friction_N): time_s (from the slam's peak), stroke_mm, fork_mm,
        rider_mm (the rider's height on the saddle), push_N, each at every coarse step. Raises
        BounceError when the bike leaves its envelope (a crash, a value not finite)."""
        from mtbmj.controllers import installed

        self.set_shock(*(p[k] for k in SHOCK_NAMES), p.get("compression_N_s_per_m"))
        self.start()
        m, d, b = self.model, self.p.data, self.p.bike
        dt = self.p.timestep
        n = int(round((before_s + after_s) / dt))
        m.opt.timestep = dt / substeps
        iphi, ifork, irz = b.qpos_index("swingarm"), b.qpos_index("fork"), self.qadr[0]
        phi, fork, rz, force = (np.empty(n + 1) for _ in range(4))
        t = -before_s + dt * np.arange(n + 1)
        fine = -before_s + (dt / substeps) * np.arange(n * substeps + 1)
        fz = push(fine, p)
        phi[0], fork[0], rz[0] = d.qpos[iphi], d.qpos[ifork], d.qpos[irz]
        messages = []  # MuJoCo's warnings (a diverging trial), routed away from MUJOCO_LOG.TXT in the cwd
        try:
            with installed(self.p.callback), guard.collected_warnings(messages):
                for i in range(n):
                    for s in range(substeps):
                        d.xfrc_applied[self.rider_body, 2] = fz[i * substeps + s]
                        mujoco.mj_step(m, d)
                    phi[i + 1], fork[i + 1], rz[i + 1] = d.qpos[iphi], d.qpos[ifork], d.qpos[irz]
        finally:
            m.opt.timestep = dt
            d.xfrc_applied[self.rider_body, :] = 0.0
        force[:] = push(t, p)
        cause = guard.warned_cause(d, messages, m)  # MuJoCo resets a blown-up state: finite values, a wrong replay
        if cause is None and not (np.all(np.isfinite(phi)) and np.all(np.isfinite(fork))):
            cause = "a value not finite"
        if cause is not None:
            raise BounceError(f"replay: the simulated bike diverged ({cause}): outside the model's envelope")
        return {"time_s": t, "stroke_mm": self.stroke_mm(phi), "fork_mm": fork * 1e3, "rider_mm": rz * 1e3,
                "push_N": force}


@dataclasses.dataclass
class Replay:
    """A fitted replay: the values with 95 % intervals, the replayed trace beside the record's."""

    name: str
    values: dict  # NAMES -> value
    sd: dict  # NAMES -> standard deviation
    trace: dict  # time_s, stroke_mm, fork_mm, push_N, record_stroke_mm, record_fork_mm (all less rest for stroke)
    rms_mm: float
    rise_mm: float
    rest_offset_mm: float  # the record's rest less the replay's (shock; ~0: the preload puts it there)
    shock_preload_N: float
    fork_rest_offset_mm: float | None  # the record's fork rest less the replay's (the fork is not fitted)
    spring_rate_N_per_mm: float
    bike_file_rate_N_per_mm: float
    saddle: dict
    shares: dict | None
    fork_rms_mm: float | None
    nfev: int
    correlation: dict | None = None  # "a|b" -> the last stage's correlation of values a and b (FREE_INDEX's)

    def summary(self) -> dict:
        v, sd = self.values, self.sd
        out = {"method": METHOD, "rms_mm": self.rms_mm, "slam_rise_mm": self.rise_mm,
               "rest_offset_mm": self.rest_offset_mm, "shock_preload_N": self.shock_preload_N,
               "fork_rest_offset_mm": self.fork_rest_offset_mm, "runs": self.nfev, "rider": self.saddle}
        for k in NAMES:
            out[k] = v[k]
            ci = interval95(v[k], sd[k]) if math.isfinite(sd[k]) else None
            if ci is not None and k in SHOCK_NAMES:  # a rate, a damper and a friction are not negative
                ci = [max(ci[0], 0.0), ci[1]]
            out[k + "_ci95"] = ci
        out["spring_rate_N_per_mm"] = self.spring_rate_N_per_mm
        lo, hi = interval95(self.spring_rate_N_per_mm, sd["spring_scale"] * self.bike_file_rate_N_per_mm)
        out["spring_rate_N_per_mm_ci95"] = [max(lo, 0.0), hi]
        out["bike_file_spring_rate_N_per_mm"] = self.bike_file_rate_N_per_mm
        if self.shares is not None:
            out["mode_strain_energy_share"] = self.shares
        out["fork_rms_mm"] = self.fork_rms_mm
        out[CORRELATION] = friction_compression_correlation(self.correlation)  # they trade (bounce_ends)
        return out

    def line(self) -> str:
        v = self.values
        s = self.summary()
        lo, hi = s["spring_scale_ci95"]
        clo, chi = s["damper_N_s_per_m_ci95"]
        flo, fhi = s["friction_N_ci95"]
        share = "" if self.shares is None else (f"; the mode's strain energy {100 * self.shares['spring']:.0f} % in "
                                                f"the spring, {100 * self.shares['rider']:.0f} % in the rider's body")
        return (f"{self.name} replayed through the bike: spring {v['spring_scale']:.2f} x the bike file's "
                f"[{lo:.2f}, {hi:.2f}] ({self.spring_rate_N_per_mm:.1f} N/mm), damper {v['damper_N_s_per_m']:.0f} "
                f"N s/m [{clo:.0f}, {chi:.0f}], friction {v['friction_N']:.0f} N [{flo:.0f}, {fhi:.0f}], RMS "
                f"{self.rms_mm:.2f} mm of a {self.rise_mm:.1f} mm slam{share}")

    def csv_columns(self) -> dict:
        return {k: self.trace[k] for k in ("time_s", "record_stroke_mm", "stroke_mm", "record_fork_mm", "fork_mm",
                                           "push_N")}


def _rest(t, x, peak_t) -> float:
    early, late = QUIET_BEFORE_S
    w = (t >= peak_t - early) & (t <= peak_t - late)
    return float(np.median(x[w]))


def _start(t, s, rest) -> dict:
    """The push's start values read off the record (times from its peak): the lift from where the
    stroke first leaves its rest downwards, the slam from the last time it was below rest before the peak."""
    below = np.nonzero((t < 0) & (s < rest - 0.3 * max(rest, 1.0)))[0]
    if below.size:
        lift0, last = float(t[below[0]]), float(t[below[-1]])
    else:
        lift0, last = -0.4, -0.15
    lift0 = max(lift0 - 0.05, -BEFORE_S + 0.01)
    return {"lift_N": 500.0, "lift_start_s": lift0, "lift_s": max(min(last - lift0, BEFORE_S - 0.05), 0.1),
            "slam_N": 1500.0, "slam_end_s": 0.0, "slam_s": min(max(0.1 - last, 0.1), 0.4)}


@dataclasses.dataclass
class Slam:
    """A record's slam made ready for the replay (``prepare_slam``): the window from ``BEFORE_S`` before
    its peak to ``AFTER_S`` after, the rest levels, the record on the residual's grid and the start values."""

    name: str
    sr: SeatedReplay
    rest: float  # the shock's rest before the slam (mm)
    frest: float | None  # the fork's (mm), or None
    tt: np.ndarray  # the window's times from the peak
    rec: np.ndarray  # the shock's travel less its rest, in the window
    fork: np.ndarray | None  # the fork's travel in the window
    rise: float  # the slam's peak above rest (mm)
    grid: np.ndarray
    rec_g: np.ndarray
    x0: np.ndarray  # NAMES' start values
    base: np.ndarray  # NAMES' scales (the fit's unknowns are x0 + u base)

    def residual(self, x, upto=None, extra: dict | None = None) -> np.ndarray:
        """The replay of values ``x`` (NAMES, with ``extra``'s: the pooled replay's compression and
        settling) less the record on the grid (up to ``upto`` s, or all)."""
        self.sr.set_rest(self.rest, None)
        try:
            out = self.sr.run({**dict(zip(NAMES, x)), **(extra or {})})
        except BounceError:  # a run that diverges: far from the record (the final run says why)
            return np.full(self.grid.size if upto is None else int(np.sum(self.grid <= upto)), 10.0 * self.rise)
        sim = np.interp(self.grid, out["time_s"], out["stroke_mm"] - out["stroke_mm"][0])
        r = sim - self.rec_g
        return r if upto is None else r[self.grid <= upto]


LOWER = np.array([BOUNDS[k][0] for k in NAMES])
UPPER = np.array([BOUNDS[k][1] for k in NAMES])


def prepare_slam(time_s, shock_mm, fork_mm, name: str, sr: SeatedReplay, shock_max_mm: float | None = None,
                 start: dict | None = None) -> Slam:
    """The record's slam read for the replay; refused (``BounceError``) when the record is too short or
    leaves the shock's stroke, or when the seated bike does not start at rest at its level."""
    t = np.asarray(time_s, float)
    s = np.asarray(shock_mm, float)
    peak = find_slam(t, s, f"{name} (shock)")
    stroke_mm = sr.spec.shock_stroke * 1e3 if shock_max_mm is None else float(shock_max_mm)
    window = (t >= t[peak] - BEFORE_S) & (t <= t[peak] + AFTER_S)
    if window.sum() < 10 or t[peak] + AFTER_S > t[-1]:
        raise BounceError(f"{name}: the record ends {t[-1] - t[peak]:.2f} s after the slam; the replay needs "
                          f"{AFTER_S:g} s of ring-down after it")
    top = float(np.max(s[window]))
    if top > stroke_mm * 1.02 or float(np.min(s[window])) < -0.02 * stroke_mm:
        raise BounceError(f"{name}: the shock's travel reaches {top:.1f} mm (from {float(np.min(s[window])):.1f}), "
                          f"outside the bike's {stroke_mm:.0f} mm stroke: not this bike's shock (or its calibration "
                          f"is off), so the replay cannot describe it")
    tp = t[peak]
    rest = _rest(t, s, tp)
    frest = None if fork_mm is None else _rest(t, np.asarray(fork_mm, float), tp)
    sr.set_rest(rest, None)  # the fork is not fitted: it rests where the bike file's preload puts it
    tt = t[window] - tp
    rec = s[window] - rest
    grid = np.arange(-BEFORE_S + SAMPLE_S, AFTER_S - SAMPLE_S / 2, SAMPLE_S)
    init = dict(_start(tt, rec + rest, rest) if start is None else start)
    init.setdefault("spring_scale", 0.6)
    init.setdefault("damper_N_s_per_m", 2000.0)
    init.setdefault("friction_N", sr.friction0)
    base = np.array([0.1 if k.endswith(("start_s", "end_s")) else max(abs(init[k]), 0.05) for k in NAMES])
    x0 = np.clip(np.array([init[k] for k in NAMES]), LOWER + 1e-9, UPPER - 1e-9)
    sr.set_shock(*(x0[6:]))
    if sr.rest_acceleration() > REST_ACC:
        raise BounceError(f"{name}: the seated bike does not start at rest (an acceleration of "
                          f"{sr.rest_acceleration():.3g} at its static equilibrium)")
    return Slam(name, sr, rest, frest, tt, rec, None if fork_mm is None else np.asarray(fork_mm, float)[window],
                float(s[peak] - rest), grid, np.interp(grid, tt, rec), x0, base)


def fit_push(sl: Slam, u: np.ndarray, max_nfev: int = 40, extra: dict | None = None) -> int:
    """The push's six values (``PUSH_INDEX``) fitted on the record up to its peak, the rest of ``u``
    held; ``u`` updated in place; returns the runs taken."""
    from scipy.optimize import least_squares

    lo_u, hi_u = (LOWER - sl.x0) / sl.base, (UPPER - sl.x0) / sl.base

    def part(v):
        full = u.copy()
        full[PUSH_INDEX] = v
        return sl.residual(sl.x0 + full * sl.base, PUSH_FIT_S, extra)

    sol = least_squares(part, u[PUSH_INDEX], bounds=(lo_u[PUSH_INDEX], hi_u[PUSH_INDEX]), diff_step=1e-3,
                        max_nfev=max_nfev)
    u[PUSH_INDEX] = sol.x
    return int(sol.nfev)


def finish(sl: Slam, x: np.ndarray, sd: dict, rms: float, nfev: int, corr: dict | None,
           extra: dict | None = None) -> Replay:
    """The Replay of values ``x`` (and ``extra``'s): the final run beside the record, the rider's share."""
    sr = sl.sr
    sr.set_rest(sl.rest, None)
    values = {**dict(zip(NAMES, (float(v) for v in x))), **(extra or {})}
    out = sr.run(values)
    rest = sl.rest
    trace = {"time_s": out["time_s"], "stroke_mm": out["stroke_mm"] - out["stroke_mm"][0] + rest,
             "record_stroke_mm": np.interp(out["time_s"], sl.tt, sl.rec + rest), "fork_mm": out["fork_mm"],
             "push_N": out["push_N"]}
    fork_rms = None
    if sl.fork is not None:
        rec_f = np.interp(out["time_s"], sl.tt, sl.fork - sl.frest)
        sim_f = out["fork_mm"] - out["fork_mm"][0]
        trace["fork_mm"] = sim_f + sl.frest
        trace["record_fork_mm"] = rec_f + sl.frest
        fork_rms = float(np.sqrt(np.mean((sim_f - rec_f) ** 2)))
    else:
        trace["record_fork_mm"] = np.full(out["time_s"].size, math.nan)
    rest_offset = float(rest - out["stroke_mm"][0])
    shares = _shares(sr, values["spring_scale"], values["damper_N_s_per_m"])
    fork_off = None if sl.frest is None else float(sl.frest - out["fork_mm"][0])
    return Replay(sl.name, values, sd, trace, rms, sl.rise, rest_offset, float(sr.preload["shock"]), fork_off,
                  values["spring_scale"] * sr.shock_rate0, sr.shock_rate0, dict(sr.saddle), shares, fork_rms,
                  int(nfev), corr)


def at_bound(x: np.ndarray) -> list:
    """The shock's values (SHOCK_NAMES) at a bound (friction at 0 is no friction found, not a bound)."""
    return [k for k, v, lo, hi in zip(SHOCK_NAMES, x[6:], LOWER[6:], UPPER[6:])
            if hi - v < 1e-3 * (hi - lo) or (k != "friction_N" and v - lo < 1e-3 * (hi - lo))]


def replay(time_s, shock_mm, fork_mm=None, name: str = "record", bike="sst", rider_hz: float = RIDER_HZ,
           shock_max_mm: float | None = None, seated: SeatedReplay | None = None, start: dict | None = None,
           max_nfev: int = 40, max_relative_rms: float = MAX_RELATIVE_RMS) -> Replay:
    """The slam in (time_s, shock_mm) replayed through the bike and fitted (module docstring)."""
    from scipy.optimize import least_squares

    sr = seated or SeatedReplay(bike, rider_hz)
    sl = prepare_slam(time_s, shock_mm, fork_mm, name, sr, shock_max_mm, start)
    x0, base = sl.x0, sl.base
    # alternately: the push alone on the record up to its peak (the suspension held), then the
    # suspension with the slam's amplitude on the whole replay (the push's timing held); twice
    lo_u, hi_u = (LOWER - x0) / base, (UPPER - x0) / base
    u = np.zeros(len(NAMES))
    nfev = 0
    sol = None
    for _ in range(ROUNDS):
        nfev += fit_push(sl, u, max_nfev)

        def part(v):
            full = u.copy()
            full[FREE_INDEX] = v
            return sl.residual(x0 + full * base)

        sol = least_squares(part, u[FREE_INDEX], bounds=(lo_u[FREE_INDEX], hi_u[FREE_INDEX]), diff_step=1e-3,
                            max_nfev=max_nfev)
        u[FREE_INDEX] = sol.x
        nfev += sol.nfev
    x = x0 + u * base
    r = sol.fun
    rms = float(np.sqrt(np.mean(r * r)))
    if rms > max_relative_rms * sl.rise:
        raise BounceError(f"{name}: the replay through the bike cannot follow the record: RMS {rms:.1f} mm of a "
                          f"{sl.rise:.1f} mm slam (more than {100 * MAX_RELATIVE_RMS:.0f} %)")
    bound = at_bound(x)
    if bound:
        raise BounceError(f"{name}: the replay's {bound[0]} ends at its bound ({x[NAMES.index(bound[0])]:.4g}): "
                          f"the bike cannot describe the record within it")
    # intervals of all nine values together: the push's timing trades with the spring (conditional on
    # the timing, the spring's interval of a heavily damped slam missed the generator's value)
    J = jacobian(sl.residual, x, base, r)
    cov, tq = covariance(r, J)
    sd = {name_: float(math.sqrt(max(cov[i, i], 0.0)) * tq) for i, name_ in enumerate(NAMES)}
    return finish(sl, x, sd, rms, nfev, correlations(cov, list(NAMES)))


def jacobian(fn, x: np.ndarray, base: np.ndarray, r0: np.ndarray, step: float = 1e-3) -> np.ndarray:
    """d fn / d x by forward differences of ``step`` x ``base`` (a value at its upper bound steps down)."""
    J = np.empty((r0.size, x.size))
    for i in range(x.size):
        h = step * base[i] * (-1.0 if x[i] + step * base[i] > UPPER[i] else 1.0)
        xi = x.copy()
        xi[i] += h
        J[:, i] = (fn(xi) - r0) / h
    return J


def _shares(sr: SeatedReplay, scale: float, rebound: float) -> dict:
    """The rear mode's strain-energy shares (spring, rider's body, elsewhere) of the linear seated bike
    with the same compliant rider, the spring scaled (``bounce_bike.SeatedBike.energy_shares``)."""
    from mtbmj.identify.bounce_bike import SeatedBike

    if sr._linear is None:
        sr._linear = SeatedBike(sr.source_spec, rider_hz=sr.rider_hz)
    return sr._linear.energy_shares("shock", scale, rebound)


def replay_records(records, clicks, bike="sst", rider_hz: float | None = None) -> dict:
    """Each record's slam replayed (``fit bounce --replay``): {"summary": fit.json's "replay" list,
    "csv": replay_<file>.csv columns by name, "replays": the Replay objects, "lines": printed, "check":
    ``bounce.rebound_check``}. Each entry has "record_rebound" (``bounce.first_rebound``, model-free) and,
    replayed, "replay_rebound" (the same on the replay). A record whose replay is refused gets
    ``"refused"`` (the reason) and no values, trace or file."""
    sr = SeatedReplay(bike, RIDER_HZ if rider_hz is None else rider_hz)
    out = {"summary": [], "csv": {}, "replays": [], "lines": []}
    for rec, k in zip(records, clicks):
        name = record_name(rec)
        if rec.shock_mm is None:
            raise BounceError(f"{name}: no shock sensor: the replay fits the shock's slam")
        t, s = np.asarray(rec.time_s, float), np.asarray(rec.shock_mm, float)
        peak = find_slam(t, s, name)
        own = {"record_rebound": first_rebound(t, s, peak, _rest(t, s, t[peak]))}
        try:
            rp = replay(rec.time_s, rec.shock_mm, rec.fork_mm, name=name, seated=sr,
                        shock_max_mm=getattr(rec, "shock_max_mm", None))
        except BounceError as e:  # this record's replay says why, the others are still replayed
            out["summary"].append({"file": name, "clicks": k, "refused": str(e), **own})
            out["lines"].append(f"replay refused: {e}")
            continue
        tr = rp.trace
        top = int(np.argmax(np.where(np.abs(tr["time_s"]) < 0.1, tr["stroke_mm"], -np.inf)))
        own["replay_rebound"] = first_rebound(tr["time_s"], tr["stroke_mm"], top, rp.trace["stroke_mm"][0])
        out["summary"].append({"file": name, "clicks": k, **rp.summary(), **own})
        stem = str(name).rsplit("/", 1)[-1].rsplit(".", 1)[0]
        out["csv"][f"replay_{stem}.csv"] = rp.csv_columns()
        out["replays"].append(rp)
        out["lines"].append(f"{rp.line()} (at {k:g} clicks)")
    out["check"] = rebound_check(out["summary"])
    if out["check"] is not None:
        out["lines"].append(f"replay check: {out['check']['line']}")
    return out


def figure_png(replays) -> bytes:
    """replay.png: per record, the record's shock (and fork) beside the replay's, and the push."""
    from matplotlib.figure import Figure

    from mtbmj.readout.quicklook import png

    fig = Figure(figsize=(9.5, 3.0 * len(replays)))
    axes = fig.subplots(len(replays), 1, squeeze=False)
    for ax, rp in zip(axes[:, 0], replays):
        tr, v = rp.trace, rp.values
        ax.plot(tr["time_s"], tr["record_stroke_mm"], "k", lw=1.6, label="record: shock")
        ax.plot(tr["time_s"], tr["stroke_mm"], "C3", lw=1.2, label="replay: shock")
        if np.isfinite(tr["record_fork_mm"]).any():
            ax.plot(tr["time_s"], tr["record_fork_mm"], "k:", lw=1.0, label="record: fork")
            ax.plot(tr["time_s"], tr["fork_mm"], "C0:", lw=1.0, label="replay: fork (not fitted)")
        ax.set_ylabel("travel (mm)")
        ax.grid(alpha=0.3)
        twin = ax.twinx()
        twin.plot(tr["time_s"], tr["push_N"], "C2", lw=0.8, alpha=0.6)
        twin.set_ylabel("push on the rider (N, up +)", color="C2")
        ax.set_title(f"{rp.name}: spring {v['spring_scale']:.2f} x the bike file's, damper "
                     f"{v['damper_N_s_per_m']:.0f} N s/m, friction {v['friction_N']:.0f} N; RMS {rp.rms_mm:.2f} mm",
                     fontsize=9)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time from the slam's peak (s)")
    fig.tight_layout()
    return png(fig, dpi=80)


__all__ = ["METHOD", "NAMES", "RIDER_HZ", "Replay", "SeatedReplay", "figure_png", "push", "replay",
           "replay_records"]
