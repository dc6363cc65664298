"""Writes the configuration reference, docs/configuration.md, from ``mtbmj.config.SCHEMA``.

Every key's unit (from its name), default (the reference preset's value), valid values (the
schema's kind), plausible range (``mtbmj.config.PLAUSIBLE``) and meaning (``MEANINGS`` below).
Regenerate the page after changing the schema; ``tests/test_config_reference.py`` fails while the
page and the schema disagree::

    python docs/configuration.py > docs/configuration.md
"""
from __future__ import annotations

import sys
import warnings

from mtbmj import config as cfg

# One sentence or two per key: what it is, which model uses it. Values and their origins are in
# mtbmj/presets/reference.toml and the README's "Parameters".
MEANINGS: dict[str, str] = {
    "description": "One line saying what the configuration is (shown by `mtbmj presets`).",
    "reading": "How the configuration reads the paper (the presets S1-S14 state it); informational.",
    # sled
    "sled.body_mass_kg": "Sprung mass on the fork: the sled (or the front share of rider and bike less the front "
                         "wheel). Give it, or the three rider inputs below, not both.",
    "sled.rider_mass_kg": "Rider mass, with gear. Rider input: with `sled.bike_mass_kg` and "
                          "`sled.front_share_percent` it sets `sled.body_mass_kg` (see *The load in a rider's terms*).",
    "sled.bike_mass_kg": "Whole bike mass, front wheel included. Rider input (see `sled.rider_mass_kg`).",
    "sled.front_share_percent": "Share of the weight of rider and bike on the front wheel (what scales under the "
                                "wheels read). Rider input (see `sled.rider_mass_kg`); at most 100.",
    "sled.wheel_mass_kg": "Unsprung mass below the fork's spring: the front wheel with its tire (on a bike also "
                          "the brake rotor and the fork's lower legs).",
    "sled.drop_height_mm": "Height of the tire's tread above the ground at release (impact speed sqrt(2 g h)); "
                           "0 sets the sled down without a drop.",
    "sled.gravity_m_per_s2": "Gravitational acceleration.",
    # fork
    "fork.travel_mm": "Fork travel: compression from full extension to the bottom-out stop.",
    "fork.length_mm": "Axle to crown (geometry of the MuJoCo model only; no effect on the drop).",
    "fork.spring.model": "Spring law: linear (S1), compression_rebound (S2), bilinear (S3, S4, S6), progressive "
                         "(S5, S7-S14) or air (an air spring from its chambers).",
    "fork.spring.rate_N_per_mm": "Rate of the linear spring (model linear).",
    "fork.spring.rate_lb_per_in": "The linear spring's rate in lb/in, as coil springs are sold; converted to "
                                  "`fork.spring.rate_N_per_mm` when read. Give one of the two.",
    "fork.spring.compression_rate_N_per_mm": "Rate while compressing (model compression_rebound).",
    "fork.spring.rebound_rate_N_per_mm": "Rate while extending (model compression_rebound; bilinear with "
                                         "`rebound_curve`).",
    "fork.spring.knee_mm": "Compression at which the bilinear spring changes rate (model bilinear).",
    "fork.spring.rate_below_knee_N_per_mm": "Bilinear spring's rate below the knee.",
    "fork.spring.rate_above_knee_N_per_mm": "Bilinear spring's rate above the knee.",
    "fork.spring.rebound_curve": "Bilinear spring extends along `rebound_rate_N_per_mm` instead of its compression "
                                 "curve (S3, S4, S6). Default false.",
    "fork.spring.progressive_rate_N_per_mm": "Linear term k of the progressive spring F = k x + c x^3.",
    "fork.spring.progressive_cubic_N_per_mm3": "Cubic term c of the progressive spring F = k x + c x^3.",
    "fork.spring.top_out": "Use the top-out spring against the main spring near full extension. Default: true "
                           "when `top_out_rate_N_per_mm` is given.",
    "fork.spring.top_out_rate_N_per_mm": "Rate of the top-out spring (engaged below preload / rate, and past "
                                         "full extension).",
    "fork.spring.preload": "Apply `preload_N` to the main spring (needs the top-out spring). Default: true when "
                           "`preload_N` is given. Air springs take their preload from the pressure.",
    "fork.spring.preload_N": "Main-spring force at full extension (coil preload).",
    "fork.spring.direction_band_mm_per_s": "Speed band over which the compression and rebound curves blend "
                                           "(numerical). Default 20.",
    "fork.spring.air_pressure_psi": "Air spring: gauge pressure of the positive chamber at full extension "
                                    "(model air); not below 0.",
    "fork.spring.air_pressure_bar": "The same in bar, as some pumps read; converted to `air_pressure_psi` when "
                                    "read. Give one of the two.",
    "fork.spring.piston_diameter_mm": "Air spring: piston (seal head) diameter.",
    "fork.spring.air_volume_cm3": "Air spring: positive-chamber volume at full extension, without spacers.",
    "fork.spring.tokens": "Air spring: number of volume spacers (whole). Default 0.",
    "fork.spring.token_volume_cm3": "Air spring: volume of one spacer.",
    "fork.spring.negative_volume_cm3": "Air spring: negative-chamber volume at full extension. Default 0 (none).",
    "fork.spring.transfer_port_mm": "Air spring: compression at which the seal passes the port joining the "
                                    "chambers. Default 0.",
    "fork.spring.polytropic_index": "Air spring: polytropic index n, from 1 (isothermal) to 1.4 (adiabatic).",
    # damper
    "fork.damper.model": "Damper law: linear, bilinear (compression and rebound slopes), digressive (two "
                         "stages per direction), orifice (a bleed and an orifice: linear plus quadratic in speed), "
                         "table (velocity-force lookup) or clicks (tables per adjuster position).",
    "fork.damper.coefficient_N_s_per_m": "Linear damper's coefficient (model linear).",
    "fork.damper.compression_N_s_per_m": "Bilinear damper: coefficient in compression.",
    "fork.damper.rebound_N_s_per_m": "Bilinear damper: coefficient in rebound.",
    "fork.damper.compression_low_N_s_per_m": "Digressive damper: compression slope below the knee speed.",
    "fork.damper.compression_high_N_s_per_m": "Digressive damper: compression slope above the knee speed.",
    "fork.damper.compression_knee_mm_per_s": "Digressive damper: compression knee speed.",
    "fork.damper.rebound_low_N_s_per_m": "Digressive damper: rebound slope below the knee speed.",
    "fork.damper.rebound_high_N_s_per_m": "Digressive damper: rebound slope above the knee speed.",
    "fork.damper.rebound_knee_mm_per_s": "Digressive damper: rebound knee speed.",
    "fork.damper.bleed_N_s_per_m": "Orifice damper: the bleed's coefficient, b in F = b v + c v abs(v).",
    "fork.damper.compression_orifice_N_s2_per_m2": "Orifice damper: c in compression (force = c v^2 at speed v "
                                                   "past the bleed).",
    "fork.damper.rebound_orifice_N_s2_per_m2": "Orifice damper: c in rebound.",
    "fork.damper.velocity_mm_per_s": "Table and clicks dampers: velocities of the table, strictly increasing, "
                                     "negative (rebound) to positive (compression).",
    "fork.damper.force_N": "Table damper: force at each velocity (0 at 0, never falling; the friction offset "
                           "belongs in fork.friction).",
    "fork.damper.compression_clicks": "Clicks damper: compression adjuster setting, clicks from closed.",
    "fork.damper.rebound_clicks": "Clicks damper: rebound adjuster setting, clicks from closed.",
    "fork.damper.compression_clicks_measured": "Clicks damper: compression positions measured on the dyno "
                                               "(whole clicks, increasing).",
    "fork.damper.rebound_clicks_measured": "Clicks damper: rebound positions measured on the dyno.",
    "fork.damper.compression_force_N": "Clicks damper: one row of compression forces per measured position "
                                       "(at the positive velocities).",
    "fork.damper.rebound_force_N": "Clicks damper: one row of rebound forces per measured position (at the "
                                   "negative velocities).",
}
for _circuit, _what in (("low_speed_compression", "low-speed compression"),
                        ("high_speed_compression", "high-speed compression"),
                        ("low_speed_rebound", "low-speed rebound"), ("high_speed_rebound", "high-speed rebound")):
    MEANINGS.update({
        f"fork.damper.{_circuit}_clicks": f"Clicks damper with separate adjusters: {_what} setting, clicks from "
                                          "closed.",
        f"fork.damper.{_circuit}_clicks_measured": f"Clicks damper: {_what} positions measured on the dyno.",
        f"fork.damper.{_circuit}_force_N": f"Clicks damper: one row of forces per measured {_what} position.",
        f"fork.damper.{_circuit}_reference_clicks": f"Clicks damper: where the {_what} adjuster stood while the "
                                                    "other adjuster of its stroke was measured.",
    })
MEANINGS.update({
    # friction
    "fork.friction.model": "Friction law of seals and bushings: none, coulomb, coulomb_viscous, stiction, "
                           "stribeck or lugre. Default none.",
    "fork.friction.coulomb_N": "Sliding (Coulomb) friction force.",
    "fork.friction.breakaway_N": "Breakaway (static) friction force: stiction, Stribeck and LuGre laws.",
    "fork.friction.viscous_N_s_per_m": "Viscous friction coefficient (coulomb_viscous and the variants).",
    "fork.friction.stiction_band_mm_per_s": "Stiction law: speed band counted as stuck (Karnopp).",
    "fork.friction.stribeck_velocity_mm_per_s": "Stribeck and LuGre laws: Stribeck speed.",
    "fork.friction.stribeck_exponent": "Stribeck law: shape exponent (2 = Gaussian). Default 2.",
    "fork.friction.sign_band_mm_per_s": "Speed band of the regularised sign of the sliding velocity "
                                        "(numerical). Default 5.",
    "fork.friction.bristle_stiffness_N_per_mm": "LuGre law: bristle stiffness.",
    "fork.friction.bristle_damping_N_s_per_m": "LuGre law: bristle damping.",
    "fork.friction.stick": "Static friction laws stick at rest (an elasto-plastic bristle). Default true.",
    "fork.friction.stick_stiffness_N_per_mm": "Stiffness of the stuck fork (presliding of seals and bushings).",
    "fork.friction.stick_damping_N_s_per_m": "Damping of the stuck fork.",
    "fork.friction.stick_damping_velocity_mm_per_s": "Speed above which that damping fades.",
    # stops
    "fork.stops.bumper_length_mm": "Bottom-out bumper: engages over this last part of the travel.",
    "fork.stops.bumper_force_N": "Bottom-out bumper's force at full travel (quadratic rise).",
    "fork.stops.stop_rate_N_per_mm": "Hard stops past full travel and full extension.",
    "fork.stops.stop_damping_N_s_per_m": "Damping of the hard stops.",
    "fork.stops.extension_mm": "Hard top stop this far past full extension.",
    # tire
    "tire.model": "Tire law: impact (impact values throughout), switch (impact values until the first topping "
                  "event, then in-contact values), undamped or static.",
    "tire.radius_mm": "Tire's outer radius (geometry; the rolling front end rolls on it).",
    "tire.impact_rate_N_per_mm": "Radial rate on impact.",
    "tire.impact_damping_N_s_per_m": "Radial damping on impact.",
    "tire.contact_rate_N_per_mm": "Radial rate in settled contact (switch tire).",
    "tire.contact_damping_N_s_per_m": "Radial damping in settled contact (switch tire).",
    "tire.static_rate_N_per_mm": "Static radial rate (static tire).",
    "tire.max_deflection_mm": "Tire deflection at which the rim strikes.",
    "tire.rim_rate_N_per_mm": "Rate of a rim strike past the maximum deflection.",
    "tire.rim_damping_N_s_per_m": "Damping of a rim strike.",
    "tire.pressure_psi": "Gauge pressure; sets the impact, in-contact and static rates, taking precedence over "
                         "their own keys (damping keeps its values; see *Tire pressure*). Above 0.",
    "tire.pressure_bar": "The same in bar; converted to `tire.pressure_psi` when read. Give one of the two.",
    # solver
    "solver.duration_s": "Simulated time of a drop.",
    "solver.timestep_s": "Engine step (the output grid); default chosen from the configuration's stiffness.",
    "solver.integrator": "MuJoCo integrator.",
    "solver.ode_method": "Integrator of the ODE reference (scipy).",
    "solver.ode_rtol": "ODE reference: relative tolerance.",
    "solver.ode_atol_mm": "ODE reference: absolute tolerance.",
    "solver.sample_rate_Hz": "Logging rate of the written time series (the sled's logger: 1 kHz).",
    "solver.antialias_Hz": "Anti-aliasing low-pass before logging; below half the sample rate.",
})

# keys whose name carries no unit
COUNTS = {"fork.spring.tokens": "spacers"}


def unit(key: str) -> str:
    if cfg.unit_of(key):
        return cfg.unit_of(key)
    if key in COUNTS:
        return COUNTS[key]
    if "clicks" in key.rpartition(".")[2]:
        return "clicks"
    return "-"


def valid(key: str) -> str:
    kind = cfg.SCHEMA[key]
    if isinstance(kind, tuple):
        return "one of " + ", ".join(kind)
    text = {"pos": "> 0", "nonneg": ">= 0", "real": "any number", "list": "list of numbers",
            "rows": "list of rows of numbers", "bool": "true or false", "text": "text"}[kind]
    if key in cfg.UPPER_LIMITS:
        text += f", <= {cfg.UPPER_LIMITS[key][0]:g}"
    return text


def default(key: str, reference) -> str:
    if key not in reference.values:
        return "none"
    value = reference.values[key]
    if isinstance(value, tuple):
        return f"{len(value)} values"
    if isinstance(value, str):
        return "(text)" if key in ("description", "reading") else value
    return cfg._toml_value(value) if not isinstance(value, float) else f"{value:g}"


def plausible(key: str) -> str:
    if key not in cfg.PLAUSIBLE:
        return ""
    low, high = cfg.PLAUSIBLE[key]
    return f"{low:g}-{high:g}"


def _cell(text: str) -> str:
    assert "|" not in text, text
    return text


def markdown() -> str:
    missing = [k for k in cfg.SCHEMA if k not in MEANINGS]
    stray = [k for k in MEANINGS if k not in cfg.SCHEMA]
    if missing or stray:
        raise SystemExit(f"docs/configuration.py: no meaning for {missing}; meanings of unknown keys {stray}")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reference = cfg.load("reference")
    lo, hi = cfg.TIRE_PRESSURE_MEASURED_PSI
    lines = [
        "# Configuration reference",
        "",
        "<!-- Generated from mtbmj.config.SCHEMA by `python docs/configuration.py > docs/configuration.md`;",
        "     edit the meanings in docs/configuration.py, not here. tests/test_config_reference.py checks it. -->",
        "",
        "A configuration is a TOML file whose tables mirror the model (`[sled]`, `[fork.spring]`, ...), or a",
        "bundled preset; a file may name a `base` (a preset or another file) whose values it overrides, and",
        "`--set KEY=VALUE` overrides a key on the command line. Values are plain numbers in the unit their",
        "key names. To see every value of a preset, resolved through its base:",
        "",
        "```bash",
        "mtbmj presets --show S12",
        "```",
        "",
        "## 1. The load in a rider's terms",
        "",
        "The fork carries `sled.body_mass_kg`, the sprung mass on the front. A rider can give it instead as",
        "`sled.rider_mass_kg`, `sled.bike_mass_kg` and `sled.front_share_percent`: the front wheel carries the",
        "front share of the weight of rider and bike, and of that the fork carries all but the front wheel",
        "itself (unsprung, below the fork):",
        "",
        "    sled.body_mass_kg = sled.front_share_percent / 100 x (sled.rider_mass_kg + sled.bike_mass_kg)",
        "                        - sled.wheel_mass_kg",
        "",
        "The paper's sled, 53.2 kg with a 2.3 kg wheel, is an 85 kg rider and an 11 kg bike at 57.8 % front",
        "(58 % gives 53.4 kg). A file, or one set of `--set` overrides, gives the load one way: the sprung mass",
        "or all three rider inputs, not both. Given on top of a base (a preset, a file or the file an",
        "override applies to), either way replaces the other's: rider inputs on a preset replace its",
        "53.2 kg, and one rider input on a file that has all three changes that one. A later",
        "`sled.wheel_mass_kg` changes the sprung mass the rider inputs give.",
        "",
        "```bash",
        "mtbmj drop S12 --set sled.rider_mass_kg=72 --set sled.bike_mass_kg=14.5 "
        "--set sled.front_share_percent=40 --out out/rider",
        "```",
        "",
        "`mtbmj sag` takes the load the same ways: `--load-kg` is the sprung mass, or the rider inputs give it",
        "(in `--set` or in the file), not both ([docs/air.md](air.md)):",
        "",
        "```bash",
        "mtbmj sag air120 --sag-percent 20 --set sled.rider_mass_kg=78 --set sled.bike_mass_kg=15 "
        "--set sled.front_share_percent=60 --out out/rider-sag",
        "```",
        "",
        "## 2. Other units",
        "",
        "Keys in the units riders use, converted when the configuration is read (downstream everything sees",
        "the canonical key). A file, or one set of overrides, gives one key of a pair; a later one",
        "replaces the value whichever key it uses.",
        "",
        "| key | canonical key | conversion |",
        "|---|---|---|",
        f"| `fork.spring.rate_lb_per_in` | `fork.spring.rate_N_per_mm` | 1 lb/in = 4.4482216152605 N / 25.4 mm "
        f"= {cfg.N_PER_MM_PER_LB_PER_IN:.8f} N/mm |",
        f"| `fork.spring.air_pressure_bar` | `fork.spring.air_pressure_psi` | 1 bar = 1e5 Pa = "
        f"{cfg.PSI_PER_BAR:.7f} psi (1 psi = 6894.757293168 Pa) |",
        f"| `tire.pressure_bar` | `tire.pressure_psi` | the same |",
        "",
        "## 3. Tire pressure",
        "",
        "`tire.pressure_psi` (or `tire.pressure_bar`) sets the tire's rates from its gauge pressure p:",
        "",
        "    k_static = 62 N/mm x p / 25 psi,  k_impact = 1.38 k_static,  k_in-contact = 1.19 k_static",
        "",
        "| number | value | source |",
        "|---|---|---|",
        "| form: rate proportional to the gauge pressure | k ~ p | a tire whose walls do not stretch carries its load "
        "by the pressure over the contact patch (Renart & Roura-Grabulosa, Am. J. Phys. 87, 102, 2019) |",
        "| static rate at the anchor | 62 N/mm | sourced, secondhand: 29 x 2.3 tire on a 25 mm rim, 418 N "
        "(Dressel & Sadauckas 2020, Appl. Sci. 10(9):3156) |",
        "| anchor pressure | 25 psi (1.72 bar) | sourced: the same measurement |",
        f"| measured range | {lo:g}-{hi:g} psi | sourced: 1.03 bar (their largest deflection, 48.7 mm) to "
        "1.72 bar |",
        "| impact / static | 1.38 | sourced, secondhand: first-impact dynamic / static (Sadauckas et al. 2024) |",
        "| in-contact / static | 1.19 | sourced, secondhand: settled dynamic / static (same source) |",
        "| carcass stiffness | neglected | assumed (the rate is likely too soft at low pressure) |",
        "| the same proportionality outside the measured range | k ~ p | assumed |",
        "",
        f"Any pressure above 0 psi is accepted. Outside the measured {lo:g}-{hi:g} psi (riders run about",
        "15-35) the rates are extrapolated, and the run says so in one warning line; 0 or less (a tire",
        "without air) is refused.",
        "",
        "## 4. Plausibility warnings",
        "",
        "A value far outside what any bike or sled has is more likely a unit mistake than a bike: metres in",
        "a mm key, N/m in an N/mm key, grams in a kg key. The run proceeds, and the command line prints one",
        "line per such value once, after the command's own output:",
        "",
        "    mtbmj: warning: sled.drop_height_mm = 0.3 mm is far below what any bike or sled has (1-5000 mm): "
        "probably meant 0.3 m = 300 mm",
        "",
        "The ranges are wide on purpose (the column *plausible* below; 0 is exempt where a key allows it).",
        "For a value outside, the mistakes checked in order are, by the key's unit:",
        "",
        "| unit | typed instead |",
        "|---|---|",
    ]
    for unit_name, mistakes in cfg.MISTAKES.items():
        lines.append(f"| {unit_name} | {', '.join(typed for typed, _ in mistakes)} |")
    lines += [
        "",
        "and the first that lands inside the range is named (\"probably meant 6000 N/m = 6 N/mm\"); when none",
        "does, the range is. A command that is refused prints only its one error line; the line adds the",
        "warning about a key it names (a travel of 0.12 mm is refused for its top-out spring, with",
        "\"probably meant 0.12 m = 120 mm\"), and a run that diverged adds them all. From Python,",
        "`mtbmj.load_config` and `run_drop` issue each as a `mtbmj.config.ConfigWarning` (shown or not as",
        "your warning filters say) and the configuration keeps them in `config.warnings`. A command's argument given",
        "to a Python entry point gets the command line's line as a `ConfigWarning` too (`run_roll` and `run_bike` at",
        "40 m/s, `solve_sag` under 180 kg or at 0.2 %: `mtbmj.limits.plausible`):",
        "",
        "```python",
        "import mtbmj",
        "config = mtbmj.load_config(\"S12\", {\"sled.body_mass_kg\": 48000})",
        "print(config.warnings)",
        "```",
        "",
        "## 5. Every key",
        "",
        "*default*: the value in the reference preset (`mtbmj/presets/reference.toml`, on which every preset",
        "builds; a preset may choose otherwise, see `mtbmj presets --show NAME`), or *none*; the meaning",
        "names a default the code takes when a key is left out. *valid*: what is refused otherwise (a",
        "model may refuse more, such as a knee outside the travel). *plausible*: outside it, a warning.",
        "Every number, of this schema and of a bike file alike, passes one gate first (`mtbmj/limits.py`):",
        "NaN, infinity, an integer too large for a float (1 followed by 400 zeros) and a value beyond 1e30",
        "in its unit are refused in one line naming the key, before any value is used.",
        "",
        "A key of `[fork.spring]`, `[fork.damper]`, `[fork.friction]` or `[tire]` typed on the command line",
        "(`--set`, or a bike's `--fork-set` / `--shock-set`) that the part's chosen model does not read is",
        "refused in one line naming the model and the keys it reads: on a progressive fork,",
        "`--fork-set fork.spring.rate_N_per_mm=9.75` would change nothing (its rate is",
        "`fork.spring.progressive_rate_N_per_mm`). Such a key the file named on the command line sets itself",
        "over its base (a configuration's own table, a bike file's own `[fork.set]` or `[shock.set]`) runs, with",
        "one warning line naming the key, the file and the keys the model reads. A configuration without a base",
        "is a whole one (as `mtbmj presets --show` writes) and, like the keys a file's bases carry",
        "for other models (the reference preset holds every key; a bike file may change the model its base",
        "chose), passes unsaid, as do the keys a program sets (a sweep's variants, a fit's trials, `overrides=`",
        "from Python).",
        "",
    ]
    section = None
    for key in cfg.SCHEMA:
        head = key.rpartition(".")[0] or "top level"
        if head != section:
            section = head
            lines += [f"### {section}" if head == "top level" else f"### [{section}]", "",
                      "| key | unit | default | valid | plausible | meaning |", "|---|---|---|---|---|---|"]
        lines.append("| " + " | ".join(_cell(c) for c in (
            f"`{key}`", unit(key), default(key, reference), valid(key), plausible(key), MEANINGS[key])) + " |")
        if key == list(cfg.SCHEMA)[-1] or (list(cfg.SCHEMA)[list(cfg.SCHEMA).index(key) + 1].rpartition(".")[0]
                                            or "top level") != section:
            lines.append("")
    lines += bike_section() + data_section()
    return "\n".join(lines).rstrip("\n") + "\n"


def _plain(value) -> str:
    if isinstance(value, list):
        return f"{len(value)} values" if len(value) > 2 else "[" + ", ".join(f"{x:g}" for x in value) + "]"
    if isinstance(value, dict):
        return f"{len(value)} keys"
    return f"{value:g}" if isinstance(value, float) else str(value)


def bike_section() -> list[str]:
    """The bike file's keys (``mtbmj.bike.keys.KEYS``), their defaults from the SST preset."""
    from mtbmj.bike import keys, spec

    table, _ = spec.read_table("sst")
    known = {f"{s}.{k}" for s, ks in spec.KNOWN.items() if ks for k in ks} | {k for k, v in spec.KNOWN.items() if v is None}
    missing = sorted(known - set(keys.KEYS))
    if missing:
        raise SystemExit(f"docs/configuration.py: mtbmj.bike.keys.KEYS has no entry for {missing}")
    lines = [
        "## Bike files",
        "",
        "`mtbmj bike BIKE ...` reads a bike file (its own TOML schema; presets `sst` and `trail`, see",
        "[docs/bike.md](bike.md)): geometry in frame coordinates (origin the bottom bracket, x forward, z",
        "up, both ends at full extension), masses, the leverage table, the shock's and the fork's laws as",
        "configurations of the schema above, the rider and the drive. A file may name a `base` (a bike",
        "preset or another bike file). *default*: the SST preset's value (`mtbmj/bike/presets/sst.toml`),",
        "or *none* where the key has one only in the code or the preset gives it another way (its axles,",
        "head angle and offset come from its `[geometry]` chart, its seated rider from the chart's saddle).",
        "*plausible*: outside it, a warning; a point's",
        "range is given for x and for z. Geometry given in metres (every axle and pivot coordinate below 3)",
        "is refused naming the keys; a point more than 5 m from the bottom bracket is refused. Every number",
        "of the file, its bases and `--set` passes the gate of section 5 before any is used (NaN, infinity,",
        "a huge integer and a value beyond 1e30 refused in one line naming the key and the file).",
        "",
        "| key | default | valid | plausible | meaning |",
        "|---|---|---|---|---|",
    ]
    for key, (meaning, valid_, rng) in keys.KEYS.items():
        section, _, name = key.partition(".")
        value = table.get(section, {}).get(name) if name else table.get(section)
        if rng is None:
            shown = ""
        elif isinstance(rng[0], tuple):
            shown = f"x {rng[0][0]:g} to {rng[0][1]:g}, z {rng[1][0]:g} to {rng[1][1]:g}"
        else:
            shown = f"{rng[0]:g}-{rng[1]:g}"
        if key in ("description", "reading"):
            value = "(text)"
        if key == "rider.limbs_share_percent" and value is None:
            value = round(spec.LIMBS_SHARE_PERCENT, 2)
        lines.append("| " + " | ".join(_cell(c) for c in (
            f"`{key}`", "none" if value is None else _plain(value), valid_, shown, meaning)) + " |")
    return lines + [""]


def data_section() -> list[str]:
    """The data files the commands read beside the configuration and bike files: their columns."""
    from mtbmj.measured.telemetry import CSV_COLUMNS

    rows = [
        ("terrain profile (`mtbmj roll TERRAIN`, `mtbmj bike BIKE TERRAIN`; `mtbmj reconstruct` writes one, "
         "`terrain.csv`)", "`distance_m` (non-decreasing), `height_mm`",
         "[docs/rolling.md](rolling.md), `mtbmj/rolling/terrain.py`"),
        ("speed along the terrain (`mtbmj bike --speed-profile FILE`; `mtbmj reconstruct` writes one, `speed.csv`)",
         "`distance_m`, `speed_m_per_s`", "[docs/bike.md](bike.md), `mtbmj/bike/schedule.py`"),
        ("speed over the ride's clock (`mtbmj reconstruct` / `mtbmj advise --speed-csv FILE`: a GPS track, a bike "
         "computer)", "`time_s`, `speed_m_per_s`", "[docs/rolling.md](rolling.md), `mtbmj/ride/reconstruct_given.py`"),
        ("a ride's travel from any logger (`mtbmj telemetry`, `reconstruct`, `advise` RIDE as a CSV; or an SST "
         "recording, v2 or v3, decoded through the bike's `[sensors]`)",
         f"`{CSV_COLUMNS[0]}` and one or more of " + ", ".join(f"`{c}`" for c in CSV_COLUMNS[1:]),
         "[docs/rolling.md](rolling.md), `mtbmj/measured/telemetry.py`"),
        ("bench, tire and sled records (`mtbmj fit ...`, `mtbmj compare`)",
         "by record kind: `displacement_mm`, `velocity_mm_per_s`, `force_N`, `deflection_mm`, `sled_mm`, "
         "`fork_mm`, `tire_mm`, `time_s`", "[docs/fitting.md](fitting.md), `mtbmj/measured/records.py`"),
    ]
    lines = [
        "## Data files",
        "",
        "CSV files with one header row: every column name ends in its unit (`time_s`, `height_mm`,",
        "`speed_m_per_s`; also `ms`, `m`, `kN`, `mm_per_s`, `N_per_mm`, `N_per_m`, `kg`, `Hz`, converted to SI on",
        "reading, `mtbmj/measured/records.py`); lines starting with `#` are comments; the delimiter `,`, `;` or a",
        "tab. A unit not read is refused in one line naming the file and the column; a terrain or speed file",
        "with other columns than its own is refused naming the file (and the option that takes it, where another",
        "does).",
        "",
        "| file | columns | where |",
        "|---|---|---|",
    ]
    lines += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
    return lines + [""]


def main() -> int:
    sys.stdout.write(markdown())
    return 0


if __name__ == "__main__":
    sys.exit(main())
