"""A seat slam's ring-down read through the bike: the spring rate and the damper's coefficient of
the end that rang, from its damping ratio and damped frequency (``mtbmj.identify.bounce``).

A slam is ridden seated. The seated rider sits on the saddle with their centre of mass at
``rider.seated_com_mm`` and is held rigid on the frame: the body's seated vertical resonance lies
at 4-6 Hz (Griffin, Handbook of Human Vibration, 1990, ch. 5; ISO 2631-1), well above the 1-3 Hz
of a bike's sprung modes, so at those frequencies the seated body moves with the frame. The
limbs' share moves with the bike as when standing.

Method. The bike's planar equations (``mtbmj.bike.reference``: the same equations the MuJoCo bike
and the bike's cross-check use) with the rider's two coordinates held, coasting on flat ground, are
linearised about their seated static equilibrium by central differences: M q'' + C q' + K q = 0
over (x, z, pitch, fork, swingarm); the swingarm's stiffness is the secant over +-3 mm of wheel
travel, as a ring-down's swing sees a leverage table whose rounded ratios make its slope jump from
one millimetre to the next (the tangent at one point made the rear mode 0.6 % stiffer than the
MuJoCo bike's ring-down of the same model). Coulomb friction is left out (it is an amplitude-dependent loss
that an exponential envelope cannot carry; the bike file's friction is set to 0 here). Of the
two lowest oscillatory modes (the sprung bounce and pitch; the wheel-hop modes lie far above),
the one whose wheel travel is most at the end that rang is that end's mode. The end's spring is
scaled by ``a`` and its damper replaced by a linear one of coefficient ``c`` (both at the end's
own coordinate: shock stroke, or fork travel along the steering axis); (a, c) are solved so that
this mode has the measured damped frequency and damping ratio. The spring rate is a times the
bike file's rate at the static stroke (the geometric stiffness of the static force is kept); the
wheel rate is the spring rate over the leverage ratio squared at sag (the fork: its own, along the
steering axis), the wheel's damping likewise. The 95 % intervals carry the ring-down fit's
intervals of zeta and f_d (taken as independent) through the solution's Jacobian.

With ``rider_hz`` the rider is compliant instead (``fit bounce --rider-hz``): the rider's two
coordinates are free, on the bike file's legs (pedals) and arms (bars) and a saddle spring and
damper added on each so that, the frame held, each alone rings at ``rider_hz`` with a damping ratio
of 0.475 (``RIDER_SOURCE``); each reading then states the rider's share of the mode's strain energy
beside the spring's (``energy_shares``).

Shared with the MuJoCo bike: the masses, the geometry, the laws, the rigid seated rider. Not
shared: the linearisation, the modes and the inverse (``tests/test_bounce_bike.py`` checks them on
ring-downs the MuJoCo bike makes, and the modes on a closed form).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from mtbmj.bike import run as bike_run
from mtbmj.bike import spec as spec_mod
from mtbmj.bike.reference import NQ, Reference
from mtbmj.errors import ConfigError, MtbmjError
from mtbmj.identify.bounce import interval95

HELD = 2  # the rider's coordinates (rider_z, rider_pitch), the last two of the reference's q
N = NQ - HELD  # x, z, pitch, fork, swingarm
COORD = {"fork": 3, "shock": 4}
COAST_M_PER_S = 2.0  # the slam is ridden coasting; on flat ground the speed does not enter the linear modes
SECANT_TRAVEL_M = 3e-3  # the swingarm's stiffness: the secant over +-3 mm of wheel travel (six steps of the SST table)
MIN_RAD_PER_S = 0.1  # below this an eigenvalue's imaginary part is no oscillation (a bike's sprung modes: 1-3 Hz)
NO_FRICTION = {"fork.friction.coulomb_N": 0.0}
RIDER_ZETA = 0.475  # the seated body's damping ratio at its 5 Hz resonance (RIDER_SOURCE)
RIDER_SOURCE = ("Fairley and Griffin, 'The apparent mass of the seated human body: vertical vibration', J. Biomech. "
                "22 (1989): a one-degree-of-freedom model of 60 subjects' apparent mass at 5 Hz with a damping ratio of "
                "0.475 (as quoted in the Biomedical Engineering and Design Handbook, vol. 1, ch. 11); 4-6 Hz: Griffin, "
                "Handbook of Human Vibration (1990), ISO 2631-1")
RIDER_HZ = (4.0, 6.0)  # a seated body's vertical resonance
METHOD = ("the bike's planar equations with the seated rider held rigid on the frame (rider.seated_com_mm), "
          "coasting on flat ground, linearised about the seated static equilibrium (Coulomb friction left out); "
          "of the two lowest oscillatory modes, the one whose wheel travel is most at the end that rang; the end's "
          "spring scaled and its damper replaced by a linear one so that this mode has the measured damped "
          "frequency and damping ratio; 95 % intervals from the ring-down fit's, through the solution's Jacobian")


class SeatedBike:
    """The linearised seated bike of ``bike`` (a preset, a file or a ``BikeSpec``)."""

    def __init__(self, bike, overrides=None, rider_hz: float | None = None):
        spec = bike if isinstance(bike, spec_mod.BikeSpec) else spec_mod.load(str(bike), overrides)
        if spec.rider.seated_com is None:
            raise ConfigError(f"rider.seated_com_mm: {spec.name} gives no seated rider; a seat slam is read through "
                              f"the bike with the rider's centre of mass on the saddle (e.g. rider.seated_com_mm = "
                              f"[-90, 920], or the chart's saddle: geometry.seat_tube_angle_deg and saddle_height_mm)")
        frictionless = dataclasses.replace(spec, fork_overrides={**spec.fork_overrides, **NO_FRICTION},
                                           shock_overrides={**spec.shock_overrides, **NO_FRICTION})
        self.spec = spec
        # the seated static equilibrium, the rider's two coordinates held at the seat (bike.run.prepare)
        self.prepared = bike_run.prepare(frictionless, "flat", COAST_M_PER_S, drive="coast", callback="python",
                                         seated=True)
        self.ref = Reference(self.prepared)
        b = self.prepared.bike
        self.q = np.array([self.prepared.initial_qpos[b.qpos_index(n)]
                           for n in ("bike_x", "bike_z", "pitch", "fork", "swingarm")])
        self.rider_hz = rider_hz
        self.n = N if rider_hz is None else NQ  # a compliant rider: its two coordinates free
        if rider_hz is not None:
            self.q = np.concatenate((self.q, np.zeros(HELD)))  # the seated position (held at 0 by the seat)
        self.M, self.K, self.C = self._linear()
        self.saddle = None
        if rider_hz is not None:
            self.saddle = self._compliant(float(rider_hz))
        pl = self.ref.planar
        w, dw = pl.wheel_travel(self.q[4])
        self.rear_travel = w
        self.leverage_ratio = float(self.ref.lev.ratio_at(w))
        self.stroke = float(self.ref.lev.stroke(w))
        self.dw_dphi = dw
        # each end's coordinate to its travel: the shock's stroke per swingarm radian, the fork's 1
        self.d_end = {"shock": dw / self.leverage_ratio, "fork": 1.0}
        self.at = {"shock": self.stroke, "fork": float(self.q[3])}
        self.rate, self.damping = {}, {}
        for end, law in (("fork", self.ref.fork), ("shock", self.ref.shock)):
            x = self.at[end]
            h = 1e-6
            self.rate[end] = (_force(law, x + h, 0.0) - _force(law, x - h, 0.0)) / (2 * h)
            self.damping[end] = (_force(law, x, 1e-5) - _force(law, x, -1e-5)) / 2e-5

    def _full(self, qa, qda):
        pad = np.zeros(NQ - qa.size)
        q = np.concatenate((qa, pad))
        qd = np.concatenate((qda, pad))
        y = np.concatenate((q, qd, np.zeros(self.ref.nf + self.ref.ns)))
        Q, out = self.ref.forces(0.0, y)
        return (Q + out["static"])[:qa.size]

    def _linear(self):
        q0 = self.q
        n = q0.size
        qd0 = np.zeros(n)
        qd0[0] = COAST_M_PER_S
        K = np.zeros((n, n))
        C = np.zeros((n, n))
        for j in range(n):
            # the swingarm's column as the secant over +-SECANT_TRAVEL_M of wheel travel: a leverage
            # table's slope, its ratios rounded per step, jumps from one step to the next, and a
            # ring-down's swing spans several steps (the other columns' laws are smooth: 1e-7)
            h = SECANT_TRAVEL_M / abs(self.ref.planar.wheel_travel(q0[4])[1]) if j == 4 else 1e-7
            e = np.zeros(n)
            e[j] = h
            K[:, j] = -(self._full(q0 + e, qd0) - self._full(q0 - e, qd0)) / (2 * h)
            ev = np.zeros(n)
            ev[j] = 1e-5
            C[:, j] = -(self._full(q0, qd0 + ev) - self._full(q0, qd0 - ev)) / 2e-5
        M = self.ref.planar.mass_matrix(np.concatenate((q0, np.zeros(NQ - n))))[:n, :n]
        return M, K, C

    def _compliant(self, hz: float) -> dict:
        """The seated body made compliant: the saddle's spring and damper on the rider's two
        coordinates (beside the legs on the pedals and the arms on the bars the reference already
        has) so that each coordinate alone, the frame held, rings at ``hz`` with the damping ratio
        RIDER_ZETA (the seated body's apparent mass: 5 Hz and 0.475, Fairley and Griffin 1989); the
        legs and arms couple the two, so the frame-held rider's two modes straddle ``hz`` (4.4 and 5.6
        Hz at 5 Hz on the sst preset), given as ``frame_held_rider_hz``. The saddle's preload, which
        makes the seated position an equilibrium, is left out of the stiffness (its turning with the
        rider's pitch). Returns the saddle's rates and dampings and the frame-held rider's modes."""
        out = {"resonance_hz": hz, "damping_ratio": RIDER_ZETA, "source": RIDER_SOURCE}
        w2 = (2 * math.pi * hz) ** 2
        r = slice(N, N + HELD)
        for i, name in ((N, "vertical"), (N + 1, "pitch")):  # each coordinate's own diagonal at hz
            add_k = max(self.M[i, i] * w2 - self.K[i, i], 0.0)
            self.K[i, i] += add_k
            add_c = max(2 * RIDER_ZETA * math.sqrt(self.K[i, i] * self.M[i, i]) - self.C[i, i], 0.0)
            self.C[i, i] += add_c
            out[f"saddle_{name}_rate"] = float(add_k)
            out[f"saddle_{name}_damping"] = float(add_c)
        lam = np.linalg.eigvals(np.linalg.solve(self.M[r, r], self.K[r, r]))
        out["frame_held_rider_hz"] = sorted(float(math.sqrt(max(v.real, 0.0)) / (2 * math.pi)) for v in lam)
        return out

    def energy_shares(self, end: str, scale: float, coefficient: float) -> dict:
        """The end's undamped mode: the shares of its strain energy in the end's spring, in the rider's
        body (the saddle, legs and arms on the rider's coordinates) and elsewhere (the other end, the
        tires), from the symmetric part of K."""
        M, _, K = self.matrices(end, scale, coefficient)
        Ks = 0.5 * (K + K.T)
        lam, vec = np.linalg.eig(np.linalg.solve(M, Ks))
        i, d = COORD[end], self.d_end[end]
        want = self.mode_of(end, scale, coefficient)["frequency_hz"]
        k = int(np.argmin([abs(math.sqrt(max(v.real, 0.0)) / (2 * math.pi) - want) for v in lam]))
        v = vec[:, k].real
        total = float(v @ Ks @ v)
        spring = scale * self.rate[end] * d * d * v[i] ** 2
        rider = float(v[N:] @ Ks[N:, N:] @ v[N:]) if self.n > N else 0.0
        return {"spring": float(spring / total), "rider": float(rider / total),
                "other": float(1.0 - (spring + rider) / total)}

    def matrices(self, end: str, scale: float = 1.0, coefficient: float | None = None):
        """(M, C, K) with ``end``'s spring rate scaled by ``scale`` and its damper a linear one of
        ``coefficient`` N s/m (None: the bike file's, linearised at rest)."""
        i, d = COORD[end], self.d_end[end]
        K = self.K.copy()
        C = self.C.copy()
        K[i, i] += (scale - 1.0) * self.rate[end] * d * d
        if coefficient is not None:
            C[i, i] += (coefficient - self.damping[end]) * d * d
        return self.M, C, K

    def modes(self, end: str, scale: float = 1.0, coefficient: float | None = None) -> list[dict]:
        """The oscillatory modes, lowest first: frequency_hz (damped), damping_ratio, and each end's
        share of the wheel travel in the mode (``front_share``, ``rear_share``)."""
        M, C, K = self.matrices(end, scale, coefficient)
        Minv = np.linalg.inv(M)
        n = self.n
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
        lam, vec = np.linalg.eig(A)
        sin_head = math.sin(self.spec.head_angle)
        out = []
        for k in np.argsort(lam.imag):
            if lam[k].imag <= MIN_RAD_PER_S:  # a rigid-body mode (the bike's roll along the ground) or overdamped
                continue
            v = vec[:n, k]
            front = abs(v[3]) * sin_head  # the front wheel's travel (vertical)
            rear = abs(v[4] * self.dw_dphi)
            mag = abs(lam[k])
            out.append({"frequency_hz": float(lam[k].imag / (2 * math.pi)), "damping_ratio": float(-lam[k].real / mag),
                        "front_share": float(front / (front + rear)), "rear_share": float(rear / (front + rear))})
        return sorted(out, key=lambda m: m["frequency_hz"])

    def mode_of(self, end: str, scale: float = 1.0, coefficient: float | None = None) -> dict:
        """The sprung mode of ``end``: of the two lowest oscillatory modes, the one with the larger
        share of wheel travel at that end."""
        modes = self.modes(end, scale, coefficient)[:2]
        if not modes:
            raise MtbmjError(f"{self.spec.name}: the seated bike has no oscillating sprung mode")
        key = "rear_share" if end == "shock" else "front_share"
        return max(modes, key=lambda m: m[key])

    def solve(self, end: str, zeta: float, fd_Hz: float) -> tuple[float, float]:
        """(spring-rate scale, damper coefficient N s/m) whose ``end`` mode has ``zeta`` and ``fd_Hz``."""
        from scipy.optimize import fsolve

        if not (0.0 < zeta < 1.0 and fd_Hz > 0.0):
            raise MtbmjError(f"{end}: a damping ratio of {zeta:.3f} at {fd_Hz:.3f} Hz cannot be read through the bike "
                             f"(it needs 0 < zeta < 1 and a positive frequency)")
        c0 = self.damping[end] if self.damping[end] > 0 else 1000.0

        def residual(p):
            m = self.mode_of(end, math.exp(p[0]), p[1] * c0)
            return [m["frequency_hz"] / fd_Hz - 1.0, m["damping_ratio"] - zeta]

        # the start: a single degree of freedom's scaling from the bike file's own mode (the rate with
        # the undamped frequency squared, the damper with zeta times the square root of the rate)
        own = self.mode_of(end)
        fn0 = own["frequency_hz"] / math.sqrt(1.0 - own["damping_ratio"] ** 2)
        a0 = (fd_Hz / math.sqrt(1.0 - zeta * zeta) / fn0) ** 2
        start = [math.log(a0), zeta / max(own["damping_ratio"], 1e-3) * math.sqrt(a0) * self.damping[end] / c0]
        p = fsolve(residual, start, xtol=1e-12, full_output=True)[0]  # judged by its residual (it may stop short of xtol)
        if not np.all(np.isfinite(p)) or max(abs(r) for r in residual(p)) > 1e-9 or p[1] <= 0:
            raise MtbmjError(f"{end}: no spring rate and damper of the bike give a mode at {fd_Hz:.3f} Hz with a damping "
                             f"ratio of {zeta:.3f} (the seated bike's modes cannot reach it)")
        return math.exp(p[0]), float(p[1] * c0)

    def identify(self, end: str, zeta: float, zeta_sd: float, fd_Hz: float, fd_sd: float) -> dict:
        """The end's spring and damper from its ring-down, with 95 % intervals, as ``fit.json`` gives them."""
        a, c = self.solve(end, zeta, fd_Hz)
        J = np.zeros((2, 2))
        for j, (h, args) in enumerate(((1e-4, (zeta + 1e-4, fd_Hz)), (1e-4 * fd_Hz, (zeta, fd_Hz * (1 + 1e-4))))):
            a2, c2 = self.solve(end, *args)
            J[:, j] = [(a2 - a) / h, (c2 - c) / h]
        sd = np.sqrt(np.diag(J @ np.diag([zeta_sd ** 2, fd_sd ** 2]) @ J.T)) if np.isfinite([zeta_sd, fd_sd]).all() \
            else np.full(2, math.nan)
        rate = self.rate[end]
        wheel = self.leverage_ratio ** 2 if end == "shock" else 1.0
        own = self.mode_of(end)
        return {
            "spring_rate_N_per_mm": a * rate / 1e3,
            "spring_rate_N_per_mm_ci95": interval95(a * rate / 1e3, sd[0] * rate / 1e3),
            "bike_file_spring_rate_N_per_mm": rate / 1e3, "spring_rate_over_bike_file": a,
            "wheel_rate_N_per_mm": a * rate / wheel / 1e3,
            "wheel_rate_N_per_mm_ci95": interval95(a * rate / wheel / 1e3, sd[0] * rate / wheel / 1e3),
            "damper_N_s_per_m": c, "damper_N_s_per_m_ci95": interval95(c, sd[1]),
            "bike_file_damper_N_s_per_m": self.damping[end],
            "wheel_damping_N_s_per_m": c / wheel, "wheel_damping_N_s_per_m_ci95": interval95(c / wheel, sd[1] / wheel),
            "leverage_ratio_at_sag": self.leverage_ratio if end == "shock" else None,
            "seated_sag_mm": self.rear_travel * 1e3 if end == "shock" else float(self.q[3]) * 1e3,
            "bike_file_mode": {"frequency_hz": own["frequency_hz"], "damping_ratio": own["damping_ratio"]},
            **({"rider": {**self.saddle, "mode_strain_energy_share": self.energy_shares(end, a, c)}}
               if self.saddle is not None else {}),
        }


def _force(law, x: float, v: float) -> float:
    return float(law.force(x, v, 0.0) if law.has_state else law.force(x, v))


__all__ = ["METHOD", "SeatedBike"]
