"""Careless input, round 27: what a new user types on the commands earlier rounds covered least
(study, fit's kinds, bike's --start-m, sweep, sensitivity, presets --show, the fork's keys typed with
a unit only, --out onto another command's folder). Each case failed before its fix: a traceback, a
refusal for a false reason, a run that did not do what was asked, or a message that did not name
the way out. Inputs are written here; refusals are checked by ``helpers.check`` (one line, exit 2,
nothing written at --out, nothing left beside it)."""
from __future__ import annotations

import json

import pytest

from helpers import command_err as _err, fresh, refused


# --- study: a preset in another case, a file, a list with a space or a trailing comma ----------------

@pytest.mark.parametrize("presets,names", [("s1", ["S1"]), ("S1, S2", ["S1", "S2"]), ("S1,", ["S1"])])
def test_study_takes_presets_as_typed(tmp_path, capfd, presets, names):
    """'s1' was a KeyError traceback (exit 1: the run named itself S1), 'S1, S2' refused ' S2' as
    an unknown preset and 'S1,' read '' as the current folder."""
    out = tmp_path / "study"
    status, err = _err(["study", "--presets", presets, "--engines", "ode", "--duration", "0.02", "--quiet",
                        "--out", out], capfd)
    assert status == 0, err
    assert sorted(json.loads((out / "study_summary.json").read_text())) == names


def test_study_takes_a_configuration_file(tmp_path, capfd):
    """A TOML file among --presets: the run is named after the file's stem (it was a KeyError)."""
    config = tmp_path / "soft.toml"
    config.write_text('base = "S1"\n[fork.spring]\npreload_N = 150\n')
    out = tmp_path / "study"
    status, err = _err(["study", "--presets", f"{config},S1", "--engines", "ode", "--duration", "0.02", "--quiet",
                        "--out", out], capfd)
    assert status == 0, err
    assert sorted(json.loads((out / "study_summary.json").read_text())) == ["S1", "soft"]


@pytest.mark.parametrize("presets,said", [("S1,s1", "S1 is named twice"), ("", "no preset named"),
                                          (" , ", "no preset named")])
def test_study_refuses_a_preset_twice_or_none(tmp_path, capfd, presets, said):
    """'S1,s1' ran S1 twice into one result; an empty --presets ran all fourteen."""
    _, out = fresh(tmp_path)
    refused(["study", "--presets", presets, "--engines", "ode", "--duration", "0.02", "--out", out], out, capfd, said)


# --- bike --start-m: the default duration from the start; a start past everything refused ---------

def test_a_start_before_the_terrain_still_crosses_the_feature(tmp_path, capfd):
    """From --start-m -5 the default run ended 5 m short: the rear never reached the rock (its
    travel the static 48 mm, no window closed). Now the run is as long as the distance asks and the
    rear's peak is the one a start at the terrain's start gives (a naive baseline: the static rear)."""
    runs = {}
    for name, start in (("at0", []), ("before", ["--start-m", "-5"])):
        out = tmp_path / name
        status, err = _err(["bike", "sst", "rock", "--speed", "3", *start, "--quiet", "--no-figure", "--out", out],
                           capfd)
        assert status == 0, err
        runs[name] = json.loads((out / "summary.json").read_text())
    at0, before = runs["at0"], runs["before"]
    assert at0["max_rear_travel_mm"] > at0["static_rear_travel_mm"] + 10.0  # the rock reaches the rear
    assert before["max_rear_travel_mm"] == pytest.approx(at0["max_rear_travel_mm"], abs=0.5)
    assert before["feature"]["closed"]
    assert before["start_m"] == pytest.approx(-5.0)
    assert before["duration_s"] == pytest.approx(at0["duration_s"] + 5.0 / 3.0, abs=0.01)  # 5 m more at 3 m/s


@pytest.mark.parametrize("scenario,start,said", [("rock", "30", "past the feature of rock"),
                                                 ("rock", "3.7", "the rear axle at 2.44 m"),
                                                 ("flat", "10", "past the end of the terrain flat")])
def test_a_start_past_everything_is_refused(tmp_path, capfd, scenario, start, said):
    """--start-m 30 past a rock ran on the level ground beyond and reported '0 % tire-load variation
    over the feature'; now one line. --start-m 9 on flat (10 m) still runs."""
    _, out = fresh(tmp_path)
    refused(["bike", "sst", scenario, "--speed", "3", "--start-m", start, "--quiet", "--no-figure", "--out", out],
            out, capfd, said)


# --- rider.height_m: read by the active rider only --------------------------------------------------

def test_the_passive_rider_says_it_does_not_read_the_height(tmp_path, capfd):
    """A passive run given rider.height_m said nothing (the height changed nothing); now one warning
    line, and none for the active rider, who reads it, nor for a run without the key."""
    lines = {}
    for name, extra in (("passive", ["--set", "rider.height_m=1.9"]), ("plain", []),
                        ("active", ["--set", "rider.height_m=1.9", "--rider", "active"])):
        out = tmp_path / name
        status, err = _err(["bike", "sst", "flat", "--speed", "3", "--duration", "0.2", *extra, "--quiet",
                            "--no-figure", "--out", out], capfd)
        assert status == 0, err
        lines[name] = [line for line in err.splitlines() if "rider.height_m" in line]
    assert len(lines["passive"]) == 1 and "active rider only" in lines["passive"][0]
    assert lines["plain"] == [] and lines["active"] == []


# --- one unknown-preset message; a unit typed as a key; sensitivity's outputs named ------------------

def test_presets_show_and_the_lookup_give_one_message(capfd):
    """presets --show had its own unknown-preset line beside mtbmj.presets.locate's; now it is
    locate's, which names the bikes too where either kind is taken."""
    from mtbmj.errors import ConfigError
    from mtbmj.presets import bike_preset_names, locate, preset_names

    status, err = _err(["presets", "--show", "S99"], capfd)
    with pytest.raises(ConfigError) as said:
        locate("S99", bikes=True)
    assert status == 2 and err == f"mtbmj: error: {said.value}\n"
    assert all(n in err for n in preset_names() + bike_preset_names())
    with pytest.raises(ConfigError) as fork_only:  # where only a fork's configuration is taken: its names
        locate("S99")
    assert "bikes" not in str(fork_only.value) and "S12" in str(fork_only.value)


@pytest.mark.parametrize("typed,meant", [("fork.spring.psi", "fork.spring.air_pressure_psi"),
                                         ("tire.psi", "tire.pressure_psi"), ("fork.spring.N", "fork.spring.preload_N"),
                                         ("fork.spring.preload", "fork.spring.preload_N")])
def test_a_unit_typed_as_the_key_names_the_key_in_it(tmp_path, capfd, typed, meant):
    """fork.spring.psi suggested fork.spring.tokens (spelling alone); fork.spring.preload=60 said
    only 'must be true or false'. The same through a bike's --fork-set."""
    _, out = fresh(tmp_path)
    line = refused(["drop", "S12", "--set", f"{typed}=60", "--out", out], out, capfd, meant)
    assert "tokens" not in line
    refused(["bike", "sst", "flat", "--speed", "3", "--fork-set", f"{typed}=60", "--out", out], out, capfd, meant)


def test_a_unit_typed_as_a_key_of_the_bikes_part_in_advise(tmp_path, capfd):
    """advise --try-set fork:fork.spring.psi on a coil-sprung fork suggested fork.spring.model,
    preload_N and knee_mm; now the adjusters the advice tries (the fork has no key in psi)."""
    _, out = fresh(tmp_path)
    line = refused(["advise", "example", "--bike", "sst", "--try-set", "fork:fork.spring.psi=60", "--out", out], out,
                   capfd, "the adjusters the advice tries")
    assert "knee_mm" not in line and "model" not in line


def test_sweep_vary_of_a_switch_names_its_number(tmp_path, capfd):
    _, out = fresh(tmp_path)
    refused(["sweep", "S12", "--vary", "fork.spring.preload=100:300:2", "--out", out], out, capfd,
            "did you mean fork.spring.preload_N?")


def test_sensitivity_output_lists_the_outputs(tmp_path, capfd):
    """--output peak said only that it was not an output; now every numeric output is named (the
    events' grid as one pattern), and each named one is taken."""
    from mtbmj.sweep.sensitivity import check_outputs
    from mtbmj.sweep.variants import OUTPUT_COLUMNS

    _, out = fresh(tmp_path)
    line = refused(["sensitivity", "S12", "--vary", "fork.spring.preload_N=100:300", "--output", "peak", "--out",
                    out], out, capfd, "{sled,fork,tire}_{peak1,topping,peak2,valley1,peak3}_{mm,s}")
    listed = line.split("they are ", 1)[1].rstrip(")").split(", ")
    named = [f"{s}_{e}_{u}" for s in ("sled", "fork", "tire") for e in ("peak1", "topping", "peak2", "valley1", "peak3")
             for u in ("mm", "s")] + listed[1:]
    assert sorted(named) == sorted(c for c in OUTPUT_COLUMNS if c not in
                                   ("lifts_off", "fork_tops_out", "at_rest", "bottomed_out"))
    assert check_outputs(named) == named


# --- fit: a record of the wrong kind names what it is ----------------------------------------------

def _spring_record(path):
    """A spring test as a dyno writes it: one slow stroke, 60 -> 110 mm at 50 mm/s, 200 Hz."""
    import numpy as np

    t = np.arange(0.0, 2.0, 0.005)
    x = 60.0 + 50.0 * np.minimum(t, 1.0) - 50.0 * np.maximum(t - 1.0, 0.0)
    rows = "\n".join(f"{a:.3f},{b:.4f},{200.0 + 8.0 * b:.2f}" for a, b in zip(t, x))
    path.write_text("time_s,displacement_mm,force_N\n" + rows + "\n")
    return path


def test_fit_damper_given_a_spring_record_says_so(tmp_path, capfd):
    """It said 'too few points (1, need at least 6)' of a file of 400 rows."""
    inputs, out = fresh(tmp_path)
    record = _spring_record(inputs / "spring.csv")
    line = refused(["fit", "damper", record, "--out", out], out, capfd, "a spring test: fit spring")
    assert "400 rows" in line
    status, err = _err(["fit", "spring", record, "--out", out], capfd)  # and fit spring takes it
    assert status in (0, 3), err


def test_fit_tire_given_a_spring_record_names_the_columns(tmp_path, capfd):
    """It asked for the drop's mass ('give mass_kg') of a file that is no drop at all."""
    inputs, out = fresh(tmp_path)
    record = _spring_record(inputs / "spring.csv")
    refused(["fit", "tire", record, "--out", out], out, capfd,
            "missing column deflection_<unit> (columns: time_s, displacement_mm, force_N)")


# --- --out onto a folder another command wrote ---------------------------------------------------------

def test_a_folder_of_another_command_is_not_replaced(tmp_path, capfd):
    """roll --out onto a drop's folder replaced the drop's result (each entry was mtbmj's); now it is
    refused naming the command that wrote it, the drop untouched; the drop replaces its own."""
    out = tmp_path / "mine"
    drop = ["drop", "S12", "--duration", "0.02", "--quiet", "--no-figure", "--out", out]
    status, err = _err(drop, capfd)
    assert status == 0, err
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".lock"}
    status, err = _err(["roll", "rock", "--speed", "3", "--duration", "0.02", "--quiet", "--no-figure", "--out", out],
                       capfd)
    assert status == 2 and err == (f"mtbmj: error: {out}: holds the result of mtbmj drop, which roll would replace: "
                                   f"choose another --out (or remove the folder first)\n")
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".lock"} == before
    assert not [p for p in out.parent.iterdir() if p.name.startswith(f".{out.name}.")]
    status, err = _err(drop, capfd)  # its own: replaced as before
    assert status == 0, err


def test_the_kinds_of_fit_share_their_folder(tmp_path, capfd):
    """fit spring and fit damper share out/fit by default: one replaces the other, as before."""
    out = tmp_path / "fit"
    for kind in ("spring", "damper"):
        status, err = _err(["fit", kind, "example", "--out", out], capfd)
        assert status in (0, 3), err
    assert json.loads((out / ".mtbmj-output.json").read_text())["command"] == "fit damper"


# --- a finished sweep run again into its folder -------------------------------------------------------

def test_a_finished_sweep_is_said_to_be_finished(tmp_path, capfd):
    """A sweep run again into its finished folder was refused with 'pass --resume to continue it'
    (nothing was left to continue). The refusal stays (the journal's guard, tests/test_sweep.py) and
    says the sweep there finished and that --resume reuses its runs; --resume then answers."""
    out = tmp_path / "sweep"

    def argv(n, *more):
        return ["sweep", "S12", "--vary", f"fork.spring.preload_N=100:300:{n}", "--duration", "0.02", "--workers", "1",
                "--quiet", "--csv", *more, "--out", out]

    status, err = _err(argv(2), capfd)
    assert status == 0, err
    before = (out / "sweep.csv").read_bytes()
    status, err = _err(argv(3), capfd)
    assert status == 2 and "holds a finished sweep (2 variants); pass --resume to reuse its runs" in err, err
    assert "continue" not in err and (out / "sweep.csv").read_bytes() == before
    status, err = _err(argv(3, "--resume"), capfd)
    assert status == 0, err
    rows = (out / "sweep.csv").read_text().splitlines()
    column = rows[0].split(",").index("fork.spring.preload_N")
    assert sorted(float(r.split(",")[column]) for r in rows[1:]) == [100.0, 200.0, 300.0]


# --- names as typed: a scenario in capitals, radians, a preset's file name, a file with no base ------

def test_a_scenario_in_capitals_is_the_scenario(tmp_path, capfd):
    """'Rock' was 'unknown scenario' beside a list holding rock (presets are named in any case)."""
    runs = {}
    for name in ("rock", "Rock"):
        out = tmp_path / name
        status, err = _err(["roll", name, "--speed", "3", "--duration", "0.3", "--quiet", "--no-figure", "--out",
                            out], capfd)
        assert status == 0, err
        runs[name] = json.loads((out / "summary.json").read_text())
    assert runs["Rock"]["max_fork_mm"] == runs["rock"]["max_fork_mm"] > 0.0
    _, out = fresh(tmp_path)
    refused(["roll", "Rocky", "--speed", "3", "--out", out], out, capfd, "unknown scenario 'Rocky'")


def test_a_head_angle_in_radians_is_named_so(tmp_path, capfd):
    _, out = fresh(tmp_path)
    # the numeric gate refuses first since round 32b (it holds the rig's (45, 90]), naming the radians as a slip
    refused(["roll", "rock", "--speed", "3", "--head-angle", "1.13", "--out", out], out, capfd,
            "(a unit mistake? probably meant 1.13 rad = 64.74 deg)")
    line = refused(["roll", "rock", "--speed", "3", "--head-angle", "25", "--out", out], out, capfd,
                   "25 deg is outside the range allowed: above 45")
    assert "radians" not in line


@pytest.mark.parametrize("base,said", [('base = "S12.toml"', "(the preset is named without .toml: S12)"),
                                       ("", 'starts from no preset: a file gives every key or names one it changes, '
                                            'e.g. base = "S12"')])
def test_a_configuration_file_without_a_preset_base_says_how_to_name_one(tmp_path, capfd, base, said):
    """base = "S12.toml" said only 'no such configuration file'; a file without base said
    'sled.wheel_mass_kg: missing', naming neither the file nor the way out."""
    inputs, out = fresh(tmp_path)
    config = inputs / "mine.toml"
    config.write_text(f"{base}\n[fork.spring]\npreload_N = 300\n")
    line = refused(["drop", config, "--out", out], out, capfd, said)
    assert base or "mine.toml" in line


def test_a_bike_base_named_as_a_file(tmp_path, capfd):
    inputs, out = fresh(tmp_path)
    bike = inputs / "mine.toml"
    bike.write_text('base = "sst.toml"\n[rider]\nmass_kg = 80\n')
    refused(["bike", bike, "flat", "--speed", "3", "--out", out], out, capfd, "(the preset is named without .toml: sst)")


@pytest.mark.parametrize("argv,said", [
    (["bike", "sst", "flat", "--speed", "3", "--set", "rider.kg=80"], "the unit is part of the key's name: rider.mass_kg"),
    (["bike", "sst", "flat", "--speed", "3", "--set", "shock.spring_rate=500"],
     "shock.spring_rate_N_per_mm or shock.spring_rate_lb_per_in"),
    (["bike", "sst", "flat", "--speed", "3", "--fork-set", "fork.spring.preload_N"], "--fork-set fork.spring.preload_N: "
                                                                                     "expected key=value"),
    (["advise", "example", "--bike", "sst", "--try-set", "rider.mass_kg"], "--try-set rider.mass_kg: expected"),
    (["advise", "example", "--bike", "sst", "--try-set", "shock.spring_rate=500"],
     "--try-set shock.spring_rate=500: shock.spring_rate: unknown key; the unit is part")])
def test_a_bike_key_without_its_unit_and_the_option_named_as_typed(tmp_path, capfd, argv, said):
    """shock.spring_rate listed every key of [shock]; --try-set and --fork-set refusals said '--set'."""
    _, out = fresh(tmp_path)
    line = refused(argv + ["--out", out], out, capfd, said)
    assert "--set" in argv or "--set" not in line  # named as typed


# --- a travel CSV under the name .SST ----------------------------------------------------------------------

def _travel_csv(path, seconds=20.0):
    """Generated travel: a fork and a shock moving over bumps (both ends, 1 kHz)."""
    import numpy as np

    t = np.arange(0.0, seconds, 0.001)
    fork = 40.0 + 25.0 * np.sin(2 * np.pi * 1.3 * t) ** 2 + 5.0 * np.sin(2 * np.pi * 7.0 * t)
    shock = 15.0 + 8.0 * np.sin(2 * np.pi * 1.3 * (t - 0.3)) ** 2
    path.write_text("time_s,fork_mm,shock_mm\n" + "\n".join(f"{a:.3f},{b:.3f},{c:.3f}" for a, b, c in
                                                            zip(t, np.clip(fork, 0, 170), shock)) + "\n")
    return path


def test_a_travel_csv_renamed_sst_is_read_as_one(tmp_path, capfd):
    """It was refused: 'not an SST file (starts with b'tim', expected b'SST')'. Read by its text, it
    gives what the same file named .csv gives; a binary file that is no SST is still refused."""
    results = {}
    for name in ("ride.csv", "ride.SST"):
        ride = _travel_csv(tmp_path / name)
        out = tmp_path / f"out_{name}"
        status, err = _err(["telemetry", ride, "--out", out], capfd)
        assert status == 0, err
        results[name] = json.loads((out / "telemetry.json").read_text())
    text = {n: json.dumps(r, sort_keys=True).replace(n, "RIDE") for n, r in results.items()}  # its name apart
    assert text["ride.csv"] == text["ride.SST"]
    assert results["ride.SST"]["measured"]["duration_s"] == pytest.approx(20.0, abs=0.01)
    inputs, out = fresh(tmp_path)
    junk = inputs / "junk.SST"
    junk.write_bytes(bytes(range(256)) * 4)
    refused(["telemetry", junk, "--out", out], out, capfd, "not an SST file")


def test_try_given_a_forks_configuration_says_it_is_one(tmp_path, capfd):
    """advise --try my_fork.toml asked whether the file was 'of the other kind, a bike's or a fork's';
    it says which, and a base that is no preset of either kind asks nothing."""
    inputs, out = fresh(tmp_path)
    fork = inputs / "fork.toml"
    fork.write_text('base = "air120"\n[fork.spring]\nair_pressure_psi = 70\n')
    refused(["advise", "example", "--bike", "sst", "--try", fork, "--out", out], out, capfd,
            "fork.toml is a fork's, a file of the other kind")
    odd = inputs / "odd.toml"
    odd.write_text('base = "nonesuch"\n')
    line = refused(["drop", odd, "--out", out], out, capfd, "'nonesuch' is no preset of a TOML configuration)")
    assert "other kind" not in line


# --- a choice typed in another case ------------------------------------------------------------------------

def test_a_choice_in_another_case_is_the_choice(tmp_path, capfd):
    """--engine MuJoCo, --rider Active, study --engines MuJoCo,ODE were refused as invalid choices
    beside lists holding them (presets and stances are taken in any case); now each runs as the
    choice in lower case, with the same result; a word that is no choice is still refused."""
    results = {}
    for engine in ("mujoco", "MuJoCo"):
        out = tmp_path / engine
        status, err = _err(["drop", "S12", "--engine", engine, "--duration", "0.05", "--quiet", "--no-figure",
                            "--out", out], capfd)
        assert status == 0, err
        results[engine] = (out / "timeseries.csv").read_bytes()
    assert results["mujoco"] == results["MuJoCo"]
    out = tmp_path / "study"
    status, err = _err(["study", "--engines", "MuJoCo,ODE", "--presets", "S1", "--duration", "0.02", "--quiet",
                        "--out", out], capfd)
    assert status == 0, err
    _, out = fresh(tmp_path)
    refused(["drop", "S12", "--engine", "Mujocoo", "--out", out], out, capfd,
            "invalid choice: 'Mujocoo' (choose from 'mujoco', 'ode', 'fast')")
    from mtbmj.cli import build_parser

    args = build_parser().parse_args(["bike", "sst", "flat", "--speed", "3", "--rider", "Active"])
    assert args.rider == "active"


# --- bob given a record that holds no pedalling ------------------------------------------------------------

SST_SENSORS = {"fork_arm_mm": 134.9375, "fork_max_mm": 234.15625, "shock_arm1_mm": 98.9, "shock_arm2_mm": 202.8,
               "shock_max_mm": 230.0}  # the sst bike's calibration (data/sst README)


@pytest.mark.parametrize("kind,warned", [("pedalling", False), ("slam", True)])
def test_bob_says_a_record_holds_no_steady_pedalling(tmp_path, capfd, kind, warned):
    """A seat slam's ring-down (00083.SST) was read as a bob of 1.6 Hz and 25 mm and a climb pedalled
    to match it, without a word; its strokes spread 8.5x. A generated slam says so in a warning
    line; a generated steady pedalling record (the baseline) does not."""
    import numpy as np

    from helpers import write_v3

    t = np.arange(0.0, 20.0, 0.001)
    if kind == "pedalling":
        shock = 16.0 + 4.0 * np.sin(2 * np.pi * 1.6 * t) + 0.3 * np.sin(2 * np.pi * 0.2 * t)
    else:
        after = np.clip(t - 5.0, 0.0, None)
        shock = 16.0 + 30.0 * np.exp(-after / 0.8) * np.sin(2 * np.pi * 1.6 * after) * (t > 5.0)
    ride = write_v3(tmp_path / "ride.SST", 40.0 + 0.2 * np.sin(2 * np.pi * 1.6 * t), np.clip(shock, 1.0, 60.0),
                    SST_SENSORS)
    out = tmp_path / "bob"
    status, err = _err(["bob", ride, "--out", out], capfd)
    assert status == 0, err
    said = [line for line in err.splitlines() if "no steady pedalling" in line]
    assert len(said) == (1 if warned else 0), err
    notes = json.loads((out / "bob.json").read_text())["records"][0]["notes"]
    assert any("no steady pedalling" in n for n in notes) == warned


# --- a file named in another case --------------------------------------------------------------------------

@pytest.mark.parametrize("argv,there", [
    (["reconstruct", "{in}/ride.sst", "--bike", "sst"], "ride.SST"),
    (["drop", "{in}/mine.toml"], "Mine.toml"),
    (["bike", "{in}/my_bike.toml", "flat", "--speed", "3"], "My_Bike.toml")])
def test_a_file_named_in_another_case_is_pointed_at(tmp_path, capfd, argv, there):
    """On a case-sensitive file system ride.sst for ride.SST said only 'No such file or directory'."""
    inputs, out = fresh(tmp_path)
    (inputs / there).write_text("whatever\n")
    line = refused([a.replace("{in}", str(inputs)) for a in argv] + ["--out", out], out, capfd,
                   f"(there is {inputs / there})")
    assert "no such" in line.lower()
    (inputs / there).unlink()  # nothing in any case: no pointer
    line = refused([a.replace("{in}", str(inputs)) for a in argv] + ["--out", out], out, capfd, "o")
    assert "there is" not in line


def test_a_bike_sweep_varying_a_parts_key_names_the_part_prefix(tmp_path, capfd):
    """sweep sst --vary fork.spring.preload_N pointed at --fork-set (which sets one value for every
    variant, not a range); a part's key is varied as fork:KEY, which runs."""
    _, out = fresh(tmp_path)
    line = refused(["sweep", "sst", "--roll", "rock", "--speed", "3", "--vary", "fork.spring.preload_N=100:300:2",
                    "--out", out], out, capfd, "(--vary fork:fork.spring.preload_N=LO:HI:N)")
    assert "--fork-set" not in line
    status, err = _err(["sweep", "sst", "--roll", "rock", "--speed", "3", "--vary", "fork:fork.spring.preload_N=100:300:2",
                        "--duration", "0.2", "--quiet", "--out", out], capfd)
    assert status == 0, err


def test_sensitivity_given_a_grid_does_not_speak_of_samples(tmp_path, capfd):
    """sensitivity --vary KEY=100:300:3 said 'with --samples give the range only', an option the
    user never typed (sensitivity always samples)."""
    _, out = fresh(tmp_path)
    refused(["sensitivity", "S12", "--vary", "fork.spring.preload_N=100:300:3", "--out", out], out, capfd,
            "a sampled range (sensitivity, sweep --samples) takes no count; give the range only, key=lo:hi")
