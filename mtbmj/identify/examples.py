"""The shipped example records of every fit kind (all SYNTHETIC, marked so in their headers), and
the call that makes them again.

``mtbmj fit KIND example`` reads these files from ``mtbmj/data/``:

- spring: ``spring_example.csv``, a dyno stroke of the reference progressive spring with top-out
  and preload (``dyno_synthetic.spring_record``);
- damper: ``damper_example.csv``, the usual dyno output: one peak force per test speed and
  direction of the bilinear damper with Coulomb friction (``dyno_synthetic.damper_record`` then
  ``peak_points``);
- tire: ``tire_drop_example.csv`` (a mass dropped on the tire; the mass is in its header) and
  ``tire_ramp_example.csv`` (a static press) from ``tire_synthetic``;
- drop: ``sled_example.csv``, a sled record on a logger clock that starts before the release
  (made by ``benchmarks/make_sled_example.py``: S12 with another impact tire rate and preload, the
  keys a drop fit frees by default, on the ODE reference).

Make the first three again with ``python -c "from mtbmj.identify.examples import write_examples;
write_examples('DIR')"`` (deterministic: the shipped files are what it writes).
"""
from __future__ import annotations

from importlib import resources
from pathlib import Path

from mtbmj.errors import MtbmjError

FILES = {
    "spring": ("spring_example.csv",),
    "damper": ("damper_example.csv",),
    "tire": ("tire_drop_example.csv", "tire_ramp_example.csv"),
    "drop": ("sled_example.csv",),
}
GENERATED = ("spring", "damper", "tire")  # written by ``write_examples``; the drop example by the benchmark script


def data_dir() -> Path:
    return Path(str(resources.files("mtbmj") / "data"))


def example_paths(kind: str) -> list[Path]:
    """The shipped example record(s) of a fit kind."""
    if kind not in FILES:
        raise MtbmjError(f"fit: no example for kind {kind!r} (one of {', '.join(FILES)})")
    paths = [data_dir() / name for name in FILES[kind]]
    missing = [p for p in paths if not p.exists()]
    if missing:
        raise MtbmjError(f"{missing[0]}: the shipped example is missing from the installation")
    return paths


def write_examples(out_dir: str | Path | None = None) -> list[Path]:
    """Write the generated example records (spring, damper, tire) to ``out_dir`` (default: the
    package's data folder); deterministic seeds, so the shipped files are what this writes."""
    from mtbmj.identify import dyno_synthetic as dyno, tire_synthetic as tires

    out = Path(out_dir) if out_dir is not None else data_dir()
    out.mkdir(parents=True, exist_ok=True)
    written = [dyno.write_csv(out / "spring_example.csv", dyno.spring_record(sample_Hz=200.0)),
               dyno.write_csv(out / "damper_example.csv", dyno.peak_points(dyno.damper_record(dyno.DAMPER_BILINEAR)))]
    for name, body in (("tire_drop_example.csv", tires.tire_drop_record(duration_s=2.0)),
                       ("tire_ramp_example.csv", tires.tire_ramp_record())):
        (out / name).write_text(body)
        written.append(out / name)
    return written


__all__ = ["FILES", "example_paths", "write_examples"]
