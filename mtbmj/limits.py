"""What one run may ask for, checked before anything is allocated: a duration that is a finite
number of seconds, at least one logger sample long, and a number of steps whose arrays fit in
the memory this machine has available (the message says how much would be needed)."""
from __future__ import annotations

import contextlib
import contextvars
import math
import os

from mtbmj.errors import ConfigError

# Memory one simulated step holds until a run is written: the engine's state record and trace,
# the derived signals and the CSV text of the raw trace. Measured with tracemalloc at about
# 200-270 bytes per step for a drop on either engine; the CSV text of ``timeseries_raw.csv``
# (about 100 bytes a row) and a margin for copies make it 1 KiB.
BYTES_PER_STEP = 1024


def available_memory() -> int:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``; else the physical
    memory)."""
    try:
        with open("/proc/meminfo", "rb") as handle:
            for line in handle:
                if line.startswith(b"MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):  # pragma: no cover - not a POSIX system
        return 1 << 34


def size_text(nbytes: float) -> str:
    for unit, scale in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{nbytes / 1024:.3g} KiB"


# The numbers a command's user typed, by option, while the command runs (``command_line``; None outside one): a
# number given to the library as the option was (``--duration 1e9`` as ``run_drop``'s duration) is refused
# naming the option (:func:`named`), not the Python argument it became.
_TYPED: contextvars.ContextVar = contextvars.ContextVar("mtbmj_typed", default=None)


@contextlib.contextmanager
def command_line():
    """The run of one command: the numbers its arguments pass (:func:`argument`) are kept for :func:`named`."""
    token = _TYPED.set({})
    try:
        yield
    finally:
        _TYPED.reset(token)


def named(label: str, value) -> str:
    """``label``, a Python argument's name (``duration``), as the user gave ``value``: the command's option
    (``--duration``) where a command runs and its user typed that option with this value; else ``label``."""
    option = "--" + label.replace("_", "-")
    typed = _TYPED.get()
    return option if typed is not None and option in typed and typed[option] == value else label


def check_duration(label: str, duration) -> None:
    """A duration given by the user: a finite positive number of seconds."""
    if duration is None:
        return
    label = named(label, duration)
    if isinstance(duration, bool) or not isinstance(duration, (int, float)):
        raise ConfigError(f"{label}: must be a number of seconds, got {duration!r}")
    if not (math.isfinite(duration) and duration > 0):
        raise ConfigError(f"{label}: must be a positive finite number of seconds, got {duration}")


def check_run(duration: float, timestep: float, sample_rate_Hz: float, label: str = "duration",
              runs: int = 1) -> int:
    """The number of steps of ``runs`` runs of ``duration`` s at ``timestep`` s, or ``ConfigError``
    when the duration is not finite, shorter than one logger sample, or the steps would need more
    memory than is available."""
    check_duration(label, duration)
    label = named(label, duration)
    shortest = 1.0 / sample_rate_Hz
    if duration < shortest:
        raise ConfigError(f"{label}: {duration:g} s is shorter than one logger sample "
                          f"({shortest:g} s at {sample_rate_Hz:g} Hz)")
    steps = duration / timestep
    need = steps * BYTES_PER_STEP * runs
    have = available_memory()
    if need > have:
        raise ConfigError(f"{label}: {duration:g} s in steps of {timestep:g} s is {steps:.3g} steps"
                          f"{f' x {runs} runs' if runs > 1 else ''}, needing about {size_text(need)} of memory; "
                          f"{size_text(have)} is available (shorten the duration or lengthen solver.timestep_s)")
    return int(round(steps))


# --- the numeric-input gate -------------------------------------------------------------------------
# Every number a user gives passes here before any work: a key's value (a configuration, a bike
# file, ``--set``) through :func:`number`, a command's numeric argument through :func:`argument`
# (``mtbmj.cli.common.numeric`` is the argparse type over it). A value that is not a number, is
# NaN or infinite, is an integer too large for a float (TOML reads 1 followed by 400 zeros as one)
# or lies beyond ``MAX_MAGNITUDE`` is refused in one line naming the key; a value outside the
# plausible range its key or argument states is warned about (``ConfigWarning``), and the run
# proceeds.

# No key's value is anywhere near this in its unit (N/mm, kg, mm, s); beyond it the models'
# arithmetic leaves the float range (a 1e300 N/mm leg: no static equilibrium can be computed).
MAX_MAGNITUDE = 1e30


def _shown(value) -> str:
    """A value as a refusal shows it: an integer of hundreds of digits by its size."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10 ** 20:
        return f"an integer of {len(str(abs(value))) if value.bit_length() < 10000 else 'thousands of'} digits"
    return repr(value)


def number(key: str, value, what: str = "a number") -> float:
    """``value`` (a key's, as read from TOML or ``--set``) as a float, or ``ConfigError`` naming
    ``key``: refused when it is not a number (a bool, a string), is NaN or infinite, or is an
    integer or float beyond ``MAX_MAGNITUDE`` (an integer that does not fit a float among them)."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or getattr(getattr(value, "dtype", None), "kind", "f") not in "iuf":  # numpy's numbers, not its times
        if hasattr(value, "isoformat"):  # TOML reads 2024-05-27 (or 12:30:00) as a date: not Python's repr of it
            raise ConfigError(f"{key}: must be {what}, got {value.isoformat()} (TOML reads it as a date or a time)")
        raise ConfigError(f"{key}: must be {what}, got {value!r}")
    try:
        x = float(value)
        if math.isinf(x) and value != x:  # a numpy long double beyond the float range (inf itself equals it)
            raise OverflowError
    except OverflowError:  # an integer beyond the float range
        raise ConfigError(f"{key}: {_shown(value)} is too large for any number the model holds "
                          f"(at most {MAX_MAGNITUDE:g} in its unit)") from None
    if not math.isfinite(x):
        raise ConfigError(f"{key}: must be finite (not NaN or infinity), got {x}")
    if abs(x) > MAX_MAGNITUDE:
        raise ConfigError(f"{key}: {x:g} is beyond anything the model holds (at most {MAX_MAGNITUDE:g} in its unit)")
    return x


# A rider's stature (m): beyond these no adult rides (a unit mistake, 178 for 1.78); refused. The
# plausible range, warned about, is mtbmj.bike.keys.KEYS'.
RIDER_HEIGHT_M = (1.2, 2.3)


def within(key: str, value: float, bounds: tuple[float, float], unit: str) -> float:
    """``value`` when within ``bounds`` (inclusive), else ``ConfigError`` naming ``key``."""
    low, high = bounds
    if not low <= value <= high:
        raise ConfigError(f"{key}: must be within {low:g}-{high:g} {unit}, got {value:g}")
    return value


def numbers_in(key: str, value):
    """``value`` with every number in it (a list, a point, a table's rows) passed through
    :func:`number` (integers that fit stay integers: teeth, clicks, spacers), or ``ConfigError``
    naming ``key``; anything else is returned as it is, for its key's own check."""
    if isinstance(value, bool) or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        x = number(key, value)
        return value if isinstance(value, int) else x
    if isinstance(value, list):
        return [numbers_in(key, v) for v in value]
    if isinstance(value, tuple):
        return tuple(numbers_in(key, v) for v in value)
    if isinstance(value, dict):
        return {k: numbers_in(f"{key}.{k}", v) for k, v in value.items()}
    return value


# --- units and their slips ------------------------------------------------------------------------
# The one table of lb/in and psi (mtbmj.config re-exports them).
# 1 lb/in = 1 lbf / 1 in = (0.45359237 kg x 9.80665 m/s2) / 25.4 mm = 0.175126835 N/mm (the pound
# and the inch are exact by definition, standard gravity too)
N_PER_MM_PER_LB_PER_IN = 0.45359237 * 9.80665 / 25.4
# 1 bar = 1e5 Pa; 1 psi = 1 lbf/in2 = 6894.757293168 Pa: 1 bar = 14.5037738 psi
PSI_PER_BAR = 1e5 / (0.45359237 * 9.80665 / 0.0254 ** 2)
PA_PER_PSI = 6894.757293168  # Pa per psi (1 lbf/in^2, exact by the definitions of the pound and the inch)

# The unit mistakes a value is checked against, in order: (what was typed, this unit per one of it).
MISTAKES: dict[str, tuple[tuple[str, float], ...]] = {
    "mm": (("m", 1000.0), ("in", 25.4), ("cm", 10.0)),
    "kg": (("g", 1e-3), ("lb", 0.45359237), ("st", 6.35029318)),
    "N/mm": (("N/m", 1e-3), ("lb/in", N_PER_MM_PER_LB_PER_IN)),
    "lb/in": (("N/mm", 1.0 / N_PER_MM_PER_LB_PER_IN), ("N/m", 1e-3 / N_PER_MM_PER_LB_PER_IN)),
    "N s/m": (("N s/mm", 1000.0),),
    "mm/s": (("m/s", 1000.0),),
    # 1 km/h = 1000 m / 3600 s; 1 mph = 1609.344 m / 3600 s = 0.44704 m/s (the mile exact by definition)
    "m/s": (("km/h", 1.0 / 3.6), ("mph", 0.44704)),
    "m/s2": (("mm/s2", 1e-3), ("ft/s2", 0.3048)),
    "psi": (("bar", PSI_PER_BAR), ("kPa", PSI_PER_BAR / 100.0)),
    "bar": (("psi", 1.0 / PSI_PER_BAR), ("kPa", 0.01)),
    "%": (("as a fraction", 100.0),),
    "N": (("kN", 1000.0),),
    "cm3": (("litres", 1000.0), ("in3", 16.387064), ("mm3", 1e-3)),
    "deg": (("rad", 180.0 / math.pi),),
}


def slip(value: float, unit: str, plausible: tuple[float, float]) -> str:
    """The first unit slip of ``MISTAKES`` that brings ``value`` (in ``unit``) within ``plausible``, said as
    " probably meant 0.16 m = 160 mm", else ""."""
    lo, hi = plausible
    return next((f" probably meant {value:g} {typed} = {value * per:.4g} {unit}" for typed, per in MISTAKES.get(unit, ())
                 if lo <= value * per <= hi), "")


def require_mapping(overrides, example: str, none_ok: bool = True) -> None:
    """Refuse ``overrides`` from Python that are not a mapping (a str, a list of "key=value") in one line,
    ``example`` a key of the caller's kind with a value (``'rider.mass_kg': 78``); None passes where ``none_ok``."""
    from collections.abc import Mapping

    if not (overrides is None and none_ok) and not isinstance(overrides, Mapping):
        raise ConfigError(f"overrides: must be a mapping of key to value, e.g. {{{example}}}, got a "
                          f"{type(overrides).__name__}")
    odd = [k for k in (overrides if isinstance(overrides, Mapping) else ()) if not isinstance(k, str)]
    if odd:  # {1: 300} met str methods deep inside ("'int' object has no attribute 'rpartition'")
        raise ConfigError(f"overrides: each key must be a str naming the key, e.g. {{{example}}}, got {odd[0]!r}")


# --- the kinds of a Python argument that is no number: a list of names, a switch, a count -------------------------
# Each refused in one line naming the argument, before any work: a str where a list goes is read letter by letter
# ("S12" as the preset "S"), a str where a switch goes is true whatever it says ("no" too), "2" where a count goes
# meets a comparison deep inside ("'<' not supported between instances of 'str' and 'int'").

def names(label: str, value, example, none_ok: bool = True, what: str = "names", as_item: bool = True) -> list | None:
    """``value`` (a list or tuple of names, or None where ``none_ok``) as a list, or ``ConfigError`` naming ``label``:
    a str, a mapping, a number or an empty list is refused (``example`` one item the list may hold, ``what`` its
    items: "names", "files"; a str given is shown in a list as the way to give it, unless not ``as_item``)."""
    from collections.abc import Iterable, Mapping

    if value is None and none_ok:
        return None
    if isinstance(value, str) and as_item:
        raise ConfigError(f"{label}: must be a list of {what}, e.g. [{value!r}], got the str {value!r}")
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
        shown = f"the str {value!r}" if isinstance(value, str) else described(value)
        raise ConfigError(f"{label}: must be a list of {what}, e.g. [{example!r}], got {shown}")
    value = list(value)
    if not value:
        raise ConfigError(f"{label}: an empty list; give at least one, e.g. [{example!r}]"
                          + (" (or None for the default)" if none_ok else ""))
    return value


def switch(label: str, value) -> bool:
    """``value`` as a bool when it is True or False (numpy's too), else ``ConfigError`` naming ``label``."""
    if isinstance(value, bool) or (type(value).__module__ == "numpy" and type(value).__name__ in ("bool_", "bool")):
        return bool(value)
    raise ConfigError(f"{label}: must be True or False, got {value!r}")


def whole(label: str, value, least: int, none_ok: bool = True) -> int | None:
    """``value`` as an int when it is a whole number (numpy's too, not a bool or a float) of at least ``least``
    (None passes where ``none_ok``), else ``ConfigError`` naming ``label``."""
    import numbers

    if value is None and none_ok:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{label}: must be a whole number, got {value!r}")
    if value < least:
        raise ConfigError(f"{label}: must be at least {least}, got {value}")
    return int(value)


def described(value) -> str:
    """``value``'s kind as a refusal says it: "None", "a str", "a dict"."""
    name = type(value).__name__
    return "None" if value is None else f"{'an' if name[0] in 'aeiou' else 'a'} {name}"


# A unit as people also type it after a number (``20 percent``, ``30 fps``)
UNIT_WORDS = {"%": "percent", "deg": "degrees", "s": "sec", "frames/s": "fps"}


# What a unit typed after a number looks like: letters (µ, °, % among them), a slash between them, a square at the
# end (``km/h``, ``N s/mm``, ``m/s2``); a lone ``e`` is an exponent left unfinished (``1e``), not a unit
_UNIT_TOKEN = r"(?!(?:[eE][-+]?)$)[A-Za-zµ°%](?:[A-Za-zµ°% /]*[A-Za-zµ°%2²])?"


def _unit_typed(raw: str, unit: str, spec: "Argument | None" = None) -> str:
    """The note of a number typed with a unit after it (``6m/s``, ``20 km/h``, ``80kg``) for an option in ``unit``:
    the number alone (as typed), converted where the unit is one of its slips (``MISTAKES``), and the range allowed
    in its place where that number is outside it (``spec``); "" for anything else (``4-6``, ``5/2``, ``1e``)."""
    import re

    found = re.fullmatch(rf"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*({_UNIT_TOKEN})", raw)
    if not found or not unit:
        return ""
    number, typed = found.group(1), found.group(2).strip()
    value = float(number)
    squeeze = typed.replace(" ", "").lower()
    if squeeze in (unit.replace(" ", "").lower(), UNIT_WORDS.get(unit, unit)):
        if spec is not None and spec.outside(value):
            return f" (the unit is the option's, {unit}: {number} is outside the range allowed: {spec.allowed()})"
        return f" (the unit is the option's, {unit}: give the number alone, {number})"
    per = next((per for name, per in MISTAKES.get(unit, ()) if name.replace(" ", "").lower() == squeeze), None)
    if per is not None:
        meant = f"{value * per:.4g}"
        if spec is not None and spec.outside(float(meant)):
            return (f" (the option is in {unit}: {value:g} {typed} = {meant} {unit}, outside the range allowed: "
                    f"{spec.allowed()})")
        return f" (the option is in {unit}: {value:g} {typed} = {meant} {unit}, give {meant})"
    return f" (the option takes a number in {unit}, without a unit)"


def unit_apart(option: str, value: str, word: str) -> str:
    """The note on ``word`` typed apart after ``value`` of ``option`` (``--speed 20 km/h``) where ``word`` is a unit,
    the option's own or one of the table's (``MISTAKES``), said and converted as ``_unit_typed`` says ``20km/h``;
    "" for any other word (a positional argument after the value, left to its parser)."""
    unit = ARGUMENTS[option].unit if option in ARGUMENTS else ""
    units = {name.replace(" ", "").lower() for key, slips in MISTAKES.items() for name in (key, *(n for n, _ in slips))}
    if not unit or word.replace(" ", "").lower() not in units | {unit.replace(" ", "").lower(), UNIT_WORDS.get(unit)}:
        return ""
    try:
        float(value)
    except ValueError:
        return ""
    return _unit_typed(f"{value} {word}", unit, ARGUMENTS[option])


class Argument:
    """A command's numeric argument: its unit, whether it is a whole number, the values the
    model allows (``low`` / ``high``, inclusive unless ``open_low``) and the plausible range
    outside which it is warned about."""

    def __init__(self, unit: str = "", low: float | None = None, high: float | None = None,
                 plausible: tuple[float, float] | None = None, integer: bool = False, open_low: bool = False,
                 beyond: str = "", why: str = "", open_high: bool = False):
        self.unit, self.low, self.high, self.plausible = unit, low, high, plausible
        self.integer, self.open_low, self.open_high, self.beyond, self.why = integer, open_low, open_high, beyond, why

    def below(self, value: float) -> bool:
        """Whether ``value`` is below the values the model allows."""
        return self.low is not None and (value <= self.low if self.open_low else value < self.low)

    def outside(self, value: float) -> bool:
        """Whether ``value`` is outside the values the model allows (refused by :func:`argument`)."""
        above = self.high is not None and (value >= self.high if self.open_high else value > self.high)
        return self.below(value) or above

    def reason(self, value: float) -> str:
        """Why ``value``, outside the values allowed, is (" (no bike is ridden faster than 30 m/s)", " (what a
        rider turns)"), or ""."""
        unit = f" {self.unit}" if self.unit else ""
        if self.beyond and not self.below(value):
            return f" ({self.beyond} faster than {self.plausible[1]:g}{unit})"
        return f" ({self.why})" if self.why else ""

    def allowed(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        if self.low is not None and self.high is not None:
            return (f"{'above' if self.open_low else 'at least'} {self.low:g} and {'below' if self.open_high else 'at most'} "
                    f"{self.high:g}{unit}")
        if self.low is not None:
            return f"{'above' if self.open_low else 'at least'} {self.low:g}{unit}"
        return f"at most {self.high:g}{unit}"


# What a pedalling rider's legs can do: cadence and power bound what any rider turns and keeps up for a few seconds
# (assumed round values: sprint peaks of trained riders stay under about 1500 W, cadences within 30-130 rpm); the
# one source of ``--pedal`` and ``--power``, of ``run_bike(pedal=...)``'s check and of the drive's law
# (``mtbmj.controllers.drive``, which reads them from here)
PEDAL_RPM = (30.0, 130.0)
PEDAL_POWER_W = (0.0, 1500.0)  # power above 0: the floor is open

_POSITIVE = dict(low=0.0, open_low=True)
_SECONDS = Argument("s", plausible=None, **_POSITIVE)  # how long a run may be: the memory check (check_run)
_WORKERS = Argument("", low=1, high=1024, plausible=(1, 256), integer=True)
_SAMPLES = Argument("", low=0, high=10 ** 7, integer=True)
_SEED = Argument("", low=0, high=2 ** 63 - 1, integer=True)
_TRAVEL_MM = Argument("mm", high=1000.0, plausible=(20.0, 400.0), **_POSITIVE)
_FORCE_N = Argument("N", low=0.0, high=1e6, plausible=(0.0, 2500.0))
_OFFSET_MM = Argument("mm", low=-1000.0, high=1000.0, plausible=(-50.0, 50.0))
_SAG_PERCENT = Argument("%", high=100.0, plausible=(5.0, 50.0), open_high=True, **_POSITIVE)  # 100 %: no travel left

# Every numeric argument of every command, by its option (the same option means the same
# quantity in every command that has it). ``plausible``: what bikes, riders and records have,
# wide; ``low`` / ``high``: beyond them the model does not hold (refused).
ARGUMENTS: dict[str, Argument] = {
    # a bike above 30 m/s (108 km/h) is beyond anything ridden; above 100 m/s beyond the model (its
    # tyres, its step rule and its terrain's features are made for ridden speeds)
    "--speed": Argument("m/s", high=100.0, plausible=(0.3, 30.0), beyond="no bike is ridden", **_POSITIVE),
    "--duration": _SECONDS,
    "--touch-s": Argument("s", low=0.0),
    # where on the terrain the front axle starts: a terrain's surface may be 100 km long (rolling.terrain's
    # MAX_SURFACE_M) and a reconstructed one hundreds of metres, so no plausible range (a start off the terrain is
    # refused by the terrain, naming its ends): -100-100 m warned of a start 300 m into a ride's terrain.csv, and
    # render refused a saved run that started at 12 km
    "--start-m": Argument("m", low=-1e5, high=1e5, plausible=None),
    "--threshold-mm-per-s": Argument("mm/s", high=1e6, plausible=(1.0, 5000.0), **_POSITIVE),
    "--bin-percent": Argument("%", high=100.0, plausible=(0.5, 50.0), **_POSITIVE),
    "--fork-max-mm": _TRAVEL_MM,
    "--shock-max-mm": Argument("mm", high=1000.0, plausible=(15.0, 150.0), **_POSITIVE),
    "--rider-kg": Argument("kg", high=1e4, plausible=(30.0, 150.0), **_POSITIVE),
    # the mass a fork (or a shock) carries at sag is part of rider and bike: at most the heaviest rider's
    # whole mass (rider.mass_kg's plausible 150 kg, mtbmj.bike.keys); 180 is more likely 180 lb = 81.6 kg
    "--load-kg": Argument("kg", high=1e4, plausible=(5.0, 150.0), **_POSITIVE),
    "--mass-kg": Argument("kg", high=1e4, plausible=(1.0, 300.0), **_POSITIVE),
    # a pedalling rider's cadence and power: the model's range (``PEDAL_RPM``, ``PEDAL_POWER_W``, the drive's law
    # too); one range, refused, no plausible one beside it
    "--pedal": Argument("rpm", low=PEDAL_RPM[0], high=PEDAL_RPM[1], why="what a rider turns"),
    "--power": Argument("W", high=PEDAL_POWER_W[1], why="what a rider keeps up", **_POSITIVE),
    "--drive-push-N": _FORCE_N,
    "--drive-power-W": Argument("W", low=0.0, high=1e5, plausible=(0.0, 2500.0)),
    "--drive-brake-N": _FORCE_N,
    # the rolling front end's head angle: the model holds (45, 90] deg (mtbmj.rolling.frontend)
    "--head-angle": Argument("deg", low=45.0, high=90.0, plausible=(55.0, 80.0), open_low=True),
    "--com-height-mm": Argument("mm", high=1e4, plausible=(300.0, 2000.0), **_POSITIVE),
    "--chainring": Argument("teeth", low=1, high=1000, plausible=(20, 60), integer=True),
    "--cog": Argument("teeth", low=1, high=1000, plausible=(9, 60), integer=True),
    "--sag-percent": _SAG_PERCENT,
    "--front-sag-percent": _SAG_PERCENT,
    "--rear-sag-percent": _SAG_PERCENT,
    # the hit an answer in clicks is for: an end's own compression above its static position; under 1 mm it lies
    # within the friction band the decay law fits (0.3-1.2 mm on the shared slams): 0.03 is 0.03 m typed
    "--hit-mm": Argument("mm", high=1e4, plausible=(1.0, 1000.0), **_POSITIVE),
    "--max-velocity-mm-per-s": Argument("mm/s", high=1e6, plausible=(100.0, 20000.0), **_POSITIVE),
    "--tolerance-mm": Argument("mm", high=1000.0, plausible=(1e-4, 10.0), **_POSITIVE),
    "--sled-offset-mm": _OFFSET_MM,
    "--fork-offset-mm": _OFFSET_MM,
    "--fps": Argument("frames/s", high=10000.0, plausible=(1.0, 1000.0), **_POSITIVE),
    "--width": Argument("pixels", low=1, high=16384, plausible=(16, 8192), integer=True),
    "--height": Argument("pixels", low=1, high=16384, plausible=(16, 8192), integer=True),
    "--workers": _WORKERS,
    "--threads": Argument("", low=1, high=1024, plausible=(1, 256), integer=True),
    "--batch-size": Argument("", low=1, high=10 ** 6, integer=True),
    "--samples": _SAMPLES,
    "--levels": Argument("", low=0, high=1000, integer=True),
    "--starts": Argument("", low=0, high=10 ** 5, integer=True),
    "--seed": _SEED,
}


def argument(option: str, text: str, integer: bool = False):
    """The value of ``option`` (a key of ``ARGUMENTS``) typed as ``text``: a float (an int for a
    whole-number option), or ``ValueError`` with the one-line reason; ``ConfigWarning`` when
    outside its plausible range. An option the table lacks is a finite number (``integer``: a
    whole number) within ``MAX_MAGNITUDE``."""
    spec = ARGUMENTS.get(option) or Argument(low=-MAX_MAGNITUDE, high=MAX_MAGNITUDE, integer=integer)
    raw = text.strip()
    typed = repr(text) if len(text) <= 30 else f"{text[:12]!r}... ({len(text)} characters)"
    if spec.integer:
        try:
            value = int(raw)
        except ValueError:
            raise ValueError(f"{typed} is not a whole number{_unit_typed(raw, spec.unit, spec)}") from None
    else:
        try:
            value = float(raw)
        except ValueError:
            comma = raw.count(",") == 1 and raw.replace(",", ".", 1).replace(".", "", 1).lstrip("+-").isdigit()
            hint = f" (a decimal comma? the decimal point is a dot: {raw.replace(',', '.')})" if comma else ""
            raise ValueError(f"{typed} is not a number{hint or _unit_typed(raw, spec.unit, spec)}") from None
        if not math.isfinite(value):
            raise ValueError(f"must be a finite number, got {typed}")
    unit = f" {spec.unit}" if spec.unit else ""
    if spec.outside(value):
        beyond = spec.reason(value)
        shown = _shown(value) if spec.integer else f"{value:g}"
        near = spec.plausible or (spec.low if spec.low is not None else -MAX_MAGNITUDE, spec.high)
        meant = slip(value, spec.unit, near) if not spec.integer else ""  # --head-angle 1.13: radians
        raise ValueError(f"{shown}{unit if not spec.integer or abs(value) < 10 ** 20 else ''} is outside the range "
                         f"allowed: {spec.allowed()}{beyond}{f' (a unit mistake?{meant})' if meant else ''}")
    if option in ARGUMENTS:
        plausible(option, value)
    typed = _TYPED.get()
    if typed is not None:  # within a command: the number its user typed as option (``named``)
        typed[option] = value
    return value


def plausible(option: str, value: float) -> None:
    """Warn (``ConfigWarning``) where ``value`` of ``option`` (a key of ``ARGUMENTS``) lies outside its plausible
    range, naming a unit slip that brings it within: the one line of a command's argument (:func:`argument`) and
    of the same number given to a Python entry point (``run_roll``'s speed, ``solve_sag``'s load), said at the
    caller's line outside the package (:func:`caller_level`)."""
    import warnings

    from mtbmj.errors import ConfigWarning

    spec = ARGUMENTS[option]
    if spec.plausible is not None and not spec.plausible[0] <= value <= spec.plausible[1]:
        lo, hi = spec.plausible
        unit = f" {spec.unit}" if spec.unit else ""
        warnings.warn(f"{option} = {value:g}{unit} is outside {lo:g}-{hi:g}{unit}, what bikes, riders and records "
                      f"have (a unit mistake?{slip(value, spec.unit, spec.plausible)})", ConfigWarning,
                      stacklevel=caller_level())


def caller_level() -> int:
    """The ``stacklevel`` of ``warnings.warn``, called in the function that calls this, that names the first line
    outside the package (the user's call, however deep in the package the check sits)."""
    import os
    import sys

    package = os.path.dirname(os.path.abspath(__file__)) + os.sep
    frame, level = sys._getframe(1), 1  # the function that warns
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package):
        frame, level = frame.f_back, level + 1
    return level


# A run's default length is the terrain crossed at its speed. Below a ridden speed (the plausible low of
# ``--speed``) and longer than this, that is a crawl of hours of computing (``mtbmj roll rock --speed
# 0.001``: 3800 s; at 0.3 m/s 13 s): refused before the run, naming the way out.
CRAWL_S = 120.0


def given(option: str, label: str, value, what: str = "", warn: bool = True) -> float:
    """``value``, given from Python as ``label`` for what the command line takes as ``option`` (a key of
    ``ARGUMENTS``), as a float: refused (one ConfigError line naming ``label``) where it is not a finite number
    (``what`` says what it is: " (the front axle's start)"), not positive for an option that must be, or outside
    the option's range; outside its plausible range warned about with the option's line (:func:`plausible`) where
    ``warn``. The one check of a command option's number given from Python (a rig's speed, the cross-check's
    tolerance, the bike's start)."""
    import numbers

    spec = ARGUMENTS[option]
    positive = spec.low == 0 and spec.open_low
    if not isinstance(value, numbers.Real) or isinstance(value, bool) or not math.isfinite(value) \
            or (positive and spec.below(value)):
        raise ConfigError(f"{label}: must be a {'positive' if positive else 'finite'} number of {spec.unit}{what}, "
                          f"got {value!r}")
    if spec.outside(value):
        raise ConfigError(f"{label}: {value:g} {spec.unit} is outside the range allowed: {spec.allowed()}"
                          f"{spec.reason(value)}")
    if warn:
        plausible(option, value)
    return float(value)


def speed(value, label: str = "speed", warn: bool = True) -> float:
    """A rig's speed given from Python (m/s): a positive finite number within ``--speed``'s range, else one
    ConfigError line; outside its plausible range warned about with ``--speed``'s line (:func:`given`; a
    command's argument, warned about by :func:`argument` before, is warned once: the command keeps each line once)."""
    return given("--speed", label, value, warn=warn)


def crossing(speed: float, seconds: float, terrain: str) -> None:
    """Refuse (``ConfigError``) a default run length of ``seconds`` that crawls over ``terrain`` at ``speed``."""
    low = ARGUMENTS["--speed"].plausible[0]
    if speed < low and seconds > CRAWL_S:
        raise ConfigError(f"--speed {speed:g} m/s: below a ridden speed ({low:g} m/s), crossing {terrain} would take "
                          f"{seconds:.3g} s of simulated time; give a ridden speed, or --duration to run part of it")
