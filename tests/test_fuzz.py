"""Property-based tests of the command line on generated input: TOML configurations, CSV and
.mat records (every fit and validate), SST byte streams and option values.

The invariant for every generated case: ``mtbmj`` succeeds (exit 0), or it refuses with exit
status 2 and exactly one line on stderr naming the cause, with no traceback, and nothing is
written where the output was asked for (no folder, no staging folder beside it).

The commands are called in-process (``mtbmj.cli.main``), far faster than a subprocess; stdout and
stderr are captured at the file-descriptor level, so MuJoCo's own prints would be seen too. The
runs are derandomized (the same cases on every CI run) and keep no example database.
"""
from __future__ import annotations

import io
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from mtbmj.config import DAMPER_MODELS, FRICTION_MODELS, SCHEMA, SPRING_MODELS, TIRE_MODELS

from helpers import CASES, FLOATS, NUMBERS, OUTCOMES, check, fresh

EXAMPLES = {"configs": 330, "records": 260, "sst": 180, "options": 300}


def fuzz_settings(name: str):
    return settings(max_examples=EXAMPLES[name], deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))


# --- values -------------------------------------------------------------------------------------

INTS = st.one_of(st.integers(-10, 10 ** 4), st.integers(-(10 ** 400), 10 ** 400))
WORDS = st.one_of(st.sampled_from(SPRING_MODELS + DAMPER_MODELS + FRICTION_MODELS + TIRE_MODELS),
                  st.text(max_size=12))
SCALARS = st.one_of(FLOATS, INTS, st.booleans(), WORDS)
VALUES = st.one_of(SCALARS, st.lists(st.one_of(FLOATS, INTS), max_size=6),
                   st.recursive(st.lists(FLOATS, max_size=2), lambda inner: st.lists(inner, max_size=2), max_leaves=6))
KEYS = st.one_of(st.sampled_from(sorted(SCHEMA)), st.sampled_from(["fork.spring.rate", "sled.mass_kg", "tire", "x.y",
                                                                    "fork.spring.rate_N_per_mm.z"]),
                 st.from_regex(r"[a-z_]{1,8}(\.[a-z_]{1,8}){0,3}", fullmatch=True))
BASES = st.sampled_from(["S12", "reference", "s1", "S99", "/dev/zero", "../../../etc/passwd", "other.toml",
                         "sub/other.toml", "../outside.toml", "self.toml", "missing.toml", "config.toml"])


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    return "[" + ", ".join(toml_value(v) for v in value) + "]"


def plausible(key: str):
    """A value of the kind ``key`` takes, in a range a fork might have."""
    kind = SCHEMA[key]
    if isinstance(kind, tuple):
        return st.sampled_from(kind)
    if kind == "bool":
        return st.booleans()
    if kind == "text":
        return st.text(max_size=20)
    if kind == "list":
        return st.lists(st.floats(0, 3000), min_size=0, max_size=6)
    return st.floats(1e-3 if kind == "pos" else 0.0, 500.0)


PAIRS = st.one_of(st.tuples(KEYS, VALUES),
                  st.sampled_from(sorted(SCHEMA)).flatmap(lambda k: st.tuples(st.just(k), plausible(k))))


@st.composite
def config_texts(draw):
    pairs = draw(st.lists(PAIRS, max_size=6))
    lines = []
    if draw(st.integers(0, 3)):
        lines.append(f"base = {json.dumps(draw(st.one_of(st.just('S12'), BASES)))}")
    for key, value in pairs:
        if key in ("solver.timestep_s", "solver.ode_rtol", "solver.ode_atol_mm") and isinstance(value, (int, float)) \
                and 0 < value < 1e-6:
            value = 1e-6  # a valid but tiny step or tolerance makes a slow run, not a different kind of input
        lines.append(f"{key} = {toml_value(value)}")
    text = "\n".join(lines) + "\n"
    mangle = draw(st.sampled_from(["none", "none", "none", "cut", "insert", "nest"]))
    if mangle == "cut" and text:
        text = text[: draw(st.integers(0, len(text)))]
    elif mangle == "insert":
        at = draw(st.integers(0, len(text)))
        text = text[:at] + draw(st.text(max_size=6)) + text[at:]
    elif mangle == "nest":
        depth = draw(st.integers(1, 700))
        text += "deep = " + "[" * depth + "]" * depth + "\n"
    return text


# --- configurations -----------------------------------------------------------------------------


@fuzz_settings("configs")
@given(text=config_texts(), binary=st.one_of(st.none(), st.binary(max_size=64)))
def test_generated_configurations(tmp_path, capfd, text, binary):
    inputs, out = fresh(tmp_path)
    (inputs / "other.toml").write_text('base = "S12"\n')
    (inputs / "sub").mkdir()
    (inputs / "sub" / "other.toml").write_text('base = "../other.toml"\n')
    (inputs / "self.toml").write_text('base = "self.toml"\n')
    (inputs.parent / "outside.toml").write_text('secret_key_of_another_file = 1\n')
    path = inputs / "config.toml"
    if binary is not None:
        path.write_bytes(binary)
    else:
        path.write_text(text)
    status = check(["drop", path, "--duration", "0.002", "--quiet", "--out", out], out, capfd, "configs")
    if status == 0:
        assert sorted(p.name for p in out.iterdir()) == [".lock", ".mtbmj-output.json", "config.toml", "manifest.json",
                                                         "quicklook.png", "summary.json", "timeseries.csv",
                                                         "timeseries_raw.csv"]


# --- records ------------------------------------------------------------------------------------

COLUMNS = ["time_s", "time_ms", "sled_mm", "fork_mm", "tire_mm", "displacement_mm", "force_N", "force_kN",
           "velocity_mm_per_s", "velocity_m_per_s", "distance_m", "height_mm", "foo", "x_furlongs", "", "time_s"]
CELLS = st.one_of(FLOATS.map(repr), st.integers(-1000, 1000).map(str), st.sampled_from(["", "nan", "inf", "abc",
                                                                                         "1e999", "-", "1,5", '"7"']))


@st.composite
def record_files(draw):
    """(file name, bytes): CSV text with unit-suffixed columns, a .mat file or junk."""
    kind = draw(st.sampled_from(["csv", "csv", "csv", "mat", "junk"]))
    if kind == "junk":
        return draw(st.sampled_from(["r.csv", "r.mat"])), draw(st.binary(max_size=200))
    header = draw(st.lists(st.sampled_from(COLUMNS), min_size=1, max_size=4))
    rows = draw(st.integers(0, 40))
    smooth = draw(st.booleans())
    if kind == "mat":
        from scipy.io import savemat

        buffer = io.BytesIO()
        data = {}
        for j, name in enumerate(header):
            key = name or "v"
            n = rows if draw(st.booleans()) else draw(st.integers(0, 40))
            data[key] = (np.linspace(0, 1, n) * (j + 1) if smooth else
                         np.array(draw(st.lists(FLOATS, min_size=n, max_size=n)), dtype=float))
        if draw(st.booleans()):
            data["note"] = "a comment"
        try:
            savemat(buffer, data)
        except Exception:  # a name scipy will not store: junk instead
            return "r.mat", b"MATLAB 5.0 MAT-file" + bytes(20)
        return "r.mat", buffer.getvalue()
    delimiter = draw(st.sampled_from([",", ",", ";", "\t", " "]))
    lines = [f"# mass_kg = {draw(CELLS)}"] if draw(st.booleans()) else []
    lines.append(delimiter.join(header))
    for i in range(rows):
        if smooth:
            cells = [repr(0.001 * i * (j + 1) + 0.5 * math.sin(0.3 * i + j)) for j in range(len(header))]
        else:
            cells = [draw(CELLS) for _ in header]
        if draw(st.integers(0, 20)) == 0:
            cells = cells[:-1]
        lines.append(delimiter.join(cells))
    return "r.csv", ("\n".join(lines) + "\n").encode()


COMMANDS = {
    "spring": ["fit", "spring"],
    "damper": ["fit", "damper"],
    "tire": ["fit", "tire"],
    "sled": ["validate", "--workers", "1", "--duration", "0.05", "--quiet", "RECORD", "S12"],
    "terrain": ["roll", "RECORD", "--speed", "3", "--duration", "0.01", "--quiet"],
}
_WELL_FORMED: dict[str, str] = {}


def well_formed() -> dict[str, str]:
    """A record of each kind that its command accepts (the synthetic generators, the shipped sled
    record, a terrain profile), as CSV text: the starting points of the derived records."""
    if not _WELL_FORMED:
        from importlib import resources

        from mtbmj.identify import dyno_synthetic as dyno, tire_synthetic as tires
        from mtbmj.measured.records import write_csv_text

        def text(record):
            return write_csv_text(dyno._unit_columns(record), record.comments)

        _WELL_FORMED["spring"] = text(dyno.spring_record())
        _WELL_FORMED["damper"] = text(dyno.peak_points(dyno.damper_record()))
        _WELL_FORMED["tire"] = tires.tire_ramp_record()
        _WELL_FORMED["sled"] = (resources.files("mtbmj") / "data" / "sled_example.csv").read_text()
        x = np.linspace(0.0, 3.0, 61)
        _WELL_FORMED["terrain"] = "distance_m,height_mm\n" + "".join(
            f"{a:.3f},{40 * max(0.0, 1 - abs(a - 1.5) / 0.2):.3f}\n" for a in x)
    return _WELL_FORMED


@st.composite
def derived_records(draw, kind: str):
    """A well-formed record of ``kind`` cut, scaled, shifted or spoiled in a few cells."""
    lines = well_formed()[kind].splitlines()
    comments = [line for line in lines if line.startswith("#")]
    body = [line for line in lines if line.strip() and not line.startswith("#")]
    header, rows = body[0], body[1:]
    a = draw(st.integers(0, len(rows)))
    b = draw(st.integers(a, len(rows)))
    step = draw(st.sampled_from([1, 1, 1, 2, 7]))
    rows = rows[a:b:step]
    scale = draw(st.sampled_from([1.0, 1.0, -1.0, 0.0, 1e-3, 1e6]))
    shift = draw(st.sampled_from([0.0, 0.0, 0.25, -1.0]))
    column = draw(st.integers(0, header.count(",")))
    out = []
    for row in rows:
        cells = row.split(",")
        if column < len(cells):
            try:
                cells[column] = repr(float(cells[column]) * scale + shift)
            except ValueError:
                pass
        out.append(",".join(cells))
    for _ in range(draw(st.integers(0, 2))):
        if out:
            i = draw(st.integers(0, len(out) - 1))
            out[i] = draw(st.sampled_from(["", "nan", "x,y", out[i] + ",1", "1e999"]))
    if draw(st.booleans()):
        comments = []
    header = draw(st.sampled_from([header, header, header.replace("_mm", "_m"), header.upper(), header + ",extra_N"]))
    return "r.csv", ("\n".join(comments + [header] + out) + "\n").encode()


@fuzz_settings("records")
@given(data=st.data(), kind=st.sampled_from(sorted(COMMANDS)), derived=st.booleans())
def test_generated_records(tmp_path, capfd, data, kind, derived):
    inputs, out = fresh(tmp_path)
    name, content = data.draw(derived_records(kind) if derived else record_files())
    path = inputs / name
    path.write_bytes(content)
    command = COMMANDS[kind]
    if "RECORD" in command:
        argv = [path if a == "RECORD" else a for a in command]
    else:
        argv = command + [path]
    if kind == "tire":
        argv += data.draw(st.sampled_from([[], ["--mass-kg", "25"], ["--mass-kg", "0"], ["--mass-kg", "nan"]]))
    # 3: a fit that ran and says its model does not explain the record (docs/identification.md)
    check(argv + ["--out", out], out, capfd, "records", results=(0, 3))


# --- SST telemetry ------------------------------------------------------------------------------


@st.composite
def sst_files(draw):
    magic = draw(st.sampled_from([b"SST"] * 6 + [b"SSX", b""]))
    version = draw(st.sampled_from([3] * 6 + [0, 2, 255]))
    rate = draw(st.sampled_from([0, 1, 100, 1000, 1000, 1000, 65535]))
    header = struct.pack("<3sBHHq", magic.ljust(3, b"\0")[:3], version, rate, 0,
                         draw(st.integers(-(2 ** 63), 2 ** 63 - 1)))
    if not magic:
        header = b""
    n = draw(st.integers(0, 30))
    if draw(st.integers(0, 3)) == 0:  # counts in range, one sensor possibly absent: files that read (a
        # success draws a figure, about 2 s, so they are a few of the cases)
        absent = draw(st.sampled_from([None, None, 0, 1]))
        counts = draw(st.lists(st.tuples(st.integers(0, 4095), st.integers(0, 4095)), min_size=n, max_size=n))
        if absent is not None and counts:
            counts[0] = tuple(0xFFFF if k == absent else c for k, c in enumerate(counts[0]))
    else:
        counts = draw(st.lists(st.tuples(st.one_of(st.integers(0, 4095), st.sampled_from([0xFFFF, 4096, 65534])),
                                         st.one_of(st.integers(0, 4095), st.sampled_from([0xFFFF, 4096]))),
                               min_size=n, max_size=n))
    body = b"".join(struct.pack("<HH", a, b) for a, b in counts)
    tail = draw(st.binary(max_size=3))
    cut = draw(st.one_of(st.none(), st.none(), st.none(), st.integers(0, 16)))
    blob = header + body + tail
    return blob[:cut] if cut is not None else blob


SHIPPED_SST = (Path(__file__).resolve().parents[1] / "mtbmj" / "data" / "sst" / "00649.SST").read_bytes()


@fuzz_settings("sst")
@example(blob=SHIPPED_SST, options=[])  # a real ride: the success side is reached whatever hypothesis draws
@given(blob=sst_files(), options=st.just([]) | st.lists(st.sampled_from([
    ["--fork-max-mm", "160"], ["--fork-max-mm", "0"], ["--shock-max-mm", "nan"], ["--bin-percent", "5"],
    ["--bin-percent", "-1"], ["--bin-percent", "1e-9"], ["--threshold-mm-per-s", "inf"]]), max_size=2))
def test_generated_sst_files(tmp_path, capfd, blob, options):
    inputs, out = fresh(tmp_path)
    path = inputs / "ride.SST"
    path.write_bytes(blob)
    check(["telemetry", path, *[a for o in options for a in o], "--out", out], out, capfd, "sst")


# --- option values ------------------------------------------------------------------------------

# Durations: the bad ones, and valid ones short enough to keep a successful run quick (a long
# valid duration is not a different kind of input, only a slower one).
DURATIONS = st.one_of(st.sampled_from(["0.002", "0.001", "0.005", "0", "-1", "1e9", "1e-9", "inf", "-inf", "nan",
                                       "1e309", "", "abc", "0x10", "1e-320", "1e5"]),
                      FLOATS.filter(lambda x: not (0 < x < 1e6)).map(repr))
SETS = st.one_of(st.tuples(st.sampled_from(sorted(SCHEMA)), st.one_of(SCALARS.map(toml_value), NUMBERS)).map("=".join),
                 st.text(max_size=12), st.sampled_from(["a\nb", "fork.spring.model=li\nnear", "=", "=1"]))


@st.composite
def option_argvs(draw):
    command = draw(st.sampled_from(["drop", "roll", "sweep", "fit", "validate", "crosscheck", "study"]))
    n = draw(NUMBERS)
    if command == "drop":
        argv = ["drop", draw(st.sampled_from(["S12", "S1", "reference", "s12", "S0", ""])), "--duration",
                draw(DURATIONS),
                "--engine", draw(st.sampled_from(["mujoco", "ode", "x"]))]
        for s in draw(st.lists(SETS, max_size=3)):
            argv += ["--set", s]
    elif command == "roll":
        argv = ["roll", draw(st.sampled_from(["flat", "root:radius_mm=60", "root:radius_mm=" + n, "rock:x=1",
                                              "nope", ""])),
                "--speed", n, "--head-angle", draw(NUMBERS), "--duration",
                draw(DURATIONS)]
    elif command == "sweep":
        argv = ["sweep", "S12", "--vary", f"{draw(st.sampled_from(sorted(SCHEMA)))}={draw(NUMBERS)}:{draw(NUMBERS)}"
                + draw(st.sampled_from(["", ":2", ":0", ":x", ":1e9", ":-1"])), "--workers", draw(NUMBERS),
                "--duration", draw(DURATIONS),
                "--quiet"]
        if draw(st.booleans()):
            argv += ["--samples", draw(NUMBERS), "--method", draw(st.sampled_from(["lhs", "sobol", "x"]))]
    elif command == "fit":
        argv = ["fit", "drop", "RECORD", "--free", draw(st.sampled_from(["", "fork.spring.preload_N", "x", ",,"])),
                "--bound", draw(st.text(max_size=20)), "--starts", draw(NUMBERS),
                "--engine", draw(st.sampled_from(["mujoco", "ode", "x"]))]
    elif command == "validate":
        argv = ["validate", "example", draw(st.sampled_from(["S12", "S0", "x.toml"])), "--presets",
                draw(st.sampled_from(["S1..S0", "S3..S1", "A1..B2", ",", "S1..S99999999999", "S12", "S0"])),
                "--sled-offset-mm", draw(NUMBERS), "--workers", draw(NUMBERS), "--quiet"]
    elif command == "crosscheck":
        argv = ["crosscheck", "S12", "--tolerance-mm", draw(NUMBERS), "--duration",
                draw(DURATIONS)]
    else:
        argv = ["study", "--presets", draw(st.sampled_from(["S1,S0", "x", "S1,,S0"])), "--workers", draw(NUMBERS),
                "--duration", draw(DURATIONS),
                "--quiet"]
    return argv


@fuzz_settings("options")
@given(argv=option_argvs())
def test_generated_option_values(tmp_path, capfd, argv):
    inputs, out = fresh(tmp_path)
    record = inputs / "drop.csv"
    record.write_text("time_s,sled_mm\n0,0\n0.001,0.1\n")
    argv = [str(record) if a == "RECORD" else a for a in argv]
    if argv[0] == "crosscheck":  # writes nothing: no --out
        check(argv, out, capfd, "options", results=(0, 1))
    elif argv[0] == "sweep":  # exit 1: every variant failed, each with its reason in the table written
        if check(argv + ["--out", out], out, capfd, "options", results=(0, 1)) == 1:
            assert (out / "sweep.parquet").is_file()
    else:
        check(argv + ["--out", out], out, capfd, "options")


def test_enough_cases_per_run():
    """At least 1000 generated cases per run (when the four fuzz tests above ran in this session)."""
    if not set(EXAMPLES) <= set(CASES):
        pytest.skip("not all fuzz tests ran in this session")
    mine = {name: CASES[name] for name in EXAMPLES}  # (tests/test_fuzz_commands.py counts its own)
    print(f"generated cases: {sum(mine.values())} {mine}; exit statuses: {OUTCOMES}")
    assert sum(mine.values()) >= 1000, mine
    for name in EXAMPLES:  # the generators reach both sides of the invariant
        counts = OUTCOMES[name]
        assert counts.get(0, 0) + counts.get(3, 0) > 0 and counts.get(2, 0) > 0, (name, counts)
