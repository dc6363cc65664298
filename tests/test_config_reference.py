"""docs/configuration.md against the schema: every key of ``mtbmj.config.SCHEMA`` in it once,
with the unit its name states and the reference preset's value (both read here independently of
the generator), the page identical to what its generator writes, and the commands it shows
running as written; and ``mtbmj presets --show``."""
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from mtbmj.cli import main
from mtbmj.config import PLAUSIBLE, SCHEMA

from helpers import one_line

REPO = Path(__file__).resolve().parents[1]
DOC = REPO / "docs" / "configuration.md"
PRESETS = REPO / "mtbmj" / "presets"

# the units key names state, written out here (longest suffix first)
SUFFIXES = [("_N_s_per_m", "N s/m"), ("_N_per_mm3", "N/mm3"), ("_N_per_mm", "N/mm"), ("_mm_per_s", "mm/s"),
            ("_m_per_s2", "m/s2"), ("_lb_per_in", "lb/in"), ("_percent", "%"), ("_kg", "kg"), ("_mm", "mm"),
            ("_Hz", "Hz"), ("_psi", "psi"), ("_bar", "bar"), ("_cm3", "cm3"), ("_N", "N"), ("_s", "s")]


def _rows() -> dict[str, list[str]]:
    """The table rows of the page's key tables: key -> cells (unit, default, valid, plausible, meaning)."""
    rows: dict[str, list[str]] = {}
    every_key = DOC.read_text().split("\n## 5. Every key\n", 1)[1].split("\n## Bike files\n", 1)[0]
    for line in every_key.splitlines():
        match = re.match(r"^\| `([\w.]+)` \| (.*) \|$", line)
        if match:
            key = match.group(1)
            assert key not in rows, f"{key} twice in {DOC.name}"
            rows[key] = [c.strip() for c in match.group(2).split(" | ")]
    return rows


def _flat(table, prefix=""):
    out = {}
    for key, value in table.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def test_the_page_is_what_its_generator_writes():
    done = subprocess.run([sys.executable, "docs/configuration.py"], cwd=REPO, capture_output=True, text=True,
                          check=True)
    assert done.stdout == DOC.read_text(), ("docs/configuration.md is out of date: "
                                            "python docs/configuration.py > docs/configuration.md")


def test_every_key_is_documented_once_with_its_unit():
    rows = _rows()
    assert sorted(rows) == sorted(SCHEMA)  # none missing, none that the schema does not have
    for key, cells in rows.items():
        assert len(cells) == 5 and cells[4], (key, cells)
        stated = next((unit for suffix, unit in SUFFIXES if key.endswith(suffix)), None)
        if stated is not None:
            assert cells[0] == stated, (key, cells[0])
        else:  # no unit in the name: a count of clicks or spacers, or none
            assert cells[0] in ("-", "clicks", "spacers"), (key, cells[0])


def test_every_default_is_the_reference_presets_value():
    reference = _flat(tomllib.loads((PRESETS / "reference.toml").read_text()))
    rows = _rows()
    for key, cells in rows.items():
        default = cells[1]
        if key not in reference:
            assert default == "none", key
        elif isinstance(reference[key], bool):
            assert default == str(reference[key]).lower(), key
        elif isinstance(reference[key], (int, float)):
            assert float(default) == pytest.approx(reference[key], rel=1e-12), key
        elif isinstance(reference[key], list):
            assert default == f"{len(reference[key])} values", key
        elif key == "description":
            assert default == "(text)"
        else:
            assert default == reference[key], key


def test_ranges_kinds_and_the_derivation_are_on_the_page():
    rows, text = _rows(), DOC.read_text()
    for key, (low, high) in PLAUSIBLE.items():
        assert rows[key][3] == f"{low:g}-{high:g}", key
    assert rows["fork.spring.model"][2].startswith("one of linear, compression_rebound")
    assert rows["sled.front_share_percent"][2] == "> 0, <= 100"
    assert rows["sled.drop_height_mm"][2] == ">= 0" and rows["tire.pressure_psi"][2] == "> 0"
    # the rider derivation and the conversions, as a reader checks them by hand
    assert "sled.front_share_percent / 100 x (sled.rider_mass_kg + sled.bike_mass_kg)" in text
    assert "- sled.wheel_mass_kg" in text and "0.17512684 N/mm" in text and "14.5037738 psi" in text
    for source in ("Dressel & Sadauckas 2020", "Sadauckas et al. 2024", "Renart & Roura-Grabulosa", "assumed"):
        assert source in text


def test_the_commands_the_page_shows_run_as_written(tmp_path):
    text = DOC.read_text()
    blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    commands = [line for block in blocks for line in block.splitlines() if line.startswith("mtbmj ")]
    assert len(commands) >= 2
    mtbmj = Path(sys.executable).parent / "mtbmj"
    for command in commands:
        done = subprocess.run(command.replace("mtbmj", str(mtbmj), 1), shell=True, cwd=tmp_path, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, (command, done.stderr)
        assert "warning" not in done.stderr, (command, done.stderr)
    python = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert python
    for code in python:
        done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        assert "probably meant 48000 g = 48 kg" in done.stdout and "ConfigWarning" in done.stderr


# ------------------------------------------------------------------------------ presets --show


def test_presets_show_prints_every_value_resolved_through_the_base(capsys):
    assert main(["presets", "--show", "S12"]) == 0
    printed = dict(line.split(" = ", 1) for line in capsys.readouterr().out.splitlines())
    # what the two files say, read here: S12's own values over reference.toml's
    expected = _flat(tomllib.loads((PRESETS / "reference.toml").read_text()))
    s12 = tomllib.loads((PRESETS / "S12.toml").read_text())
    assert s12.pop("base") == "reference"
    expected.update(_flat(s12))
    assert sorted(printed) == sorted(expected)
    for key, value in expected.items():
        shown = tomllib.loads(f"v = {printed[key]}")["v"]
        if isinstance(value, (str, bool)):
            assert shown == value, key
        else:
            assert shown == pytest.approx(value, rel=1e-12), key
    assert printed["fork.spring.preload"] == "true" and printed["tire.model"] == '"switch"'


def test_presets_show_of_an_air_fork_and_of_a_users_file(tmp_path, capsys):
    assert main(["presets", "--show", "air120"]) == 0
    out = capsys.readouterr().out
    assert "fork.spring.air_pressure_psi = 85.0\n" in out and 'fork.spring.model = "air"\n' in out
    mine = tmp_path / "mine.toml"
    mine.write_text('base = "S12"\n[sled]\nrider_mass_kg = 85\nbike_mass_kg = 11\nfront_share_percent = 58\n'
                    '[fork.spring]\nrate_lb_per_in = 90\n')
    assert main(["presets", "--show", str(mine)]) == 0
    printed = dict(line.split(" = ", 1) for line in capsys.readouterr().out.splitlines())
    assert float(printed["sled.body_mass_kg"]) == pytest.approx(0.58 * 96 - 2.3, rel=1e-12)
    assert float(printed["fork.spring.rate_N_per_mm"]) == pytest.approx(90 * 4.4482216152605 / 25.4, rel=1e-12)
    assert "fork.spring.rate_lb_per_in" not in printed


@pytest.mark.parametrize("name", ["S99", "nope", ""])
def test_presets_show_of_an_unknown_name_is_one_line(capsys, name):
    err = one_line(capsys, ["presets", "--show", name], "--show" if not name else name)
    assert capsys.readouterr().out == ""
    assert "S12" in err  # the known names


def test_presets_lists_the_presets_as_before(capsys):
    assert main(["presets"]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert names[:3] == ["configurations", "S1", "S2"] and "air120" in names and "reference" in names
    assert names[names.index("bikes"):] == ["bikes", "sst", "trail"]  # the bikes after the configurations


def test_every_bike_key_is_on_the_page_with_its_range():
    """A bike file's keys (mtbmj.bike.spec.KNOWN) each have a row in the page's bike section, with
    the plausible range the warnings use (issue 40: the bike's keys were documented nowhere)."""
    from mtbmj.bike import keys, spec

    section = DOC.read_text().split("\n## Bike files\n", 1)[1]
    rows = {m.group(1): m.group(2) for m in re.finditer(r"^\| `([\w.]+)` \| (.*) \|$", section, re.M)}
    known = {f"{s}.{k}" for s, ks in spec.KNOWN.items() if ks for k in ks}
    assert known <= set(rows)
    for key, (_, _, rng) in keys.KEYS.items():
        if rng is not None and not isinstance(rng[0], tuple):
            assert f"{rng[0]:g}-{rng[1]:g}" in rows[key], key
