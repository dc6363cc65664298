"""A bike file's ``base`` chain is read by the same code as a drop configuration's
(``mtbmj.config.read_chain``): the same rules, the same refusals (issue 38 item 4)."""
from __future__ import annotations

import pytest

import mtbmj
from mtbmj.bike import spec
from mtbmj.config import ConfigError


def _bike(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_bike_chain_of_files_merges_from_the_last_base(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    _bike(tmp_path, "sub/heavy.toml", 'base = "trail"\n[rider]\nmass_kg = 90.0\n')
    top = _bike(tmp_path, "mine.toml", 'base = "sub/heavy.toml"\n[bike]\nfork_offset_mm = 51.0\n')
    # a relative base is relative to the folder of the file naming it
    _bike(tmp_path, "sub/again.toml", 'base = "heavy.toml"\n')
    assert spec.load(str(top)) != spec.load("trail")  # the merged file builds a bike
    table, _ = spec.read_table(str(top))
    assert table["rider"]["mass_kg"] == 90.0 and table["bike"]["fork_offset_mm"] == 51.0
    # the rest from the preset: its chart's head angle, the chart turned into the axles it gives
    assert table["bike"]["head_angle_deg"] == spec.read_table("trail")[0]["geometry"]["head_angle_deg"]
    assert spec.read_table(str(tmp_path / "sub/again.toml"))[0]["rider"]["mass_kg"] == 90.0


@pytest.mark.parametrize("kind", ["drop", "bike"])
def test_both_readers_refuse_the_same_chains(tmp_path, monkeypatch, kind):
    monkeypatch.chdir(tmp_path)
    base = "S12" if kind == "drop" else "trail"
    load = mtbmj.load_config if kind == "drop" else spec.load
    _bike(tmp_path, "a.toml", 'base = "b.toml"\n')
    _bike(tmp_path, "b.toml", 'base = "a.toml"\n')
    with pytest.raises(ConfigError, match="base chain longer than"):
        load(str(tmp_path / "a.toml"))
    _bike(tmp_path, "notoml.toml", 'base = "elsewhere.txt"\n')
    with pytest.raises(ConfigError, match="must be a preset name or a .toml file"):
        load(str(tmp_path / "notoml.toml"))
    _bike(tmp_path, "number.toml", "base = 3\n")
    with pytest.raises(ConfigError, match="base must be a preset name or a path"):
        load(str(tmp_path / "number.toml"))
    # a base outside the current directory and the named file's folder is not read
    outside = tmp_path.parent / f"outside-{kind}-{tmp_path.name}.toml"
    outside.write_text(f'base = "{base}"\n')
    try:
        _bike(tmp_path, "far.toml", f'base = "{outside}"\n')
        with pytest.raises(ConfigError, match="lies outside the current directory"):
            load(str(tmp_path / "far.toml"))
    finally:
        outside.unlink()
    _bike(tmp_path, "missing.toml", 'base = "nowhere.toml"\n')
    with pytest.raises(ConfigError):
        load(str(tmp_path / "missing.toml"))


@pytest.mark.parametrize("argv, file, base, kind", [
    (["drop", "{dir}/bike.toml"], "bike.toml", "trail", "a TOML configuration"),
    (["sag", "{dir}/bike.toml", "--load-kg", "70", "--sag-percent", "20"], "bike.toml", "trail", "a TOML configuration"),
    (["bike", "{dir}/fork.toml", "flat", "--speed", "4"], "fork.toml", "S12", "a bike description"),
])
def test_a_file_of_the_other_kind_is_named_so(tmp_path, capsys, argv, file, base, kind):
    """A rider's bike file given to drop or sag (without --bike), or a fork's configuration given to
    bike, was refused as "base 'trail' must be a preset name or a .toml file": but trail is a preset
    name (of bikes). The line now says which kind's preset it is not and asks whether the file is of
    the other kind; the same files given to their own kind's commands run."""
    from mtbmj.cli import main

    (tmp_path / "bike.toml").write_text('base = "trail"\n[rider]\nmass_kg = 72.0\n')
    (tmp_path / "fork.toml").write_text('base = "S12"\n[sled]\nbody_mass_kg = 60.0\n')
    out = tmp_path / "out"
    capsys.readouterr()
    assert main([a.replace("{dir}", str(tmp_path)) for a in argv] + ["--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    if argv[0] == "sag":  # sag tells a bike file from a fork's first, and says what a bike's sag takes
        assert f"{tmp_path / file}: is a bike: give --bike with --front-sag-percent and --rear-sag-percent" in err, err
    else:
        other = "a fork's" if kind == "a bike description" else "a bike's"  # the kind it is, said (careless27)
        assert (f"base '{base}' must be a preset name or a .toml file ('{base}' is no preset of {kind}: {file} is "
                f"{other}, a file of the other kind)" in err), err
    assert not out.exists()
    assert main(["presets", "--show", str(tmp_path / file)]) == 0  # each is a valid file of its own kind
