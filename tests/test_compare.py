"""``mtbmj compare`` / ``mtbmj.readout.compare``: runs made here by ``mtbmj drop`` and ``mtbmj roll``
overlaid (what the figure shows: one line per run on every axis, the runs' own samples, labels
with units, the legend by folder) and tabulated (every summary figure, each run's value as its
summary.json holds it, differences from the first run); what is not a drop or roll result, or a
mix of the two, refused in one line with nothing written."""
import csv
import json

import numpy as np
import pytest

from mtbmj import output
from mtbmj.cli import main
from mtbmj.readout.compare import compare_runs, figure
from helpers import one_line


@pytest.fixture(scope="module")
def drops(tmp_path_factory):
    root = tmp_path_factory.mktemp("drops")
    runs = {"base": ["S12"], "firm": ["S12", "--set", "fork.spring.preload_N=300"],
            "ode": ["S12", "--engine", "ode"]}
    for name, args in runs.items():
        assert main(["drop", *args, "--duration", "0.5", "--quiet", "--out", str(root / name)]) == 0
    return root


@pytest.fixture(scope="module")
def rolls(tmp_path_factory):
    root = tmp_path_factory.mktemp("rolls")
    for speed in ("3", "5"):
        assert main(["roll", "washboard", "--speed", speed, "--duration", "0.4", "--quiet",
                     "--out", str(root / f"v{speed}")]) == 0
    return root


def _leaves(tree, prefix=""):
    """The summary's single values by dotted key, written out here (lists left out)."""
    out = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(_leaves(value, f"{prefix}{key}."))
        elif not isinstance(value, list):
            out[f"{prefix}{key}"] = value
    return out


def _table(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], {row[0]: row[1:] for row in rows[1:]}


def test_drops_are_overlaid_and_their_summaries_differenced(drops, tmp_path, capsys):
    out = tmp_path / "cmp"
    names = ["base", "firm", "ode"]
    assert main(["compare", *[str(drops / n) for n in names], "--out", str(out)]) == 0
    assert "compared 3 drop runs (base, firm, ode)" in capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [".lock", output.RECORD, "compare.png", "differences.csv", "compare.json"])
    header, rows = _table(out / "differences.csv")
    assert header == ["figure", "base", "firm", "ode", "firm - base", "ode - base"]
    summaries = [_leaves(json.loads((drops / n / "summary.json").read_text())) for n in names]
    keys = set().union(*summaries)
    assert set(rows) == keys | {"manifest.name", "manifest.engine"}
    assert rows["manifest.engine"][:3] == ["mujoco", "mujoco", "ode"]
    for key in ("max_fork_mm", "max_tire_mm", "events.fork.peak1.value_mm", "lift_off_s"):
        values = [s[key] for s in summaries]
        assert [float(v) for v in rows[key][:3]] == pytest.approx(values, rel=1e-8)
        assert float(rows[key][3]) == pytest.approx(values[1] - values[0], rel=1e-6, abs=1e-9)
        assert float(rows[key][4]) == pytest.approx(values[2] - values[0], rel=1e-6, abs=1e-9)
    assert float(rows["max_fork_mm"][3]) < -1.0  # the firmer preload compresses the fork less
    flags = [k for k in keys if isinstance(summaries[0][k], bool)]
    assert flags and all(rows[k][0] in ("true", "false") and rows[k][3] == "" for k in flags)
    assert main(["compare", *[str(drops / n) for n in names], "--out", str(out)]) == 0  # replaces its own


def test_the_figure_draws_each_runs_samples_on_four_labelled_axes(drops):
    comparison = compare_runs([drops / "base", drops / "firm"])
    fig = figure(comparison.runs)
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["fork travel (mm)", "tire deflection (mm)", "fork force (N)",
                                               "tire force (N)"]
    assert axes[-1].get_xlabel() == "time (s) from the tire touch"
    for ax, column in zip(axes, ("fork_mm", "tire_mm", "fork_force_N", "tire_force_N")):
        lines = [line for line in ax.get_lines() if not line.get_label().startswith("_")]
        assert [line.get_label().split(" ")[0] for line in lines] == ["base", "firm"]
        assert lines[0].get_color() != lines[1].get_color()
        for line, name in zip(lines, ("base", "firm")):
            text = (drops / name / "timeseries.csv").read_text().splitlines()
            head = [i for i, t in enumerate(text) if t.startswith("time_s,")][0]
            data = np.loadtxt(text[head + 1:], delimiter=",")
            cols = text[head].split(",")
            np.testing.assert_array_equal(line.get_xdata(), data[:, cols.index("time_s")])
            np.testing.assert_array_equal(line.get_ydata(), data[:, cols.index(column)])
    assert axes[0].get_xlim() == pytest.approx((0.0, 0.5))
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["base (S12, mujoco)", "firm (S12, mujoco)"]
    travel = [line for line in axes[0].get_lines() if line.get_linestyle() == ":"]
    assert travel and travel[0].get_ydata()[0] == 120.0  # the full travel, from the runs' config.toml


def test_rolls_compare_with_rolls(rolls, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", str(rolls / "v3"), str(rolls / "v5"), "--out", str(out)]) == 0
    header, rows = _table(out / "differences.csv")
    assert header == ["figure", "v3", "v5", "v5 - v3"]
    assert rows["speed_m_per_s"] == ["3", "5", "2"]
    assert rows["manifest.scenario"][:2] == ["washboard", "washboard"]
    fig = figure(compare_runs([rolls / "v3", rolls / "v5"]).runs)
    assert fig.axes[-1].get_xlabel() == "time (s) from the start of the run"


def test_same_names_in_two_folders_are_told_apart_by_path(drops, tmp_path):
    other = tmp_path / "again"
    other.mkdir()
    assert main(["drop", "S12", "--duration", "0.2", "--quiet", "--out", str(other / "base")]) == 0
    comparison = compare_runs([drops / "base", other / "base"])
    assert [r.label for r in comparison.runs] == [str(drops / "base"), str(other / "base")]


def test_refusals_are_one_line_and_write_nothing(drops, rolls, tmp_path, capsys):
    out = tmp_path / "cmp"
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine\n")
    sag = tmp_path / "sag"
    assert main(["sag", "S12", "--load-kg", "60", "--sag-percent", "25", "--out", str(sag)]) == 0
    fake = tmp_path / "fake"
    fake.mkdir()
    for name in ("summary.json", "timeseries.csv"):
        (fake / name).write_bytes((drops / "base" / name).read_bytes())
    (fake / "manifest.json").write_text('{"name": "my-web-app", "versions": {"node": "20"}}\n')
    cases = [
        ([drops / "base"], "at least two run folders"),
        ([drops / "base", drops / "base"], "given twice"),
        ([drops / "base", mine], f"{mine}: not an mtbmj drop, roll or bike result (no manifest.json)"),
        ([drops / "base", sag], f"{sag}: not an mtbmj drop, roll or bike result"),
        ([drops / "base", fake], "versions name no mtbmj"),
        ([drops / "base", mine / "notes.txt"], "not a folder"),
        ([drops / "base", tmp_path / "missing"],
         "not a folder (give the --out folder of mtbmj drop, mtbmj roll or mtbmj bike)"),
        ([drops / "base", rolls / "v3"], "is a roll and"),
    ]
    for runs, needle in cases:
        one_line(capsys, ["compare", *runs, "--out", out], needle)
        assert not out.exists()
    one_line(capsys, ["compare", drops / "base", drops / "firm", "--out", drops / "base"], "which this command reads")


def test_a_timeseries_without_its_columns_is_refused(drops, tmp_path, capsys):
    broken = tmp_path / "broken"
    broken.mkdir()
    for name in ("summary.json", "manifest.json"):
        (broken / name).write_bytes((drops / "base" / name).read_bytes())
    (broken / "timeseries.csv").write_text("time_s,fork_mm\n0,0\n0.001,1\n")
    one_line(capsys, ["compare", drops / "base", broken, "--out", tmp_path / "o"], "no tire_mm column")
    (broken / "timeseries.csv").write_text("x\n")
    one_line(capsys, ["compare", drops / "base", broken, "--out", tmp_path / "o"], "no time_s column")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("edit, said, told", [
    # re-saved with semicolons: compare misses its columns, telemetry --compare reads one column of text
    (lambda t: t.replace(",", ";"), "no time_s column", "is not a number"),
    (lambda t: t.rsplit(",", 3)[0] + "\n", "values for", "values for"),  # cut off inside its last row
    (lambda t: "\n".join(t.splitlines()[:8] + ["0.0055,x" + ",0" * 7] + t.splitlines()[8:]) + "\n",
     "line 9: 'x' is not a number", "line 9: 'x' is not a number"),  # a value typed in by hand
])
def test_an_edited_timeseries_is_refused_naming_its_line(drops, tmp_path, capsys, edit, said, told):
    """A run's timeseries.csv opened in a spreadsheet and saved, or copied short: numpy's own message
    ("could not convert string ... at row 0, column 1", Python's "list index out of range") reached
    the user; now the line at fault is named, by compare and by telemetry --compare alike."""
    edited = tmp_path / "edited"
    edited.mkdir()
    for name in ("summary.json", "manifest.json", "config.toml"):
        (edited / name).write_bytes((drops / "base" / name).read_bytes())
    (edited / "timeseries.csv").write_text(edit((drops / "base" / "timeseries.csv").read_text()))
    for argv, needle in ((["compare", drops / "base", edited], said),
                         (["telemetry", "example", "--compare", edited], told)):
        err = one_line(capsys, [*argv, "--out", tmp_path / "o"], f"{edited / 'timeseries.csv'}", needle)
        assert "could not convert" not in err and "index out of range" not in err and "cannot read" not in err
        assert needle == "no time_s column" or ": line " in err, err
        assert not (tmp_path / "o").exists()
    assert main(["compare", str(drops / "base"), str(drops / "firm"), "--out", str(tmp_path / "ok")]) == 0
