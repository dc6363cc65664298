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
from dataclasses import dataclass
from pathlib import Path

from mtbmj.errors import ConfigError

# the key a rider sets on each spring law, and a plausible range to search it in
KEYS = {"air": ("fork.spring.air_pressure_psi", 5.0, 500.0),
        "linear": ("fork.spring.rate_N_per_mm", 1.0, 1000.0),
        "progressive": ("fork.spring.progressive_rate_N_per_mm", 0.5, 500.0)}
SAG_TOLERANCE = 1e-4  # of the travel: 0.01 %


VERIFY_TOLERANCE = 0.01  # of the travel: the written file's sag against the one printed


@dataclass
class BikeSag:
    bike: str
    base: str
    overrides: dict  # what the solved bike is: the --set changes with the two solved keys
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

    def table(self) -> dict:
        """The bike as one self-contained table: :func:`written_table` of the bike and the overrides
        it was solved with."""
        return written_table(self.base, self.overrides)

    def toml(self) -> str:
        description = (f"{self.bike} set to {100 * self.front_mm / self.front_travel_mm:.1f} % front and "
                       f"{100 * self.rear_mm / self.rear_travel_mm:.1f} % rear sag by mtbmj sag --bike "
                       f"({self.fork_key} = {self.fork_value:.6g}, shock {self.shock_key} = {self.shock_value:.6g}); "
                       f"every key of {self.base.encode('utf-8', 'replace').decode()} with its --set changes, its "
                       f"bases and leverage CSV written in")
        return toml_text({"description": description, **self.table()})

    def verify(self, text: str) -> None:
        """Load ``text`` as a bike file from a folder of its own and solve its static sag with the code
        every run starts from: the same bike as solved, sagging within ``VERIFY_TOLERANCE`` of each
        travel of the sag printed, or a ``ConfigError`` (one line) and nothing written."""
        import tempfile
        import warnings

        from mtbmj.errors import MtbmjError

        with tempfile.TemporaryDirectory(prefix="mtbmj-sag-") as folder, warnings.catch_warnings():
            warnings.simplefilter("ignore")  # its plausibility notes were given when the bike was read
            path = Path(folder) / self.file_name
            path.write_text(text)
            try:
                differs = _difference(str(path), self.base, self.overrides)
                got = None if differs else _static(str(path), {})
            except MtbmjError as exc:
                raise ConfigError(f"sag: the bike file it would write does not run ({exc}); nothing written") from None
        if differs:
            raise ConfigError(f"sag: the bike file it would write is not the bike it solved ({differs} differs); "
                              f"nothing written")
        front, rear = got[0] * 1e3, got[2] * 1e3
        for end, printed, written, travel in (("front", self.front_mm, front, self.front_travel_mm),
                                              ("rear", self.rear_mm, rear, self.rear_travel_mm)):
            if not abs(written - printed) <= VERIFY_TOLERANCE * travel:
                raise ConfigError(f"sag: the bike file it would write sags {100 * written / travel:.1f} % at the {end}, "
                                  f"not the {100 * printed / travel:.1f} % solved; nothing written")

    def write(self, out_dir) -> list[Path]:
        """``OUT/BIKE_sag.toml``, checked by :meth:`verify` first: a bike file that runs as is from
        any folder (no ``base`` and no relative path in it)."""
        from mtbmj import output

        text = self.toml()
        self.verify(text)
        # named after the bike it sets (out/my_sag/my_enduro_sag.toml): its runs are named so too
        return output.write_atomically(Path(out_dir), {self.file_name: text.encode()})

    @property
    def file_name(self) -> str:
        return f"{self.bike}_sag.toml"


def _ordered(overrides: dict) -> dict:
    """``overrides`` with ``fork.set`` and ``shock.set`` last: a ``--set shock.KEY`` of a shock as sold
    (which sets ``[shock.set]`` keys) never overwrites a ``[shock.set]`` key given with them."""
    out = {k: v for k, v in overrides.items() if k not in ("fork.set", "shock.set")}
    for key in ("fork.set", "shock.set"):
        if key in overrides:
            out[key] = overrides[key]
    return out


def written_table(bike: str, overrides: dict) -> dict:
    """The bike ``bike`` with ``overrides`` as one bike file's table that loads to the same bike from
    any folder: its ``base`` chain merged and the overrides applied (``mtbmj.bike.spec.read_table``
    and ``overridden``, as every run reads them), then

    - a leverage CSV written in as its two lists;
    - a fork or shock configuration file named by its absolute path;
    - a shock's keys as sold (``[shock] spring_rate_lb_per_in``, ...) left out: they are in its
      ``[shock.set]`` already, where a key as sold would overwrite a solved one;
    - a geometry chart's fork keys (wheel diameter, fork travel and length) left out of ``[fork.set]``,
      where the chart sets them (a ``--fork-set`` that gives one otherwise is refused naming both)."""
    from mtbmj.bike import chart as chart_mod
    from mtbmj.bike import shock as shock_mod
    from mtbmj.bike import spec as spec_mod
    from mtbmj.config import preset_names

    table = spec_mod.overridden(spec_mod.read_table(str(bike))[0], _ordered(overrides))
    table = {k: (dict(v) if isinstance(v, dict) else v) for k, v in table.items() if k not in ("description", "reading")}
    lev = table.get("leverage")
    if isinstance(lev, dict) and "csv" in lev:
        w, r = spec_mod.read_leverage_csv(lev["csv"])
        table["leverage"] = {**{k: v for k, v in lev.items() if k != "csv"}, "wheel_travel_mm": w, "ratio": r}
    for section in ("fork", "shock"):
        part = table.get(section)
        if not isinstance(part, dict):
            continue
        config = part.get("config")
        if isinstance(config, str) and not any(config.lower() == n.lower() for n in preset_names()):
            part["config"] = str(Path(config).resolve())
        if isinstance(part.get("set"), dict):
            part["set"] = dict(part["set"])
    shock = table.get("shock")
    if isinstance(shock, dict):
        table["shock"] = {k: v for k, v in shock.items() if k not in shock_mod.KEYS}
    geo, fork = table.get("geometry"), table.get("fork")
    if isinstance(geo, dict) and isinstance(fork, dict) and isinstance(fork.get("set"), dict):
        from_chart = chart_mod.fork_keys(geo)
        for key, value in from_chart.items():
            if key in fork["set"] and fork["set"][key] != value:
                chart_key = next(k for k, v in chart_mod.FORK.items() if v == key)
                raise ConfigError(f"--fork-set {key}: this bike's geometry chart gives it (geometry.{chart_key}); "
                                  f"set geometry.{chart_key} instead")
        fork["set"] = {k: v for k, v in fork["set"].items() if k not in from_chart}
    return table


def toml_text(table: dict) -> str:
    """``table`` (scalars, lists of scalars, nested tables) as TOML text that ``tomllib`` reads back to it."""
    import json

    def key(name) -> str:
        name = str(name)
        return name if name.replace("_", "").replace("-", "").isalnum() and name.isascii() else json.dumps(name)

    def value(v) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int):
            return str(v)
        if isinstance(v, float):
            if not math.isfinite(v):
                raise ConfigError(f"sag: a value of the bike is not finite ({v!r})")
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        raise ConfigError(f"sag: cannot write {v!r} in a bike file")

    lines: list[str] = []

    def emit(path: list[str], part: dict) -> None:
        scalars = {k: v for k, v in part.items() if not isinstance(v, dict)}
        tables = {k: v for k, v in part.items() if isinstance(v, dict)}
        if path:
            lines.append("")
            lines.append("[" + ".".join(key(p) for p in path) + "]")
        for name, v in scalars.items():
            lines.append(f"{key(name)} = {value(v)}")
        for name, v in tables.items():
            emit(path + [name], v)

    emit([], table)
    return "\n".join(lines) + "\n"


def _difference(written: str, bike: str, overrides: dict) -> str | None:
    """The first part in which the bike file ``written`` differs from ``bike`` with ``overrides``
    (None: the same bike, configurations compared by their values)."""
    import dataclasses

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod

    specs = [spec_mod.load(written), spec_mod.load(str(bike), _ordered(overrides))]
    setups = [bike_run.setups(s) for s in specs]
    for name, (a, b) in (("the fork's configuration", (setups[0][0], setups[1][0])),
                         ("the shock's configuration", (setups[0][1], setups[1][1]))):
        if a.config.digest() != b.config.digest():
            return name
    skip = {"name", "source", "overrides", "fork_config", "shock_config", "shock_sold"}  # (which keys, not values)
    for f in dataclasses.fields(specs[0]):
        if f.name not in skip and getattr(specs[0], f.name) != getattr(specs[1], f.name):
            return f.name
    return None


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
            raise ConfigError(f"{name}: must be above 0 and below 100 %, got {value!r}")  # 100 % was "within 0-100"
    overrides = dict(overrides or {})
    spec = spec_mod.load(str(bike), _ordered(overrides))
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

    def solved(fv, sv) -> dict:  # the overrides with the two settings, applied after every other key
        ov = _ordered(overrides)
        ov["fork.set"] = {**ov.get("fork.set", {}), fk: fv}
        ov["shock.set"] = {**ov.get("shock.set", {}), sk: sv}
        return ov

    def trial(u):
        fv, sv = f0 * math.exp(u[0]), s0 * math.exp(u[1])  # positive, and scaled alike
        if not (flo <= fv <= fhi and slo <= sv <= shi):
            return None, (fv, sv)
        ov = solved(fv, sv)
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
        small = [(p, end) for p, end in ((front_percent, "front"), (rear_percent, "rear")) if p < 1.0]
        fraction = (f" ({' and '.join(f'{p:g} % {end}' for p, end in small)}: a fraction typed for a percent? "
                    f"{small[0][0]:g} is {small[0][0] * 100:g} %)" if small else "")
        raise ConfigError(f"sag: no setting of {fk} within {flo:g}-{fhi:g} and {sk} within {slo:g}-{shi:g} gives "
                          f"{front_percent:g} % front and {rear_percent:g} % rear sag{fraction}")
    return BikeSag(spec.name, str(bike), solved(fv, sv), fk, fv, sk, sv, got[0] * 1e3, got[1] * 1e3, got[2] * 1e3,
                   got[3] * 1e3)
