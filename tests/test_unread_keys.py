"""A key the caller sets that the part's model does not read is refused in one line (first issue's kind:
what a careless input still broke). On the SST preset, whose fork spring is progressive
(``fork.spring.progressive_rate_N_per_mm``), ``--fork-set fork.spring.rate_N_per_mm=9.75`` was taken
silently and changed nothing: the run printed as if the fork were stiffer. And a shock spring typed in
the other unit (``fork.spring.rate_lb_per_in``) over the file's ``rate_N_per_mm`` was refused as "the
same value given in two units", although the user's key replaces the file's."""
from __future__ import annotations

import pytest

from mtbmj import cli, compose
from mtbmj.cli.common import Typed
from mtbmj.bike import run, spec
from mtbmj.config import load
from mtbmj.errors import ConfigError

LB_PER_IN = 4.4482216152605 / 0.0254  # N/m per lb/in, written here from the pound-force and the inch


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("argv, key, model, reads", [
    (["bike", "sst", "flat", "--speed", "5", "--fork-set", "fork.spring.rate_N_per_mm=9.75"],
     "fork.spring.rate_N_per_mm", "'progressive'", "progressive_rate_N_per_mm"),
    (["bike", "sst", "flat", "--speed", "5", "--shock-set", "fork.spring.progressive_rate_N_per_mm=50"],
     "fork.spring.progressive_rate_N_per_mm", "'linear'", "rate_N_per_mm"),
    (["bike", "sst", "flat", "--speed", "5", "--fork-set", "fork.damper.rebound_clicks=3"],
     "fork.damper.rebound_clicks", "'table'", "force_N"),
    (["drop", "S1", "--set", "fork.spring.progressive_rate_N_per_mm=9", "--engine", "fast"],
     "fork.spring.progressive_rate_N_per_mm", "'linear'", "rate_N_per_mm"),
])
def test_a_key_the_model_does_not_read_is_refused_naming_the_model_and_what_it_reads(argv, key, model, reads,
                                                                                     capsys, tmp_path):
    out = tmp_path / "out"
    assert cli.main(argv + ["--out", str(out)]) == 2
    err = one_line(capsys)
    assert key in err and model in err and reads in err and "would change nothing" in err
    if "--fork-set" in argv or "--shock-set" in argv:
        assert ("--fork-set" if "--fork-set" in argv else "--shock-set") in err  # which part's key
    assert not out.exists()  # nothing half-written


def test_the_key_the_model_reads_changes_the_spring():
    """The refusal is not a blanket one: the progressive fork's own key sets its rate (read back from
    the composed law), and the preset's keys its model does not read (the reference's, beneath) pass."""
    fork, _ = run.setups(spec.load("sst", {"fork.set": {"fork.spring.progressive_rate_N_per_mm": 9.75}}))
    assert fork.fork.spring.main.main.rate == pytest.approx(9.75e3)
    base, _ = run.setups(spec.load("sst"))
    assert base.fork.spring.main.main.rate == pytest.approx(6.5e3)


def test_a_spring_typed_in_the_other_unit_replaces_the_file_s():
    """The SST file's shock spring is ``rate_N_per_mm`` = 80; ``--shock-set fork.spring.rate_lb_per_in=500``
    replaces it (500 lb/in is 87.56 N/mm, written out here), where it was refused as given twice."""
    _, shock = run.setups(spec.load("sst", {"shock.set": {"fork.spring.rate_lb_per_in": 500.0}}))
    assert shock.fork.spring.main.main.rate == pytest.approx(500.0 * LB_PER_IN, rel=1e-9)
    # in one source (the same set table typed twice) the two units are still refused
    with pytest.raises(ConfigError, match="two units"):
        load("reference", {"fork.spring.rate_lb_per_in": 500.0, "fork.spring.rate_N_per_mm": 80.0})


def test_only_the_keys_a_person_typed_are_held_to_it():
    """A bike file whose base set a bilinear shock damper and which itself chooses a table of clicks keeps
    the base's coefficients in [shock.set] unread: they are the files', and the bike composes
    (``tests/test_bike_shock_clicks.py`` has such a file). Keys a program sets (a sweep's grid, a fit's
    trial: a plain dict) pass; the command line's (``mtbmj.cli.common.Typed``) are refused."""
    c = load("S1")  # a linear spring: its file's progressive keys (from the reference) are not read
    assert "fork.spring.progressive_rate_N_per_mm" in c.values
    compose.setup(c)  # taken
    compose.setup(c.with_overrides({"fork.spring.progressive_rate_N_per_mm": 7.0}))  # a program's: taken
    with pytest.raises(compose.NotRead, match="progressive_rate_N_per_mm"):
        compose.setup(c.with_overrides(Typed({"fork.spring.progressive_rate_N_per_mm": 7.0})))
    with pytest.raises(compose.NotRead, match="progressive_rate_N_per_mm"):  # typed once, held through later sets
        compose.setup(load("S1", Typed({"fork.spring.progressive_rate_N_per_mm": 7.0}))
                      .with_overrides({"fork.spring.rate_N_per_mm": 9.0}))
    taken = compose.setup(c.with_overrides(Typed({"fork.spring.rate_N_per_mm": 7.0})))
    assert taken.fork.spring.main.rate == pytest.approx(7e3)
    # the bike: a program's set table passes, the command line's is refused naming its option
    run.setups(spec.load("sst", {"fork.set": {"fork.spring.rate_N_per_mm": 9.75}}))
    with pytest.raises(ConfigError, match="--fork-set fork.spring.rate_N_per_mm"):
        run.setups(spec.load("sst", {"fork.set": Typed({"fork.spring.rate_N_per_mm": 9.75})}))
