"""The spring settings that give a bike the sag a rider sets, front and rear (``mtbmj sag --bike``).

The bike stands on flat ground under its rider in the static equilibrium the runs start from
(``mtbmj.bike.run.prepare``: every spring, both tyres and the rider's legs and arms balanced; the
friction of the fork and the shock has no part in it). The sag is the fork's travel there over its
full travel, and the rear wheel's over the leverage table's. Two settings are solved together,
since the load each end carries moves with the other's sag: the fork's spring and the shock's,
each the key a rider turns for its spring (``KEYS``: an air spring's pressure, a coil's rate).

The result is written as a bike file on the given bike (``base``, with the ``--set`` changes and
the two solved keys), which ``mtbmj bike`` runs as is.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from mtbmj.errors import ConfigError

# the key a rider sets on each spring law, and a plausible range to search it in
KEYS = {"air": ("fork.spring.air_pressure_psi", 5.0, 500.0),
        "linear": ("fork.spring.rate_N_per_mm", 1.0, 1000.0),
        "progressive": ("fork.spring.progressive_rate_N_per_mm", 0.5, 500.0)}
SAG_TOLERANCE = 1e-4  # of the travel: 0.01 %


@dataclass
class BikeSag:
    bike: str
    base: str
    overrides: dict
    fork_key: str
    fork_value: float
    shock_key: str
    shock_value: float
    front_mm: float
    front_travel_mm: float
    rear_mm: float
    rear_travel_mm: float

    def line(self) -> str:
        return (f"{self.bike}: [fork.set] {self.fork_key} = {self.fork_value:.4g} gives "
                f"{100 * self.front_mm / self.front_travel_mm:.1f} % front sag ({self.front_mm:.1f} of "
                f"{self.front_travel_mm:g} mm), [shock.set] {self.shock_key} = {self.shock_value:.4g} gives "
                f"{100 * self.rear_mm / self.rear_travel_mm:.1f} % rear ({self.rear_mm:.1f} of {self.rear_travel_mm:g} mm "
                f"of wheel travel), friction left out")

    def toml(self, base: str) -> str:
        import json

        lines = [f'description = "{self.bike} set to {100 * self.front_mm / self.front_travel_mm:.1f} % front and '
                 f'{100 * self.rear_mm / self.rear_travel_mm:.1f} % rear sag by mtbmj sag --bike"',
                 f"base = {json.dumps(base)}"]
        tables: dict[str, dict] = {}
        for key, value in self.overrides.items():
            if key in ("fork.set", "shock.set"):
                tables.setdefault(key, {}).update(value)
            else:
                section, _, name = key.partition(".")
                tables.setdefault(section, {})[name] = value
        tables.setdefault("fork.set", {})[self.fork_key] = round(self.fork_value, 6)
        tables.setdefault("shock.set", {})[self.shock_key] = round(self.shock_value, 6)
        for section, values in tables.items():
            lines.append(f"\n[{section}]")
            for name, value in values.items():
                key = json.dumps(name) if "." in name else name
                lines.append(f"{key} = {json.dumps(value)}")
        return "\n".join(lines) + "\n"

    def write(self, out_dir) -> list[Path]:
        from mtbmj import output

        out = Path(out_dir)
        base = self.base
        if Path(base).suffix.lower() == ".toml":  # a file: named from the folder the new file is in
            base = os.path.relpath(Path(base).resolve(), out.resolve())
        # named after the bike it sets (out/my_sag/my_enduro_sag.toml): its runs are named so too
        return output.write_atomically(out, {self.file_name: self.toml(base).encode()})

    @property
    def file_name(self) -> str:
        return f"{self.bike}_sag.toml"


def _static(bike: str, overrides: dict) -> tuple[float, float, float, float]:
    """(front travel, its full travel, rear wheel travel, its full travel), m, at rest on flat ground."""
    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod

    p = bike_run.prepare(bike, "flat", 4.0, callback="python", overrides=overrides)
    b = p.bike
    fork = float(p.data.qpos[b.qpos_index("fork")])
    phi = float(p.data.qpos[b.qpos_index("swingarm")])
    _, z = spec_mod.rear_axle_in_frame(p.spec, phi)
    return fork, p.fork_setup.travel, float(z) - p.spec.rear_axle[1], p.spec.leverage.full_travel


def solve(bike: str, front_percent: float, rear_percent: float, overrides: dict | None = None) -> BikeSag:
    """The fork's and the shock's spring settings for ``front_percent`` and ``rear_percent`` sag."""
    from scipy.optimize import root

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod

    for name, value in (("--front-sag-percent", front_percent), ("--rear-sag-percent", rear_percent)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 < value < 100.0):
            raise ConfigError(f"{name}: must be within 0-100 %, got {value!r}")
    overrides = dict(overrides or {})
    spec = spec_mod.load(str(bike), overrides)
    fork_setup, shock_setup = bike_run.setups(spec)
    keys = []
    for end, setup in (("fork", fork_setup), ("shock", shock_setup)):
        model = setup.config.get("fork.spring.model")
        if model not in KEYS:
            raise ConfigError(f"{end}: a {model} spring has no sag setting here (known: {', '.join(KEYS)})")
        keys.append((KEYS[model], float(setup.config[KEYS[model][0]])))
    (fk, flo, fhi), f0 = keys[0]
    (sk, slo, shi), s0 = keys[1]
    target = (front_percent / 100.0, rear_percent / 100.0)

    def trial(u):
        fv, sv = f0 * math.exp(u[0]), s0 * math.exp(u[1])  # positive, and scaled alike
        if not (flo <= fv <= fhi and slo <= sv <= shi):
            return None, (fv, sv)
        ov = dict(overrides)
        ov["fork.set"] = {**ov.get("fork.set", {}), fk: fv}
        ov["shock.set"] = {**ov.get("shock.set", {}), sk: sv}
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the plausibility of trial values is not the user's concern
            return _static(str(bike), ov), (fv, sv)

    def residual(u):
        got, _ = trial(u)
        if got is None:
            return [10.0, 10.0]
        return [got[0] / got[1] - target[0], got[2] / got[3] - target[1]]

    from mtbmj.errors import RunError

    try:
        sol = root(residual, [0.0, 0.0], method="hybr", options={"xtol": 1e-10})
        got, (fv, sv) = trial(sol.x)
    except RunError as exc:
        raise ConfigError(f"sag: a trial setting has no static equilibrium ({exc})") from None
    if got is None or max(abs(r) for r in residual(sol.x)) > SAG_TOLERANCE:
        raise ConfigError(f"sag: no setting of {fk} within {flo:g}-{fhi:g} and {sk} within {slo:g}-{shi:g} gives "
                          f"{front_percent:g} % front and {rear_percent:g} % rear sag")
    return BikeSag(spec.name, str(bike), overrides, fk, fv, sk, sv, got[0] * 1e3, got[1] * 1e3, got[2] * 1e3,
                   got[3] * 1e3)
