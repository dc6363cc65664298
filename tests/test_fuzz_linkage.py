"""Fuzzing the rear end from hardpoints (``mtbmj linkage``) and the leverage CSV (``[leverage] csv``
read by ``mtbmj bike``) with cases generated here: random single pivots (on 45-65 mm shocks),
linkage-driven single pivots, Horst links and short links (some of whose lower links turn back inside
the travel), degenerate points (coincident, zero-length members, collinear four-bars), and CSVs
valid and broken in every careless way. For each case the command either answers, and its answer
agrees with the mechanism solved here another way (the loop-closure equations and the axle's rise
solved together for the links' turns by Newton's method, continued along the wheel travel: no driving
link at all; the leverage ratio a finite difference of that path) or with the CSV's curve integrated
here, or it refuses: one line, exit status 2, nothing written, and a refusal that the mechanism
solved here contradicts (it does reach the stroke, its points are not degenerate) fails."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mtbmj.cli import main

MM = 1e-3
TRAIL_STROKE = 0.050  # the trail preset's shock


def rot(v, a):
    return np.array([math.cos(a) * v[0] - math.sin(a) * v[1], math.sin(a) * v[0] + math.cos(a) * v[1]])


# each four-bar's loop (frame pivot A, joint B on the input link, joint C on the output link, frame
# pivot D), the link carrying the rear axle, and the shock's eye (on the output link in every layout)
LOOPS = {"linkage_driven_single_pivot": (("main_pivot", "swingarm_link", "rocker_link", "rocker_pivot"), "input",
                                         "shock_rocker"),
         "horst_link": (("main_pivot", "horst_pivot", "seatstay_rocker", "rocker_pivot"), "coupler", "shock_rocker"),
         "short_link": (("lower_pivot", "lower_link", "upper_link", "upper_pivot"), "coupler", "shock_upper_link")}
EYE = {"single_pivot": "shock_swingarm", **{k: v[2] for k, v in LOOPS.items()}}


class Mechanism:
    """The rear end solved for its links' turns at a given wheel travel: a single pivot's swingarm
    turn t with the axle's rise; a four-bar's turns (u1, u2, u3) of input, coupler and output from
    the loop's two closure equations and the axle's rise (Newton's method), continued from the last
    solution."""

    def __init__(self, kind, pts):
        self.kind, self.p = kind, pts
        self.u = np.zeros(1 if kind == "single_pivot" else 3)
        eye = pts[EYE[kind]]
        self.length0 = float(np.hypot(*(eye - pts["shock_frame"])))

    def parts(self, u):
        p = self.p
        if self.kind == "single_pivot":
            A = p["main_pivot"]
            return None, A + rot(p["rear_axle"] - A, u[0]), A + rot(p["shock_swingarm"] - A, u[0])
        (a, b, c, d), on, eye = LOOPS[self.kind]
        A, B0, C0, D = p[a], p[b], p[c], p[d]
        B = A + rot(B0 - A, u[0])
        loop = B + rot(C0 - B0, u[1]) - (D + rot(C0 - D, u[2]))
        axle = A + rot(p["rear_axle"] - A, u[0]) if on == "input" else B + rot(p["rear_axle"] - B0, u[1])
        return loop, axle, D + rot(p[eye] - D, u[2])

    def residual(self, u, w):
        loop, axle, _ = self.parts(u)
        rise = [axle[1] - self.p["rear_axle"][1] - w]
        return rise if loop is None else [loop[0], loop[1], rise[0]]

    def jacobian(self, u, w):
        """d residual / d u, written out (d/du of rot(v, u) is rot(v turned a quarter, u))."""
        p = self.p
        d = lambda v, a: rot(np.array([-v[1], v[0]]), a)  # noqa: E731
        if self.kind == "single_pivot":
            return [[d(p["rear_axle"] - p["main_pivot"], u[0])[1]]]
        (a, b, c, dd), on, _ = LOOPS[self.kind]
        A, B0, C0, D = p[a], p[b], p[c], p[dd]
        db = d(B0 - A, u[0])
        loop = np.column_stack([db, d(C0 - B0, u[1]), -d(C0 - D, u[2])])
        rise = [d(p["rear_axle"] - A, u[0])[1], 0.0, 0.0] if on == "input" else \
            [db[1], d(p["rear_axle"] - B0, u[1])[1], 0.0]
        return np.vstack([loop, rise])

    def at(self, w):
        """(axle, stroke) at wheel travel ``w`` (m), continued from the last solution; None where the
        root finder finds none near it (the axle cannot rise that far, or the loop would jump)."""
        u = self.u.copy()
        for _ in range(30):  # Newton's method with the Jacobian written out
            r = np.asarray(self.residual(u, w), float)
            if np.max(np.abs(r)) < 1e-13:
                break
            try:
                u = u - np.linalg.solve(np.asarray(self.jacobian(u, w), float), r)
            except np.linalg.LinAlgError:
                return None
        if np.max(np.abs(self.residual(u, w))) > 1e-12 or np.max(np.abs(u - self.u)) > 0.05:
            return None
        self.u = u
        _, axle, eye = self.parts(u)
        return axle, self.length0 - float(np.hypot(*(eye - self.p["shock_frame"])))

    def walk(self, limit, step=0.5e-3):
        """March the wheel up in ``step``s: (travels, strokes, axles) until the stroke reaches
        ``limit`` or the mechanism stops (the list then ends short of it)."""
        self.u[:] = 0.0
        ws, ss, axles = [0.0], [0.0], [self.p["rear_axle"]]
        while ss[-1] < limit and ws[-1] < 0.4:
            here = self.at(ws[-1] + step)
            if here is None or here[1] <= ss[-1]:
                break
            ws.append(ws[-1] + step)
            ss.append(here[1])
            axles.append(here[0])
        return np.array(ws), np.array(ss), np.array(axles)


def P(x, z):
    return np.array([x, z], float) * MM


def random_points(rng, kind):
    u = rng.uniform
    if kind == "single_pivot":
        return dict(main_pivot=P(u(-60, 40), u(30, 250)), rear_axle=P(u(-470, -420), u(5, 40)),
                    shock_swingarm=P(u(-250, -50), u(100, 300)), shock_frame=P(u(50, 250), u(150, 450)))
    if kind == "short_link":
        return dict(lower_pivot=P(u(-20, 60), u(20, 100)), lower_link=P(u(-80, 0), u(0, 80)),
                    upper_pivot=P(u(-100, -20), u(220, 300)), upper_link=P(u(-180, -100), u(240, 320)),
                    rear_axle=P(u(-460, -420), u(10, 40)), shock_upper_link=P(u(-160, -60), u(300, 400)),
                    shock_frame=P(u(100, 250), u(100, 250)))
    if kind == "horst_link":
        return dict(main_pivot=P(u(-60, 0), u(40, 100)), horst_pivot=P(u(-440, -380), u(0, 40)),
                    rear_axle=P(u(-460, -430), u(10, 40)), rocker_pivot=P(u(-80, -20), u(340, 420)),
                    seatstay_rocker=P(u(-160, -100), u(360, 440)), shock_rocker=P(u(-60, 20), u(400, 460)),
                    shock_frame=P(u(120, 220), u(150, 230)))
    return dict(main_pivot=P(u(-60, 0), u(40, 100)), rear_axle=P(u(-460, -420), u(10, 40)),
                swingarm_link=P(u(-160, -80), u(90, 150)), rocker_pivot=P(u(-60, 20), u(300, 360)),
                rocker_link=P(u(-140, -80), u(300, 360)), shock_rocker=P(u(40, 120), u(380, 460)),
                shock_frame=P(u(180, 260), u(150, 210)))


def degenerate(rng):
    """(kind, points, the keys the refusal must name) with one degeneracy made here."""
    kind = str(rng.choice(["single_pivot", "short_link", "horst_link", "linkage_driven_single_pivot"]))
    pts = random_points(rng, kind)
    how = int(rng.integers(4))
    if kind == "single_pivot" or how == 0:  # a member of no length: the shock, the swingarm to its axle
        pairs = [(EYE[kind], "shock_frame")]
        if kind in ("single_pivot", "linkage_driven_single_pivot"):
            pairs.append(("main_pivot", "rear_axle"))
        one, two = pairs[int(rng.integers(len(pairs)))]
        pts[two] = pts[one] + P(*rng.uniform(-0.3, 0.3, 2))
        return kind, pts, (one, two)
    names = LOOPS[kind][0]
    if how == 3:  # the four loop points on one line
        start, d = P(rng.uniform(-40, 40), rng.uniform(20, 100)), rng.uniform(-1, 1, 2)
        d /= np.hypot(*d)
        for i, n in enumerate(names):
            pts[n] = start + d * (0.05 + 0.06 * i + rng.uniform(0, 0.02))
        return kind, pts, names
    i, j = sorted(rng.choice(4, 2, replace=False))  # two of the loop's points on one another
    pts[names[j]] = pts[names[i]] + P(*rng.uniform(-0.3, 0.3, 2))
    return kind, pts, (names[i], names[j])


def bike_file(tmp_path, name, kind, pts, stroke_mm):
    points = "\n".join(f"{k}_mm = [{v[0] / MM:.4f}, {v[1] / MM:.4f}]" for k, v in pts.items())
    path = tmp_path / f"{name}.toml"
    path.write_text(f'base = "trail"\n[shock]\nstroke_mm = {stroke_mm}\n[shock.set]\n"fork.travel_mm" = {stroke_mm}\n'
                    f'[linkage]\nkind = "{kind}"\n{points}\n')
    return path


def read_csv(path):
    lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    head = lines[0].split(",")
    rows = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return {k: rows[:, i] for i, k in enumerate(head)}


def outcome(capsys, argv, out):
    """(exit status, the error line or None) of ``argv``, checking the house's rules for a refusal."""
    code = main(argv + ["--out", str(out)])
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    errors = [ln for ln in err.splitlines() if ln.strip()]
    if code == 0:
        return 0, None
    assert code == 2, err
    assert len(errors) == 1 and errors[0].startswith("mtbmj: error: "), err  # one line, nothing before it
    assert not out.exists()  # nothing written
    return 2, errors[0]


def test_fuzzed_linkages_answer_as_the_mechanism_solved_here_or_refuse_in_one_line(tmp_path, capsys):
    rng = np.random.default_rng(20240649)
    kinds = ["single_pivot"] * 6 + ["short_link"] * 6 + ["horst_link"] * 3 + ["linkage_driven_single_pivot"] * 3
    answered, refused_solved = 0, 0
    for n, kind in enumerate(kinds):
        pts = {k: np.round(v / MM, 4) * MM for k, v in random_points(rng, kind).items()}  # as written
        stroke_mm = float(rng.choice([45.0, 50.0, 55.0, 65.0]))
        bike = bike_file(tmp_path, f"b{n}", kind, pts, stroke_mm)
        out = tmp_path / f"out{n}"
        code, line = outcome(capsys, ["linkage", str(bike)], out)
        mech = Mechanism(kind, pts)
        limit = stroke_mm * MM
        if code == 2:
            # the leverage table solved at the shock's own stroke never fails that stroke's check
            assert "shorter than the leverage curve needs" not in line, line
            # a refusal the mechanism solved here contradicts: it reaches the stroke, the shock
            # shortening and the axle rising all the way
            if "linkage: " in line and ("never reaches" in line or "lengthens" in line):
                ws, ss, _ = mech.walk(limit)
                assert ss[-1] < limit - 0.2 * MM, (kind, pts, line, ss[-1])
                refused_solved += 1
            continue
        answered += 1
        c = read_csv(out / "linkage.csv")
        w = c["wheel_travel_mm"] * MM
        assert c["shock_stroke_mm"][-1] == pytest.approx(stroke_mm, abs=1e-6)
        mech.u[:] = 0.0
        for i in range(0, w.size, 10):
            # continue the solution here up to this row (steps of at most 1 mm), then differentiate
            prev = w[i - 10] if i else 0.0
            for x in np.linspace(prev, w[i], max(2, int((w[i] - prev) / MM) + 1))[1:]:
                assert mech.at(x) is not None, (kind, pts, x)
            axle, s = mech.at(w[i])
            assert abs(axle[0] - c["axle_x_mm"][i] * MM) < 1e-6  # 1 um: the same path
            assert s == pytest.approx(c["shock_stroke_mm"][i] * MM, abs=1e-8)
            # the leverage ratio dw/ds by a finite difference of the path solved here (central; at full
            # extension one-sided, second order): by virtual work, the shock's force F through ds does
            # the wheel's work F / LR dw
            h = 1e-5
            keep = mech.u.copy()
            at = []
            for x in ((w[i] - h, w[i] + h) if i else (h, 2 * h)):
                here = mech.at(x)
                mech.u[:] = keep
                at.append(None if here is None else here[1])
            if None in at:
                continue  # at an edge of the mechanism's range: no difference across it
            ds_dw = (at[1] - at[0]) / (2 * h) if i else (4 * at[0] - at[1]) / (2 * h)
            assert c["leverage_ratio"][i] == pytest.approx(1.0 / ds_dw, rel=1e-4), (kind, i)
        assert w[-1] > 0.0
    # the fuzz exercised both sides
    assert answered >= 5 and answered + refused_solved >= 10, (answered, refused_solved)


def test_fuzzed_degenerate_points_are_refused_naming_them(tmp_path, capsys):
    rng = np.random.default_rng(49)
    for n in range(12):
        kind, pts, keys = degenerate(rng)
        bike = bike_file(tmp_path, f"d{n}", kind, pts, 50.0)
        out = tmp_path / f"out{n}"
        code, line = outcome(capsys, ["linkage", str(bike)], out)
        assert code == 2, (kind, keys)
        assert all(f"linkage.{k}_mm" in line for k in keys), (line, keys)


# ---- leverage CSVs ----------------------------------------------------------------------------

def stroke_of(w_tab, r_tab, w):
    """The stroke (m) at wheel travel ``w`` (m) of the curve linear between the table's points
    (mm, -), the end ratios held beyond it: integral of dw / LR by Simpson's rule on 400 pieces a
    segment (not the package's closed form)."""
    if w <= 0.0:
        return w / r_tab[0]
    total, edges = 0.0, list(w_tab)
    if w > edges[-1]:
        total += (w - edges[-1] * MM) / r_tab[-1]
    for (a, ra), (b, rb) in zip(zip(edges, r_tab), zip(edges[1:], r_tab[1:])):
        if w * 1e3 <= a:
            break
        top = min(b, w / MM)
        x = np.linspace(a, top, 401)
        f = 1.0 / (ra + (rb - ra) * (x - a) / (b - a))
        total += (top - a) * MM / 1200.0 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    return total


def valid_curve(rng):
    """Wheel travels (mm, from 0 to 120 in uneven steps) and ratios (a random smooth curve scaled
    so that it needs 49.3-50 mm of the trail bike's 50 mm stroke)."""
    w = np.concatenate([[0.0], np.sort(rng.uniform(1.0, 119.0, int(rng.integers(3, 12)))), [120.0]])
    w = np.unique(np.round(w, 3))
    shape = 2.6 + rng.uniform(-0.4, 0.4) * (w / 120.0) + rng.uniform(-0.2, 0.2) * (w / 120.0) ** 2
    need = stroke_of(w, shape, 0.120)
    scale = need / (TRAIL_STROKE * (1.0 - rng.uniform(0.0, 0.014)))
    return w, np.round(shape * scale, 6)


def csv_text(rng, w, r):
    sep = str(rng.choice([",", ";", "\t"]))
    head = str(rng.choice(["", "Travel (mm);Leverage ratio\n", "wheel_travel_mm,ratio\n\n"]))
    return head + "".join(f"{a:g}{sep}{b:.6f}\n" for a, b in zip(w, r))


def broken(rng, w, r):
    """A careless CSV: (text or bytes, what the one line must contain)."""
    rows = [f"{a:g},{b:.6f}" for a, b in zip(w, r)]
    k = int(rng.integers(1, len(rows)))
    how = int(rng.integers(11))
    if how == 0:
        rows[k] = rows[k].split(",")[0] + ",abc"
        return "\n".join(rows), f"line {k + 1}: not two numbers"
    if how == 1:
        rows[k] += ",7"
        return "\n".join(rows), f"line {k + 1}: expected wheel travel and leverage ratio"
    if how == 2:
        rows[k] = rows[k].split(",")[0] + "," + str(rng.choice(["nan", "inf", "1e400"]))
        return "\n".join(rows), f"line {k + 1}: expected wheel travel and leverage ratio"
    if how == 3:
        rows[k] = rows[k].split(",")[0] + "," + str(rng.choice(["0", "-2.5"]))
        return "\n".join(rows), "ratio: every leverage ratio must be > 0"
    if how == 4:
        rows[k], rows[k - 1] = rows[k - 1], rows[k]
        return "\n".join(rows), "must start at 0 mm" if k == 1 else "wheel_travel_mm: must increase strictly"
    if how == 5:
        return rows[0] + "\n", "holds 1 row(s)"
    if how == 6:
        return "", "holds 0 row(s)"
    if how == 7:
        return bytes(rng.integers(0, 256, 300, dtype=np.uint8)) + b"\xff\x00", "not a text file"
    if how == 8:
        return "\n".join(f"{a + 3:g},{b:.6f}" for a, b in zip(w, r)), "wheel_travel_mm: must start at 0 mm"
    if how == 9:  # a curve needing 2 % more than the shock's stroke
        return "\n".join(f"{a:g},{b / 1.02:.6f}" for a, b in zip(w, r)), "shock.stroke_mm: 50 mm is shorter"
    return "Travel;Ratio\n" + "\n".join(rows[:1] + ["oops"] + rows[1:]), "line 3: not two numbers"


def test_fuzzed_leverage_csvs_run_with_their_curve_or_refuse_in_one_line(tmp_path, capsys):
    rng = np.random.default_rng(4949)
    ran = 0
    for n in range(22):
        w, r = valid_curve(rng)
        good = n % 5 == 0  # a few whole runs (each a second or two); the rest broken
        content, said = (csv_text(rng, w, r), None) if good else broken(rng, w, r)
        csv = tmp_path / f"lr{n}.csv"
        if isinstance(content, bytes):
            csv.write_bytes(content)
        else:
            csv.write_text(content)
        bike = tmp_path / f"c{n}.toml"
        bike.write_text(f'base = "trail"\n[leverage]\ncsv = "{csv.name}"\n')
        out = tmp_path / f"cout{n}"
        code, line = outcome(capsys, ["bike", str(bike), "flat", "--speed", "4", "--duration", "0.05"], out)
        if not good:
            assert code == 2 and said in line, (content, line, said)
            continue
        assert code == 0, line
        ran += 1
        # the run's shock stroke at its rear wheel travel: the CSV's curve integrated here
        ts = read_csv(out / "timeseries.csv")
        for i in range(0, ts["time_s"].size, max(1, ts["time_s"].size // 5)):
            travel = ts["rear_travel_mm"][i] * MM
            assert ts["stroke_mm"][i] * MM == pytest.approx(stroke_of(w, r, travel), abs=2e-6), i
        assert np.ptp(ts["rear_travel_mm"]) >= 0.0 and ts["rear_travel_mm"].max() > 5.0  # it sat in its travel
    assert ran >= 4
