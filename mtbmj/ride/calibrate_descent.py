"""The sag path's load carried as a mean descent (``mtbmj advise --static-sag-mm F,S --carried-as descent``):
the grade whose steady run the calibration reads as the ride's load.

The calibration (``mtbmj.ride.calibrate``) reads a load carried forward from each end's mean suspension
force at the wheel, and converts it to a descent in closed form: the weight's component along the slope
at the centre of mass, ``m g h sin(theta) / L``. On a real descent at a steady speed the brakes hold the
bike, and their forces at the patches do more than move load: the front brake's pushes the raked fork
into its travel (brake dive: its share along the fork's axis, read as load at the wheel by the fork's
force over sin(head angle)), the rear's acts through the linkage (squat or rise), and the frame pitches
and the rider leans on his arms. Ridden at the closed form's grade, the made ride of a rider 150 mm
forward (85 N, 5.7 deg) had the model's fork at 37 % dynamic sag where the ride's sat at 31 %, and 7
bottom-outs for none.

So the grade is found through the engine that rides it (:func:`grade_for`): the whole bike, with the
calibrated springs and the rider in the file's place, rides a steady descent (``climb`` with a negative
grade) and the level ground at one speed; each end's mean force is read from the run's travels as the
calibration reads a ride's (``mtbmj.ride.calibrate._MeanForce``: the same laws, the same conversion to
the wheel), the level run's reading taken off; the secant on sin(grade) meets the ride's load forward
within ``TOLERANCE_N`` in a few runs. What it shares with the advice's runs: everything of the engine
(that is the point: the runs then carry the ride's load as the ride's balances read it); what it assumes:
the load comes from a steady descent with the brakes holding the speed (not pedalling, not the rider's
place), shared between the wheels by their loads (``controllers.drive.wheel_forces``)."""
from __future__ import annotations

import math

SPEED_M_PER_S = 5.0  # steady: the brakes' forces do not depend on it (no air drag in the model)
AT_M, LENGTH_M, SETTLE_M, READ_M = 3.0, 70.0, 15.0, 40.0  # the grade from AT_M; read SETTLE_M in, over READ_M
TOLERANCE_N = 3.0  # the load forward read within this of the ride's
MAX_RUNS = 4  # descents tried (the level run besides)
MAX_DEG = 20.0  # beyond this a load is no trail's steady descent


def grade_for(read, load_forward_N: float, first_deg: float) -> dict:
    """The mean descent (deg; negative: a climb) whose steady run is read as ``load_forward_N`` carried
    forward, from ``first_deg`` (the closed form's). ``read(grade_percent)`` runs the bike at that grade
    (0: level ground) and returns (the load forward the calibration reads from it, N; the run):
    ``mtbmj.ride.calibrate.descent_for`` gives it. Returns {"descent_deg", "runs", "read_N",
    "level_read_N", "closed_form_deg"}; raises ``RideNotDescribed`` where no grade within ``MAX_DEG``
    reads it or a run crashes."""
    from mtbmj.ride.advice_rules import RideNotDescribed

    level, _ = read(0.0)
    target = load_forward_N
    sine = math.sin(math.radians(first_deg))
    tried = []
    for _ in range(MAX_RUNS):
        if abs(sine) > math.sin(math.radians(MAX_DEG)):
            raise RideNotDescribed(f"the load the ride carried forward ({load_forward_N:.0f} N) reads as a descent "
                                   f"steeper than {MAX_DEG:g} deg: no steady descent carries it")
        grade = -100.0 * math.tan(math.asin(sine))
        got, run = read(grade)
        if run.summary.get("crash"):
            raise RideNotDescribed(f"the steady descent of {math.degrees(math.asin(sine)):.1f} deg that carries the "
                                   f"ride's load: {run.summary['crash']['line']}")
        tried.append((sine, got - level))
        if abs(got - level - target) <= TOLERANCE_N:
            break
        if len(tried) == 1:  # the load read is proportional to sin(grade) to first order
            sine = sine * target / (got - level) if got != level else sine
        else:
            (s0, r0), (s1, r1) = tried[-2], tried[-1]
            sine = s1 + (target - r1) * (s1 - s0) / (r1 - r0) if r1 != r0 else s1
    sine, read = tried[-1]
    return {"descent_deg": math.degrees(math.asin(sine)), "runs": len(tried) + 1, "read_N": read,
            "level_read_N": level, "closed_form_deg": first_deg}


__all__ = ["grade_for"]
