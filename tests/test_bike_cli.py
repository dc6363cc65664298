"""Your own bike from the command line (issue 40's findings): bike keys changed with --set, the
fork's and the shock's with --fork-set / --shock-set; the bike presets listed and shown; two bike
folders compared."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

import mtbmj
from mtbmj.bike import replay
from mtbmj.cli import main


def test_set_changes_the_bike_as_a_file_would(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["bike", "trail", "root", "--speed", "5", "--duration", "0.6", "--set", "rider.mass_kg=78",
                 "--shock-set", "fork.spring.rate_N_per_mm=90", "--out", "set", "--quiet", "--no-figure"]) == 0
    (tmp_path / "mine.toml").write_text('base = "trail"\n[rider]\nmass_kg = 78.0\n[shock.set]\n'
                                        '"fork.spring.rate_N_per_mm" = 90.0\n')
    assert main(["bike", "mine.toml", "root", "--speed", "5", "--duration", "0.6", "--out", "file", "--quiet",
                 "--no-figure"]) == 0
    a = np.genfromtxt(tmp_path / "set" / "timeseries.csv", delimiter=",", names=True, skip_header=2)
    b = np.genfromtxt(tmp_path / "file" / "timeseries.csv", delimiter=",", names=True, skip_header=2)
    assert np.array_equal(a["front_travel_mm"], b["front_travel_mm"]) and np.array_equal(a["stroke_mm"], b["stroke_mm"])
    manifest = json.loads((tmp_path / "set" / "manifest.json").read_text())
    assert manifest["bike_overrides"] == {"rider.mass_kg": 78, "shock.set": {"fork.spring.rate_N_per_mm": 90}}
    # the folder replays with its overrides (what render draws)
    again = replay.rerun(tmp_path / "set")
    assert np.max(np.abs(again.raw["front_travel_mm"] - a["front_travel_mm"])) < 1e-6  # the CSV keeps 9 digits
    capsys.readouterr()


@pytest.mark.parametrize("argv,words", [
    (["--set", "rider.weight=78"], "unknown key"),
    (["--set", "mass_kg=78"], "SECTION.KEY"),
    (["--set", "wheels.size=29"], "unknown section"),
    (["--fork-set", "sled.body_mass_kg=10"], "not used by the bike"),
    # a part's configuration key given as a bike key, and the other way round: the line says where it goes
    (["--set", "fork.spring.air_pressure_psi=60"], "goes with --fork-set, e.g. --fork-set fork.spring.air_pressure_psi="),
    (["--set", "shock.damper.rebound_N_s_per_m=900"], "--shock-set fork.damper.rebound_N_s_per_m="),
    (["--fork-set", "spring.air_pressure_psi=60"], "did you mean 'fork.spring.air_pressure_psi'?"),
    (["--shock-set", "shock.damper.rebound_N_s_per_m=900"], "did you mean 'fork.damper.rebound_N_s_per_m'?"),
    (["--shock-set", "shock.spring_rate_lb_per_in=450"], "given on the command line with --set "
                                                          "shock.spring_rate_lb_per_in=VALUE"),
    (["--fork-set", "rider.mass_kg=78"], "with --set rider.mass_kg=VALUE"),
])
def test_bad_overrides_are_one_line(tmp_path, monkeypatch, capsys, argv, words):
    monkeypatch.chdir(tmp_path)
    assert main(["bike", "trail", "flat", "--speed", "4", "--out", "run", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and not (tmp_path / "run").exists()


def test_no_hint_where_the_key_is_no_part_s_either(tmp_path, monkeypatch, capsys):
    """The hints above name a key that exists: a --set key that no part's configuration has either gets
    the bike's table only, a --fork-set key with no near configuration key no guess."""
    monkeypatch.chdir(tmp_path)
    for argv in (["--set", "shock.rebound_clicks=8"], ["--set", "fork.spring.stiffness=8"],
                 ["--fork-set", "spring.stiffness=8"]):
        assert main(["bike", "trail", "flat", "--speed", "4", "--out", "run", *argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "-set" not in err.split(":", 2)[2].replace(argv[0], "") \
            and "did you mean" not in err, err


@pytest.mark.parametrize("text", ["", "[rider]\nmass_kg = 72.0\n"])
def test_a_bike_file_lacking_keys_names_itself_and_a_base(tmp_path, monkeypatch, capsys, text):
    """An empty bike file, or one of a few keys without a base, said only "bike.head_angle_deg: missing":
    not which file, nor that a base gives the rest. A preset's keys stand in the message's place."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text(text)
    assert main(["bike", "mine.toml", "flat", "--speed", "4", "--out", "run"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mine.toml: bike." in err and ": missing" in err
    assert 'base = "' in err and not (tmp_path / "run").exists()
    (tmp_path / "mine.toml").write_text('base = "trail"\n' + text)  # the base the message names rides
    assert main(["bike", "mine.toml", "flat", "--speed", "4", "--duration", "0.2", "--out", "run"]) == 0


def test_a_bad_value_in_a_bike_file_names_the_file_and_one_typed_does_not(tmp_path, monkeypatch, capsys):
    """A rider's mass of -5 kg in the file said only "rider.mass_kg: must be > 0": not which file. Typed
    with --set, the option is where it came from, and the file is not blamed."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text('base = "trail"\n[rider]\nmass_kg = -5\n')
    assert main(["bike", "mine.toml", "flat", "--speed", "4", "--out", "run"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mine.toml: rider.mass_kg: must be > 0" in err
    (tmp_path / "mine.toml").write_text('base = "trail"\n')
    assert main(["bike", "mine.toml", "flat", "--speed", "4", "--out", "run", "--set", "rider.mass_kg=-5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "rider.mass_kg: must be > 0" in err and "mine.toml" not in err
    assert not (tmp_path / "run").exists()


def test_presets_shows_a_bike_file_saved_with_a_byte_order_mark(tmp_path, capsys):
    """A bike file saved by Notepad as "UTF-8" (a byte-order mark first) was taken for a configuration
    of the fork schema and refused as not valid TOML."""
    text = 'base = "trail"\n[rider]\nmass_kg = 72.0\n'
    (tmp_path / "plain.toml").write_text(text)
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert main(["presets", "--show", str(tmp_path / "plain.toml")]) == 0
    plain = capsys.readouterr().out
    assert "rider.mass_kg = 72.0" in plain
    assert main(["presets", "--show", str(tmp_path / "bom.toml")]) == 0
    assert capsys.readouterr().out == plain


def test_presets_show_of_an_unknown_name_lists_both_kinds(capsys):
    """``--show`` takes a configuration or a bike preset; a misspelt one listed the configurations
    alone, as if sst and trail were not presets. A known name of each kind, typed in another case,
    is shown (the check can pass)."""
    from helpers import one_line

    err = one_line(capsys, ["presets", "--show", "trial"], "trial: unknown preset", "S12", "air120", "bikes sst, trail")
    assert "no such file" in err
    for name in ("TRAIL", "s12"):
        assert main(["presets", "--show", name]) == 0
        assert " = " in capsys.readouterr().out


@pytest.mark.parametrize("text", ['[drive]\nchainring_teeth = 30\n', '[sensors]\nfork_arm_mm = 130.0\n',
                                  '[fork.set]\n"fork.spring.preload_N" = 120.0\n', 'description = "mine"\n'])
def test_presets_shows_a_bike_file_of_a_bike_s_base_and_bike_keys_alone(tmp_path, capsys, text):
    """A bike file changing only [drive], [sensors] or [fork.set] of a bike preset (or nothing) was taken
    for a fork's configuration and refused ("base 'trail' ... is it a file of the other kind?"), though
    mtbmj bike runs it; it is a bike by its sections or its base, through a chain of files too. A fork's
    configuration on S12 is still shown as one."""
    (tmp_path / "mine.toml").write_text('base = "trail"\n' + text)
    (tmp_path / "over.toml").write_text('base = "mine.toml"\n')
    for name in ("mine.toml", "over.toml"):
        assert main(["presets", "--show", str(tmp_path / name)]) == 0, capsys.readouterr().err
        assert "rider.mass_kg = 85.0" in capsys.readouterr().out
    (tmp_path / "fork.toml").write_text('base = "S12"\n[fork]\ntravel_mm = 110.0\n')
    assert main(["presets", "--show", str(tmp_path / "fork.toml")]) == 0
    out = capsys.readouterr().out
    assert "fork.travel_mm = 110.0" in out and "rider.mass_kg" not in out


def test_presets_lists_and_shows_the_bikes(capsys):
    assert main(["presets"]) == 0
    out = capsys.readouterr().out
    assert "bikes (" in out and "\n  sst " in out and "\n  trail " in out
    assert main(["presets", "--show", "trail"]) == 0
    shown = dict(line.split(" = ", 1) for line in capsys.readouterr().out.splitlines() if " = " in line)
    assert shown["geometry.head_angle_deg"] == "65.5" and shown["rider.mass_kg"] == "85.0"  # from its base, sst
    assert shown["shock.set.fork.spring.rate_N_per_mm"] == "80.0"
    # the axles the chart gives, as comments: the rear axle the drop above the BB and a chainstay from
    # it, the front axle level with it a wheelbase ahead (trail: 1225, 435.5, 16.4 mm)
    rear_x = -math.sqrt(435.5 ** 2 - 16.4 ** 2)
    assert shown["#   bike.rear_axle_mm"] == f"[{rear_x:.1f}, 16.4]"
    assert shown["#   bike.front_axle_mm"] == f"[{1225.0 + rear_x:.1f}, 16.4]"
    assert shown["#   bike.head_angle_deg"] == "65.50"


def test_two_bike_folders_compare(tmp_path, monkeypatch, capsys):
    """`mtbmj compare` of two bike folders answered 'no fork_mm column'."""
    monkeypatch.chdir(tmp_path)
    for name, mass in (("light", 70), ("heavy", 100)):
        r = mtbmj.run_bike("trail", "root", speed_m_per_s=5.0, duration=0.8, overrides={"rider.mass_kg": mass})
        r.write(tmp_path / name, figure=False)
    assert main(["compare", "light", "heavy", "--out", "cmp"]) == 0
    line = capsys.readouterr().out
    light = json.loads((tmp_path / "light" / "summary.json").read_text())["max_front_travel_mm"]
    assert line.startswith("compared 2 bike runs (light, heavy): front travel peak ") and f"{light:.1f} / " in line
    from mtbmj.readout import compare

    fig = compare.figure(compare.load_runs([tmp_path / "light", tmp_path / "heavy"]))
    assert [ax.get_ylabel() for ax in fig.axes] == [label for _, label in compare.BIKE_SIGNALS]
    assert all(len([ln for ln in ax.lines if ln.get_label().startswith(("light", "heavy"))]) == 2 for ax in fig.axes)
    rows = (tmp_path / "cmp" / "differences.csv").read_text().splitlines()
    assert any(r.startswith("mass_kg.rider,70,100,30") for r in rows)
