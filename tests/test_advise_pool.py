"""``mtbmj advise RIDE RIDE ...``: several rides of one setting pooled into one advice (issue 52 item 4,
mtbmj/ride/advice_pool.py).

Two kinds of input. Advices made here by hand (no simulation, as tests/test_advise_verdict.py): rides
whose simulated and recorded series differ by known offsets per segment, so the pooled verdict and
the pooled spread have closed forms. And rides made by the independent whole bike of
tests/helpers.py (``advise_ride``: scipy's solve_ivp on its own equations, written as SST v3 counts)
on different terrains (seeds) at one setting, the fork far too soft."""
from __future__ import annotations

import json
import shutil
from argparse import Namespace

import numpy as np
import pytest

from mtbmj.cli import main
from mtbmj.ride import advice_pool, advise

from helpers import advise_ride, reconstruction_passing, reconstruction_stand_in

TOP_F, TOP_R = 130.0, 125.0
T = np.linspace(0.0, 20.0, 4000)  # 20 s: four 5 s segments, no sample on an edge between two
SEG = np.minimum((T // 5.0).astype(int), 3)


def wave(seed):
    rng = np.random.default_rng(seed)
    return 50.0 + 15.0 * np.sin(2 * np.pi * 1.3 * T) + 5.0 * np.sin(2 * np.pi * 4.1 * T + rng.uniform(0, 6))


REAR = 0.9 * wave(2)


def run(label, front, static_f_percent):
    m = advise.ride_metrics(T, front, REAR, TOP_F, TOP_R, static=(static_f_percent / 100 * TOP_F, 0.28 * TOP_R))
    return advise.Run(label, {}, m, advise.penalties(m), front, REAR, None, T.copy())


def made(name, seed, base_static, cands, record_off=0.02, offsets=(0.0, 0.0, 0.0, 0.0)):
    """One ride's Advice by hand: its simulated fork ``wave(seed)``, recorded ``record_off`` of travel
    below it; each candidate ``(direction, value, static sag %)`` rides the fork ``offsets`` (points
    of travel per segment) deeper than the recorded setting."""
    front = wave(seed)
    base = run("recorded setting", front, base_static)
    deeper = front + np.asarray(offsets)[SEG] / 100 * TOP_F
    adj = advise.Adjuster("front", "fork.set", "fork.spring.rate_N_per_mm", 5.0, 4.5, 5.5, "fork spring rate")
    measured = advise.ride_metrics(T, front - record_off * TOP_F, REAR, TOP_F, TOP_R)
    recon = {"speed_m_per_s": 6.0, "checks": {"front_reproduced_rms_mm": 1.0, "rear_predicted_rms_mm": 5.0,
                                                "rear_predicted_rms_percent_of_used": 10.0,
                                                "samples_checked_percent": 90.0}}
    a = advise.Advice(name, "bike", recon, measured, base,
                      [(adj, d, v, run(f"{d} {v}", deeper, s)) for d, v, s in cands], None,
                      front - record_off * TOP_F, REAR, record_t=T.copy())
    a.recommendation, a.verdict = advise.judge(a)
    return a


def test_rides_that_agree_give_their_answer_and_a_narrower_spread():
    """Two rides, each advising the stiffer spring (static sag 40 -> 22 %): the pooled answer is
    theirs. The candidate rides the fork -4, +4, -4, +4 points deeper per segment on one ride, the
    other way on the other: a ride's bootstrap mean over its 4 segments is -4 + 2K (K ~ Bin(4, 1/2)),
    its 5-95 % interval -4..4 (half 4); pooled, over 8 segments, -4 + K (K ~ Bin(8, 1/2)): -2..2 (half 2)."""
    a = made("A.SST", 1, 40.0, [("up", 5.5, 22.0)], offsets=(-4, 4, -4, 4))
    b = made("B.SST", 3, 40.0, [("up", 5.5, 22.0)], offsets=(4, -4, 4, -4))
    assert a.verdict["answer"] == b.verdict["answer"] == "change"
    p = advice_pool.combine([a, b], [])
    advice_pool.judge(p)
    assert p.verdict["answer"] == "change", p.verdict
    assert (p.recommendation["key"], p.recommendation["direction"], p.recommendation["to"]) == (
        "fork:fork.spring.rate_N_per_mm", "up", 5.5)
    (_, _, _, pooled_run), = p.candidates
    key = "front.dynamic_sag_percent"
    one = [r.spread(r.candidates[0][3])[key] for r in (a, b)]
    assert one == [pytest.approx(4.0, abs=1e-9)] * 2
    assert p.spread(pooled_run)[key] == pytest.approx(2.0, abs=1e-9)
    # the whole uncertainty of the change (the model's error beside it) narrower than one ride's too
    assert p.change_uncertainty(pooled_run)[key] < min(r.change_uncertainty(r.candidates[0][3])[key] for r in (a, b))
    # the pooled metrics: both rides' 20 s together; a count summed, per minute over the 40 s
    assert p.base.metrics["duration_s"] == pytest.approx(40.0)
    assert p.base.metrics["front"]["bottom_outs"] == a.base.metrics["front"]["bottom_outs"] + b.base.metrics[
        "front"]["bottom_outs"]
    d = p.to_dict()
    assert [(e["ride"], e["answer"]) for e in d["rides"]] == [("A.SST", "change"), ("B.SST", "change")]
    # the report: the rides' table after the change, every column of every table with its unit
    import re

    html = p.html(b"png")
    tables = dict(re.findall(r'<table id="(\w+)">(.*?)</table>', html, re.S))
    assert set(tables) == {"changes", "match", "candidates", "rides"}
    for name, body in tables.items():
        heads = re.findall(r"<th>(.*?)</th>", re.search(r"<tr>(.*?)</tr>", body, re.S).group(1))
        if "unit" not in heads:  # no unit column: each header names its own
            assert all("(" in h for h in heads[1:]), (name, heads)
    assert "<td>A.SST</td><td>20.0</td><td>change</td><td>fork spring rate 5 -&gt; 5.5</td>" in tables["rides"]


def test_rides_that_contradict_each_other_are_inconclusive_saying_so():
    """One ride's fork sits at 40 % sag (a stiffer spring advised), the other's at 10 % (a softer one
    advised): the pooled answer is inconclusive, naming the adjuster and each ride's way."""
    a = made("A.SST", 1, 40.0, [("up", 5.5, 22.0), ("down", 4.5, 55.0)])
    b = made("B.SST", 3, 10.0, [("up", 5.5, 2.0), ("down", 4.5, 22.0)])
    assert (a.recommendation["direction"], b.recommendation["direction"]) == ("up", "down")
    p = advice_pool.combine([a, b], [])
    advice_pool.judge(p)
    assert p.verdict["answer"] == "inconclusive" and p.recommendation is None
    why = p.verdict["why"]
    assert why.startswith("the rides disagree (fork spring rate: ") and "raised by A.SST" in why
    assert "lowered by B.SST" in why and "one setting should give one answer" in why
    assert p.line().startswith("2 rides (A.SST, B.SST) on bike: inconclusive: the rides disagree")


def _record(sst, bike):
    from mtbmj.cli.telemetry import ride_record

    return ride_record(sst, Namespace(bike=str(bike), fork_max_mm=None, shock_max_mm=None))


def _made_rides(folder, seeds, seconds):
    """Rides of the soft fork (5 N/mm) made by the independent whole bike on the terrains of ``seeds``,
    each copied to its own name (seed<N>.SST); the one bike file."""
    out = []
    for seed in seeds:
        bike, sst, *_ = advise_ride(folder / f"s{seed}", seconds=seconds, fork_rate=5.0, seed=seed)
        out.append(shutil.copy(sst, folder / f"seed{seed}.SST"))
    return bike, out


@pytest.mark.slow  # 26 whole-bike runs of 21 s: about 3 min on two busy cores
def test_made_rides_of_one_setting_pooled(tmp_path):
    """Two 20 s rides of the fork far too soft on two terrains and a 10 s one: the short ride is left
    out naming why; the pooled answer raises the fork's spring (the truth), no ride contradicts it,
    and the change's spread is narrower pooled than on one ride alone."""
    bike, (a, b) = _made_rides(tmp_path, (21, 5), 20.0)
    _, (short,) = _made_rides(tmp_path, (8,), 10.0)
    with reconstruction_passing():
        p = advice_pool.pooled([_record(x, bike) for x in (a, short, b)], str(bike), workers=2, search=False)
    assert [r["ride"] for r in p.refused] == ["seed8.SST"] and "cannot support advice" in p.refused[0]["why"]
    assert [r.ride for r in p.rides] == ["seed21.SST", "seed5.SST"]
    assert p.verdict["answer"] == "change", p.verdict
    rec = p.recommendation
    assert (rec["key"], rec["direction"]) == ("fork:fork.spring.rate_N_per_mm", "up")
    for r in p.rides:  # each ride alone: never the fork spring lowered
        said = [] if r.recommendation is None else [r.recommendation] + r.recommendation["then"]
        assert all(c["direction"] == "up" for c in said if c["key"] == rec["key"]), said
    (pooled_run,) = [c[3] for c in p.candidates if c[0].name == rec["key"] and c[1] == "up"]
    for key in ("front.dynamic_sag_percent", "front.max_travel_percent"):
        alone = [next(c[3] for c in r.candidates if c[0].name == rec["key"] and c[1] == "up") for r in p.rides]
        one = [r.spread(x)[key] for r, x in zip(p.rides, alone)]
        # narrower than one ride's (the wider): not always than both, where the change itself differs
        # from terrain to terrain (the rides' own means apart: measured 0.433 pooled against 0.355 and
        # 0.550 alone for the dynamic sag; 0.447 against 0.442 on one ride on the point-contact rides)
        assert p.spread(pooled_run)[key] < max(one), (key, p.spread(pooled_run)[key], one)
    out = tmp_path / "advice"
    p.write(out)
    d = json.loads((out / "advice.json").read_text())
    assert [e["ride"] for e in d["rides"]] == ["seed21.SST", "seed5.SST"] and d["refused"][0]["ride"] == "seed8.SST"
    # one calibration for the pool, from both kept rides (not the first's): between the rides' own scales
    cal = d["calibration"]
    assert "2 rides pooled" in cal["method"]
    for end in ("front", "rear"):
        per = [e["spring_scales"][end] for e in d["rides"]]
        assert min(per) - 1e-9 <= cal["springs"][end]["scale"] <= max(per) + 1e-9, (end, per, cal["springs"][end])
    for end in ("front", "rear"):  # the bike file says the springs ridden (the soft fork's 5 N/mm): x1 held
        assert cal["springs"][end]["low"] <= 1.0 <= cal["springs"][end]["high"], (end, cal["springs"][end])
    assert cal["rides"] == 2 and d["rides"][0]["spring_scales"] != d["rides"][1]["spring_scales"]
    html = (out / "advice.html").read_text()
    assert 'id="rides"' in html and 'id="refused"' in html and "<th>length (s)</th>" in html
    from helpers import CHROMIUM, rendered

    if CHROMIUM.exists():  # the pooled report as a browser shows it: the rides' table there, one row each
        result, dom = rendered(out / "advice.html", tmp_path)
        assert result["tables"]["rides"]["visible"] and result["tables"]["rides"]["rows"] == 3
        assert result["resources"] == [] and "seed8.SST: 10.0 s of ride cannot support advice" in dom


def test_a_bad_file_among_the_rides_is_one_line_before_any_work(tmp_path, capsys, monkeypatch):
    """A ride that is not a recording among good ones: one line naming it, exit 2, nothing
    reconstructed or simulated, nothing written."""
    reached = reconstruction_stand_in(monkeypatch)
    bike, (good,) = _made_rides(tmp_path, (21,), 16.0)
    bad = tmp_path / "broken.SST"
    bad.write_bytes(b"SST\x03 not a recording")
    out = tmp_path / "advice"
    assert main(["advise", str(good), str(bad), "--bike", str(bike), "--out", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("mtbmj: warning")]
    assert len(err) == 1 and err[0].startswith("mtbmj: error: ") and "broken.SST" in err[0], err
    assert not reached and not out.exists()


def test_one_ride_given_twice_is_refused_in_one_line_before_any_work(tmp_path, capsys, monkeypatch):
    """A careless pool: the same ride twice, by one path or by a copy under another name (a glob over two
    folders): one line naming both, exit 2, nothing reconstructed, nothing written. Two different rides of
    one setting are not taken for one (the check can fail)."""
    import pathlib

    reached = reconstruction_stand_in(monkeypatch)
    bike, (a, b) = _made_rides(tmp_path, (21, 5), 10.0)
    a, b = pathlib.Path(a), pathlib.Path(b)
    copy = tmp_path / "copy.SST"
    shutil.copyfile(a, copy)
    for pair in ((a, a), (a, copy)):
        out = tmp_path / "advice"
        assert main(["advise", *map(str, pair), "--bike", str(bike), "--out", str(out)]) == 2
        err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("mtbmj: warning")]
        assert len(err) == 1 and err[0].startswith(f"mtbmj: error: {pair[1].name}: the same ride as {a.name}"), err
        assert not reached and not out.exists()
    from mtbmj.ride.advice_pool import repeated
    from mtbmj.measured.telemetry import read_ride

    assert repeated([read_ride(a), read_ride(b)]) is None


def test_no_ride_left_is_a_refusal_naming_each(tmp_path, capsys):
    """Two rides each too short: the refusal names both and why, exit 2, nothing written."""
    bike, (a, b) = _made_rides(tmp_path, (21, 5), 10.0)
    out = tmp_path / "advice"
    assert main(["advise", str(a), str(b), "--bike", str(bike), "--out", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("mtbmj: warning")]
    assert err == ["mtbmj: error: none of the 2 rides can be advised on: seed21.SST: 10.0 s of ride cannot support "
                   "advice (at least 15 s); seed5.SST: 10.0 s of ride cannot support advice (at least 15 s)"], err
    assert not out.exists()


def test_pooled_through_the_command_keeps_stderr_clean_when_piped(tmp_path, capfd, monkeypatch):
    """Two made rides through the command (each run cut to 0.3 s: the plumbing, not the advice):
    exit 0, each ride's own answer on the terminal, and stderr free of the progress counter (it is
    not a terminal here)."""
    real = advise.simulate

    def short(bike, overrides, terrain, speed, duration, label, lead_s, profile=None):
        return real(bike, overrides, terrain, speed, min(duration, 0.3), label, lead_s, profile)

    monkeypatch.setattr(advise, "simulate", short)
    bike, (a, b) = _made_rides(tmp_path, (21, 5), 16.0)
    out = tmp_path / "advice"
    with reconstruction_passing():
        assert main(["advise", str(a), str(b), "--bike", str(bike), "--workers", "1", "--out", str(out)]) == 0
    got = capfd.readouterr()
    assert "run 1/" not in got.err and "\r" not in got.err and "advise [" not in got.err, got.err
    assert "seed21.SST alone: " in got.out and "seed5.SST alone: " in got.out
    d = json.loads((out / "advice.json").read_text())
    assert d["ride"] == "2 rides (seed21.SST, seed5.SST)" and len(d["rides"]) == 2


@pytest.mark.slow  # 2 x 13 runs of 3 s and the search's: about a minute
def test_the_pooled_search_runs_every_value_on_every_ride(tmp_path, monkeypatch, capsys):
    """Two made rides of the fork far too soft through the command, each run cut to its first 3 s
    (the plumbing of the pooled search, not the advice's numbers): the fork's spring raised and
    searched on, each step simulated on both rides (twice the runs of one ride's search)."""
    real, seen = advise.simulate, []

    def short(bike, overrides, terrain, speed, duration, label, lead_s, profile=None):
        seen.append(label)
        return real(bike, overrides, terrain, speed, min(duration, 3.0), label, lead_s, profile)

    monkeypatch.setattr(advise, "simulate", short)
    bike, (a, b) = _made_rides(tmp_path, (21, 5), 16.0)
    out = tmp_path / "advice"
    with reconstruction_passing():
        assert main(["advise", str(a), str(b), "--bike", str(bike), "--workers", "1", "--out", str(out)]) == 0
    d = json.loads((out / "advice.json").read_text())
    rec = d["recommendation"]
    assert d["verdict"]["answer"] == "change" and rec["key"] == "fork:fork.spring.rate_N_per_mm", d["verdict"]
    assert rec["search"] and rec["setting"]["to"] == rec["search"][-1]["setting"]["to"] > 5.5
    for step in rec["search"]:
        assert seen.count(f"fork spring rate {step['to']:g}") == 2, (step, seen)
    printed = capsys.readouterr().out
    assert printed.index("seed21.SST alone: ") < printed.index("Recommended: raise the fork spring rate from 5 to ")


def test_the_run_counter_shows_on_a_terminal_only(monkeypatch, capsys):
    """The progress bar with its run counter ("run 3/12") on a terminal; nothing when stderr is not one."""
    import sys

    from mtbmj.cli.common import Progress

    step = advise.counter(Progress("advise"), 12)  # stderr captured here: not a terminal
    for _ in range(3):
        step()
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    step = advise.counter(Progress("advise"), 12)
    for _ in range(3):
        step()
    err = capsys.readouterr().err
    assert err.endswith("advise [#######                       ]  25.0% run 3/12") and err.count("\r") == 3, err


def _ride_with(offsets, level, seconds, static):
    """A ride's stand-in for the pooled advice's calibration bookkeeping: its calibration's other reading
    (static sag offsets, None for none), its level offsets (the sag path), its length and a part run whose
    static sags are ``static`` (front, rear)."""
    from types import SimpleNamespace

    cal = SimpleNamespace(split=None if offsets is None else object(), static_sag_offsets=lambda: dict(offsets or {}),
                          level_offsets=lambda: dict(level))
    ride = advise.Advice.__new__(advise.Advice)
    ride.calibration, ride.base = cal, SimpleNamespace(metrics={"duration_s": seconds})
    part = advise.Run("part", {}, {"front": {"static_sag_percent": static[0]}, "rear": {"static_sag_percent": static[1]},
                                   "duration_s": seconds}, {})
    return ride, part


def test_pooled_rides_read_the_other_way_and_levelled_each_by_its_own_calibration():
    """Two rides of 60 s and 120 s: the pooled other reading moves each end's static sag by the rides'
    own offsets weighted by length (front +9 and -3 -> +1; rear -6 and 0 -> -2), none where one ride has no
    other reading; on the sag path each part is levelled by its own ride's offsets (front -10 on a 30 %
    part, 0 on a 20 % one) before they are pooled again (by length: (20 + 40) / 3 = 20), once only."""
    a, pa = _ride_with({"front": 9.0, "rear": -6.0}, {"front": -10.0, "rear": 0.0}, 60.0, (30.0, 28.0))
    b, pb = _ride_with({"front": -3.0, "rear": 0.0}, {"front": 0.0, "rear": 0.0}, 120.0, (20.0, 28.0))
    pooled = advice_pool.PooledAdvice.__new__(advice_pool.PooledAdvice)
    pooled.rides, pooled.calibration = [a, b], a.calibration
    assert pooled.other_offsets() == pytest.approx({"front": 1.0, "rear": -2.0})
    c, _ = _ride_with(None, {"front": 0.0, "rear": 0.0}, 60.0, (20.0, 28.0))
    lone = advice_pool.PooledAdvice.__new__(advice_pool.PooledAdvice)
    lone.rides, lone.calibration = [a, c], a.calibration
    assert lone.other_offsets() is None
    run = advise.Run("pooled", {}, {"front": {"static_sag_percent": 23.3}, "rear": {"static_sag_percent": 28.0}}, {},
                     parts=[pa, pb])
    pooled.levelled(run)
    assert run.metrics["front"]["static_sag_percent"] == pytest.approx((60 * 20.0 + 120 * 20.0) / 180)
    assert pa.metrics["front"]["static_sag_percent"] == pytest.approx(20.0) and run.levelled
    pooled.levelled(run)  # once only
    assert pa.metrics["front"]["static_sag_percent"] == pytest.approx(20.0)
