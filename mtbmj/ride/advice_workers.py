"""The processes ``mtbmj advise`` runs its bike runs in, started before the ride is prepared.

The ride's calibration and reconstruction (``mtbmj.ride.advise.prepare``) run in the calling process,
one core, for seconds; every bike run after them runs in a process of the pool. A process's first
bike run also imports the bike's run path and loads its compiled code (numba's cache: the bike's
callback, the laws' kernels), about a second. So the pool is started first (:func:`started`) and
each process does that while the ride is prepared (:func:`warm`: a short run of the bike on flat
ground, thrown away), on the core the preparation leaves idle. Nothing a run computes depends on
it: a warmed process steps the same arithmetic from the same state (``tests/test_advise_speed.py``
compares the runs)."""
from __future__ import annotations

WARM_S = 0.05  # s of the bike on flat ground that :func:`warm` runs (100 steps of 0.5 ms)
WARMED: list = []  # the bikes :func:`warm` ran in this process (what the tests read)


def warm(bike) -> None:
    """Load what a bike run of ``bike`` needs in this process (each pool process runs it as it starts): a
    :data:`WARM_S` run on flat ground, its result dropped. Whatever goes wrong is left to the real runs
    to meet and report (a process whose start raised would break the pool)."""
    import warnings

    try:
        from mtbmj.bike import run as bike_run

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the real runs warn where there is something to say
            bike_run.run_bike(bike, "flat", 4.0, duration=WARM_S, drive="rider")
        WARMED.append(bike if isinstance(bike, str) else getattr(bike, "name", "bike"))
    except Exception:  # noqa: BLE001 - the real runs raise it again, where it is reported
        pass


def started(stack, workers: int, bike):
    """A pool of ``workers`` processes (``mtbmj.workers.process_pool``, entered on ``stack``, a
    ``contextlib.ExitStack``), started now, each warming for ``bike`` (:func:`warm`) while the caller
    goes on."""
    from mtbmj.workers import process_pool

    pool = stack.enter_context(process_pool(workers, warm, (bike,)))
    pool.submit(int)  # the processes start at the first task (all of them where they are forked)
    return pool


__all__ = ["WARMED", "WARM_S", "started", "warm"]
