"""Configurations: presets, base chains, overrides, the TOML round trip, and every bad input
raising ``ConfigError`` that names the key."""
import math
from pathlib import Path

import pytest

from mtbmj import compose
from mtbmj.cli.common import parse_assignment
from mtbmj.config import SCHEMA, Config, load, preset_names, study_presets
from mtbmj.errors import ConfigError

PRESETS = [f"S{i}" for i in range(1, 15)] + ["air120", "reference"]

# What each preset chooses (spring model, top_out, preload, damper, friction, tire).
EXPECTED = {
    "S1": ("linear", False, False, "linear", "none", "impact"),
    "S2": ("compression_rebound", False, False, "linear", "none", "impact"),
    "S3": ("bilinear", False, False, "linear", "none", "impact"),
    "S4": ("bilinear", True, False, "linear", "none", "impact"),
    "S5": ("progressive", True, False, "linear", "none", "impact"),
    "S6": ("bilinear", True, True, "linear", "none", "impact"),
    "S7": ("progressive", True, True, "linear", "none", "impact"),
    "S8": ("progressive", True, True, "linear", "none", "impact"),
    "S9": ("progressive", True, True, "bilinear", "none", "impact"),
    "S10": ("progressive", True, True, "table", "coulomb", "impact"),
    "S11": ("progressive", True, True, "table", "coulomb", "impact"),
    "S12": ("progressive", True, True, "table", "coulomb", "switch"),
    "S13": ("progressive", True, True, "table", "coulomb", "undamped"),
    "S14": ("progressive", True, True, "table", "coulomb", "static"),
}


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def assert_names(exc_info, *needles):
    message = str(exc_info.value)
    assert "\n" not in message, message
    for needle in needles:
        assert needle in message, f"{needle!r} not in {message!r}"


# --------------------------------------------------------------------------------------- presets


def test_preset_names():
    assert preset_names() == PRESETS
    assert study_presets() == PRESETS[:14]


@pytest.mark.parametrize("name", PRESETS)
def test_every_preset_loads_validates_and_composes(name):
    c = load(name)
    assert c.name == name
    assert all(key in SCHEMA for key in c.values)
    assert c["sled.body_mass_kg"] == 53.2 and c["fork.travel_mm"] == 120.0
    setup = compose.setup(c)  # cross-key rules (knee, table, preload, timestep) pass
    assert setup.body_mass == 53.2 and setup.travel == pytest.approx(0.12)
    assert setup.impact_speed == pytest.approx(math.sqrt(2 * 9.81 * 0.095))
    if name in EXPECTED:
        spring, top_out, preload, damper, friction, tire = EXPECTED[name]
        assert c["fork.spring.model"] == spring
        assert c["fork.spring.top_out"] is top_out and c["fork.spring.preload"] is preload
        assert c["fork.damper.model"] == damper
        assert c["fork.friction.model"] == friction
        assert c["tire.model"] == tire
        assert c.get("description", "").startswith(f"{name}:")
        # every preset builds on reference: two sources, reference first
        assert len(c.sources) == 2 and Path(c.sources[0]).name == "reference.toml"
        assert Path(c.sources[1]).name == f"{name}.toml"


def test_preset_names_are_case_insensitive():
    assert load("s12").values == load("S12").values
    assert load("REFERENCE").values == load("reference").values


def test_units_are_converted_to_si_by_compose():
    c1 = load("S1")
    s = compose.setup(c1)
    assert s.fork.spring.main.rate == pytest.approx(c1["fork.spring.rate_N_per_mm"] * 1e3)  # N/mm -> N/m
    assert s.fork.damper.coefficient == c1["fork.damper.coefficient_N_s_per_m"]
    assert s.tire.impact.rate == pytest.approx(c1["tire.impact_rate_N_per_mm"] * 1e3)
    assert s.tire.impact.damping == c1["tire.impact_damping_N_s_per_m"]
    assert s.drop_height == pytest.approx(0.095) and s.tire_radius == pytest.approx(0.37)
    c12 = load("S12")
    s12 = compose.setup(c12)
    assert s12.fork.spring.main.preload == c12["fork.spring.preload_N"]
    assert s12.fork.spring.main.top_out_rate == pytest.approx(c12["fork.spring.top_out_rate_N_per_mm"] * 1e3)
    assert s12.fork.spring.main.main.cubic == pytest.approx(c12["fork.spring.progressive_cubic_N_per_mm3"] * 1e9)
    stops = s12.fork.spring  # the end stops wrap the spring: the stop keys in SI
    assert stops.travel == pytest.approx(0.12) and stops.stop_rate == pytest.approx(c12["fork.stops.stop_rate_N_per_mm"] * 1e3)
    assert s12.tire.rim.max_deflection == pytest.approx(c12["tire.max_deflection_mm"] * 1e-3)
    assert s12.fork.damper.velocity[0] == pytest.approx(c12["fork.damper.velocity_mm_per_s"][0] * 1e-3)
    assert s12.tire.switches
    assert s12.tire.in_contact.rate == pytest.approx(c12["tire.contact_rate_N_per_mm"] * 1e3)


# ------------------------------------------------------------------------------------ base chains


def test_preset_overrides_its_base():
    ref, s12 = load("reference"), load("S12")
    assert s12["fork.spring.top_out"] is True  # only in S12
    for key, value in ref.values.items():
        if key not in ("description", "reading", "fork.spring.model", "fork.damper.model",
                       "fork.friction.model", "tire.model"):
            assert s12[key] == value, key
    s1 = load("S1")
    assert s1["fork.spring.model"] == "linear" and ref["fork.spring.model"] == "progressive"
    assert s1["description"] != ref["description"]


def test_file_with_preset_base(tmp_path, monkeypatch):
    f = write(tmp_path / "mine.toml", 'base = "S12"\n[sled]\ndrop_height_mm = 150.0\n[fork.spring]\npreload_N = 300\n')
    monkeypatch.chdir(Path("/"))
    c = load(f)
    s12 = load("S12")
    assert c.name == "mine"
    assert c["sled.drop_height_mm"] == 150.0 and c["fork.spring.preload_N"] == 300.0
    assert isinstance(c["fork.spring.preload_N"], float)
    changed = {k for k in s12.values if c.get(k) != s12[k]}
    assert changed == {"sled.drop_height_mm", "fork.spring.preload_N", "description", "reading"}
    assert c.get("description") is None  # the base's description does not describe this file
    assert len(c.sources) == 3 and Path(c.sources[-1]) == f
    assert c.digest() != s12.digest()
    assert compose.setup(c).drop_height == pytest.approx(0.15)


def test_chain_of_files_resolves_relative_bases_from_the_file(tmp_path, monkeypatch):
    sub = tmp_path / "configs"
    sub.mkdir()
    write(sub / "parent.toml", 'base = "S12"\n[sled]\ndrop_height_mm = 150.0\nbody_mass_kg = 60.0\n')
    child = write(sub / "child.toml", 'base = "parent.toml"\n[sled]\ndrop_height_mm = 200.0\n')
    monkeypatch.chdir(tmp_path)  # not the directory of the files
    c = load("configs/child.toml")
    assert c["sled.drop_height_mm"] == 200.0  # child wins
    assert c["sled.body_mass_kg"] == 60.0  # from parent
    assert c["tire.model"] == "switch"  # from S12
    assert c["fork.spring.knee_mm"] == 67.0  # from reference
    assert [Path(s).name for s in c.sources] == ["reference.toml", "S12.toml", "parent.toml", "child.toml"]
    assert Path(c.sources[-1]).resolve() == child.resolve()


def test_base_cycle_is_an_error(tmp_path):
    write(tmp_path / "a.toml", 'base = "b.toml"\n')
    write(tmp_path / "b.toml", 'base = "a.toml"\n')
    with pytest.raises(ConfigError) as exc:
        load(tmp_path / "a.toml")
    assert_names(exc, "base")


def test_base_must_be_text(tmp_path):
    f = write(tmp_path / "c.toml", "base = 12\n")
    with pytest.raises(ConfigError) as exc:
        load(f)
    assert_names(exc, "base")


# -------------------------------------------------------------------------------------- overrides


@pytest.mark.parametrize("text, key, value", [
    ("fork.spring.rate_N_per_mm=12", "fork.spring.rate_N_per_mm", 12),
    ("  fork.spring.rate_N_per_mm = 12.5 ", "fork.spring.rate_N_per_mm", 12.5),
    ("sled.drop_height_mm=1e3", "sled.drop_height_mm", 1000.0),
    ("fork.spring.model=bilinear", "fork.spring.model", "bilinear"),
    ('fork.spring.model="bilinear"', "fork.spring.model", "bilinear"),
    ("fork.spring.top_out=false", "fork.spring.top_out", False),
    ("fork.damper.force_N=[-1, 0, 2.5]", "fork.damper.force_N", [-1, 0, 2.5]),
    ("description=a = b", "description", "a = b"),
])
def test_parse_assignment(text, key, value):
    k, v = parse_assignment(text)
    assert k == key and v == value and type(v) is type(value)


def test_parse_assignment_reads_nan_as_a_float():
    k, v = parse_assignment("fork.spring.rate_N_per_mm=nan")
    assert k == "fork.spring.rate_N_per_mm" and math.isnan(v)


def test_parse_assignment_without_equals_sign():
    with pytest.raises(ConfigError) as exc:
        parse_assignment("fork.spring.rate_N_per_mm")
    assert_names(exc, "fork.spring.rate_N_per_mm")


def test_overrides_apply_and_validate():
    pairs = ["fork.spring.rate_N_per_mm=12", "fork.damper.model=bilinear", "fork.damper.velocity_mm_per_s=[-1, 1]"]
    c = load("S1", dict(parse_assignment(p) for p in pairs))
    assert c["fork.spring.rate_N_per_mm"] == 12.0 and isinstance(c["fork.spring.rate_N_per_mm"], float)
    assert c["fork.damper.model"] == "bilinear"
    assert c["fork.damper.velocity_mm_per_s"] == (-1.0, 1.0)
    assert load("S1")["fork.spring.rate_N_per_mm"] != 12.0  # the preset is untouched
    assert c.digest() != load("S1").digest()
    assert compose.setup(c).fork.spring.main.rate == pytest.approx(12e3)
    # with_overrides on a Config validates too
    with pytest.raises(ConfigError) as exc:
        load("S1").with_overrides({"sled.body_mass_kg": -1})
    assert_names(exc, "sled.body_mass_kg")


# ------------------------------------------------------------------------------------- round trip


@pytest.mark.parametrize("name", PRESETS)
def test_to_toml_round_trips(name, tmp_path):
    c = load(name)
    f = write(tmp_path / f"{name}_copy.toml", c.to_toml())
    back = load(f)
    assert dict(back.values) == dict(c.values)
    assert {k: type(v) for k, v in back.values.items()} == {k: type(v) for k, v in c.values.items()}
    assert back.digest() == c.digest()
    assert back.to_toml() == c.to_toml()
    assert not any(line.startswith("base") for line in c.to_toml().splitlines())  # self-contained


def test_to_toml_round_trips_overrides_and_awkward_text(tmp_path):
    c = load("S12", {
        "description": 'quotes " and \\ backslash, ümlaut, tab\there',
        "fork.damper.force_N": [-300, -175, -95, -40, -12, 0, 14, 45, 115, 225, 420.123456789012],
        "solver.timestep_s": 3.3e-5,
        "sled.drop_height_mm": 0,
    })
    back = load(write(tmp_path / "x.toml", c.to_toml()))
    assert dict(back.values) == dict(c.values)
    assert back.digest() == c.digest()


def test_digest_is_canonical_and_sensitive():
    a = load("S12")
    b = Config("other", dict(reversed(list(a.values.items()))))
    assert a.digest() == b.digest()  # name, order and sources do not matter
    assert len(a.digest()) == 64
    assert a.with_overrides({"sled.drop_height_mm": 95.000001}).digest() != a.digest()


# -------------------------------------------------------------------------------------- bad input


def full_toml_without(name: str, line_start: str) -> str:
    """The full TOML of a preset (no base) with one key's line removed."""
    lines = load(name).to_toml().splitlines()
    kept = [line for line in lines if not line.startswith(line_start)]
    assert len(kept) == len(lines) - 1
    return "\n".join(kept) + "\n"


def test_missing_key_names_the_key(tmp_path):
    f = write(tmp_path / "noknee.toml", full_toml_without("S3", "knee_mm ="))
    c = load(f)  # a valid file on its own ...
    assert "fork.spring.knee_mm" not in c.values
    with pytest.raises(ConfigError) as exc:  # ... but bilinear needs the knee
        compose.setup(c)
    assert_names(exc, "fork.spring.knee_mm", "bilinear")


@pytest.mark.parametrize("preset, line, key", [
    ("S1", "rate_N_per_mm =", "fork.spring.rate_N_per_mm"),
    ("S10", "velocity_mm_per_s =", "fork.damper.velocity_mm_per_s"),
    ("S12", "contact_rate_N_per_mm =", "tire.contact_rate_N_per_mm"),
    ("S12", "body_mass_kg =", "sled.body_mass_kg"),
    ("S12", "drop_height_mm =", "sled.drop_height_mm"),
    ("S12", "top_out_rate_N_per_mm =", "fork.spring.top_out_rate_N_per_mm"),
    ("S10", "coulomb_N =", "fork.friction.coulomb_N"),
])
def test_other_missing_keys(tmp_path, preset, line, key):
    f = write(tmp_path / "missing.toml", full_toml_without(preset, line))
    with pytest.raises(ConfigError) as exc:
        compose.setup(load(f))
    assert_names(exc, key)


@pytest.mark.parametrize("text, needles", [
    # misspelled key, with the hint
    ("[fork.spring]\nrate_N_per_m = 5\n", ["fork.spring.rate_N_per_m", "did you mean fork.spring.rate_N_per_mm"]),
    ("[sled]\nbody_mas_kg = 50\n", ["sled.body_mas_kg", "did you mean sled.body_mass_kg"]),
    ("[solver]\nzzz = 1\n", ["solver.zzz", "unknown key"]),
    # value without its unit in the key name
    ("[fork.spring]\nrate = 5\n", ["fork.spring.rate", "fork.spring.rate_N_per_mm"]),
    ("[sled]\nbody_mass = 50\n", ["sled.body_mass", "sled.body_mass_kg"]),
    # a string with a unit
    ('[fork.spring]\nrate_N_per_mm = "5 N/mm"\n', ["fork.spring.rate_N_per_mm", "5 N/mm"]),
    # wrong types
    ("[fork.spring]\nrate_N_per_mm = true\n", ["fork.spring.rate_N_per_mm"]),
    ("[fork.spring]\ntop_out = 1\n", ["fork.spring.top_out"]),
    ('[fork.damper]\nforce_N = [1, "2"]\n', ["fork.damper.force_N"]),
    # negative values
    ("[sled]\nbody_mass_kg = -53.2\n", ["sled.body_mass_kg", "positive"]),
    ("[sled]\nwheel_mass_kg = 0\n", ["sled.wheel_mass_kg", "positive"]),
    ("[fork.spring]\nrate_N_per_mm = -10\n", ["fork.spring.rate_N_per_mm", "positive"]),
    ("[fork.damper]\ncoefficient_N_s_per_m = -1\n", ["fork.damper.coefficient_N_s_per_m", "negative"]),
    # NaN and infinity
    ("[fork.spring]\nrate_N_per_mm = nan\n", ["fork.spring.rate_N_per_mm", "nan"]),
    ("[sled]\ndrop_height_mm = inf\n", ["sled.drop_height_mm"]),
    ("[fork.damper]\nforce_N = [-300.0, nan, 0.0, 14.0]\n", ["fork.damper.force_N", "NaN"]),
    # unknown model names
    ('[fork.spring]\nmodel = "helical"\n', ["fork.spring.model", "helical", "progressive"]),
    ('[fork.damper]\nmodel = "magic"\n', ["fork.damper.model", "magic"]),
    ('[fork.friction]\nmodel = "dahl"\n', ["fork.friction.model", "dahl"]),
    ('[tire]\nmodel = "tubeless"\n', ["tire.model", "tubeless"]),
    ('[solver]\nintegrator = "rk45"\n', ["solver.integrator", "rk45"]),
])
def test_bad_value_in_a_file_names_the_key(tmp_path, text, needles):
    f = write(tmp_path / "bad.toml", 'base = "S12"\n' + text)
    with pytest.raises(ConfigError) as exc:
        load(f)
    assert_names(exc, "bad.toml", *needles)


@pytest.mark.parametrize("key, value, needles", [
    ("fork.spring.rat_N_per_mm", 5, ["did you mean fork.spring.rate_N_per_mm"]),
    ("fork.spring.rate", 5, ["fork.spring.rate_N_per_mm"]),
    ("fork.spring.rate_N_per_mm", "5 N/mm", ["5 N/mm"]),
    ("sled.body_mass_kg", -1.0, ["positive"]),
    ("fork.spring.rate_N_per_mm", float("nan"), ["nan"]),
    ("fork.spring.model", "helical", ["helical"]),
])
def test_bad_override_names_the_key(key, value, needles):
    with pytest.raises(ConfigError) as exc:
        load("S1", {key: value})
    assert_names(exc, key, *needles)


@pytest.mark.parametrize("preset, overrides, key", [
    # knee outside the travel
    ("S3", {"fork.spring.knee_mm": 150.0}, "fork.spring.knee_mm"),
    ("S3", {"fork.spring.knee_mm": 120.0}, "fork.spring.knee_mm"),
    ("S6", {"fork.travel_mm": 60.0}, "fork.spring.knee_mm"),
    # non-monotonic damper table: velocities, then forces
    ("S10", {"fork.damper.velocity_mm_per_s": [-1500, -800, -400, -150, -50, 0, 50, 150, 400, 1500, 800]},
     "fork.damper.velocity_mm_per_s"),
    ("S10", {"fork.damper.velocity_mm_per_s": [-1500, -800, -400, -150, -50, 0, 50, 150, 400, 800, 800]},
     "fork.damper.velocity_mm_per_s"),
    ("S10", {"fork.damper.force_N": [-300, -175, -95, -40, -12, 0, 14, 45, 115, 500, 420]}, "fork.damper.force_N"),
    # too short
    ("S10", {"fork.damper.velocity_mm_per_s": [-100, 0, 100], "fork.damper.force_N": [-10, 0, 10]},
     "fork.damper.velocity_mm_per_s"),
    # mismatched lengths
    ("S10", {"fork.damper.force_N": [-300, -175, -95, -40, -12, 0, 14, 45, 115, 225]}, "fork.damper.force_N"),
    # table not spanning rebound and compression; offset at zero velocity
    ("S10", {"fork.damper.velocity_mm_per_s": [50, 150, 400, 800], "fork.damper.force_N": [14, 45, 115, 225]},
     "fork.damper.velocity_mm_per_s"),
    ("S10", {"fork.damper.force_N": [-300, -175, -95, -40, -12, 5, 14, 45, 115, 225, 420]}, "fork.damper.force_N"),
    # preload without top-out
    ("S1", {"fork.spring.preload": True}, "fork.spring.preload"),
    ("S5", {"fork.spring.top_out": False, "fork.spring.preload": True}, "fork.spring.preload"),
    # a top-out spring so soft the preload keeps it engaged over the whole travel
    ("S7", {"fork.spring.top_out_rate_N_per_mm": 1.0}, "fork.spring.preload_N"),
    # timestep too large for the stiffness
    ("S1", {"solver.timestep_s": 0.01}, "solver.timestep_s"),
    ("S12", {"solver.timestep_s": 0.002}, "solver.timestep_s"),
    ("S1", {"sled.wheel_mass_kg": 0.001}, "solver.timestep_s"),
    # anti-aliasing above Nyquist
    ("S1", {"solver.antialias_Hz": 600.0}, "solver.antialias_Hz"),
])
def test_cross_key_rules_name_the_key(preset, overrides, key):
    c = load(preset, overrides)  # each value is fine on its own ...
    with pytest.raises(ConfigError) as exc:  # ... the combination is not
        compose.setup(c)
    assert_names(exc, key)


def test_timestep_limit_is_stated_and_honoured():
    """The message says "use at most X s": X itself must then be accepted (a logger rate low
    enough that the sample-rate rule does not interfere)."""
    slow_logger = {"solver.sample_rate_Hz": 300.0, "solver.antialias_Hz": 100.0}
    with pytest.raises(ConfigError) as exc:
        compose.setup(load("S1", {"solver.timestep_s": 0.01, **slow_logger}))
    limit = float(str(exc.value).rsplit("use at most ", 1)[1].split()[0])
    assert 0 < limit < 0.01
    compose.setup(load("S1", {"solver.timestep_s": limit * 0.5, **slow_logger}))
    compose.setup(load("S1", {"solver.timestep_s": limit, **slow_logger}))  # the stated limit


def test_unknown_preset():
    with pytest.raises(ConfigError) as exc:
        load("S15")
    assert_names(exc, "S15", "S14", "reference")


@pytest.mark.parametrize("ref", ["nothere.toml", "no/such/dir/x.toml"])
def test_missing_file(tmp_path, monkeypatch, ref):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError) as exc:
        load(ref)
    assert_names(exc, ref)


def test_missing_base_file(tmp_path):
    f = write(tmp_path / "orphan.toml", 'base = "gone.toml"\n')
    with pytest.raises(ConfigError) as exc:
        load(f)
    assert_names(exc, "gone.toml")


@pytest.mark.parametrize("text", [
    "[fork.spring\nrate_N_per_mm = 5\n",
    "base = S12\n",
    "[sled]\nbody_mass_kg = 5 kg\n",
    "[sled]\nbody_mass_kg = 5\nbody_mass_kg = 6\n",
    "hello, this is not TOML\n",
])
def test_invalid_toml_syntax(tmp_path, text):
    f = write(tmp_path / "syntax.toml", text)
    with pytest.raises(ConfigError) as exc:
        load(f)
    assert_names(exc, "syntax.toml", "TOML")


def test_binary_file_is_a_config_error(tmp_path):
    """A file that is not text (here a PNG header) must be a ConfigError, not a UnicodeDecodeError."""
    f = tmp_path / "picture.png"
    f.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe")
    with pytest.raises(ConfigError) as exc:
        load(f)
    assert_names(exc, "picture.png")


def test_directory_is_a_config_error(tmp_path):
    d = tmp_path / "dir.toml"
    d.mkdir()
    with pytest.raises(ConfigError) as exc:
        load(d)
    assert_names(exc, "dir.toml")


@pytest.mark.parametrize("argv", [["curve", "trail"], ["drop", "SST", "--duration", "0.1"],
                                  ["synth", "spring", "trail"]])
def test_a_bike_preset_given_to_a_fork_command_is_named_a_bike(tmp_path, capsys, argv):
    """A bike preset where a fork's configuration is read was "trail: unknown preset (known: S1, ...)":
    a false cause, trail being a preset; the line says it is a bike's and where it goes. A name of
    neither kind is still unknown (the check can fail)."""
    from helpers import one_line

    out = tmp_path / ("out.csv" if argv[0] == "synth" else "out")
    one_line(capsys, [*argv, "--out", out], f"mtbmj: error: {argv[2 if argv[0] == 'synth' else 1]}: a bike preset (mtbmj bike, sag --bike), not a "
             "fork's configuration (known: S1, ")
    assert not out.exists()
    with pytest.raises(ConfigError, match=r"^trial: unknown preset \(known: S1, .*\) and no such file$"):
        load("trial")
