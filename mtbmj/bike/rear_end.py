"""A bike's rear end from its hardpoints, solved with the bike (``mtbmj linkage``): the curves of
``mtbmj.bike.linkage`` with the bike's tyre radius, front axle and centre of mass (``com_height_mm``
when given, else the bike's and rider's at full extension, :func:`com_height_of`), and the CSV,
figure and summary the command writes."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.bike.linkage import MM, Curves, Linkage, circle_path, curves, from_table, path_departure
from mtbmj.errors import ConfigError


def com_height_of(spec, tyre_radius: float) -> float:
    """The bike's and rider's centre of mass over the ground (m) at full extension with the frame
    level: every body at its frame position (the rider at its stance, the wheels at their axles,
    the swingarm halfway along it; ``mtbmj.bike.model.centre_of_mass``), the ground a tyre radius
    below the rear axle."""
    from mtbmj.bike.model import centre_of_mass

    _, (_, z) = centre_of_mass(spec)
    return z - (float(spec.rear_axle[1]) - tyre_radius)




@dataclass
class BikeLinkage:
    """A bike's rear end from its hardpoints, solved (``for_bike``)."""

    name: str
    link: Linkage
    curves: Curves
    pivot: np.ndarray  # where the bike's single pivot turns the axle (the main pivot, or the centre of the circle fitting a four-bar's axle path)
    tyre_radius: float
    stroke: float

    def csv_bytes(self) -> bytes:
        from mtbmj import output

        rows = self.curves.rows()
        columns = {k: np.array([r[k] for r in rows]) for k in rows[0]}
        return output.csv_bytes(columns, f"mtbmj linkage {self.name}: {self.link.kind}, chainring "
                                         f"{self.link.chainring} T, cog {self.link.cog} T, brake on {self.link.brake_on}, "
                                         f"centre of mass {self.curves.com_height / MM:.0f} mm over the ground\n")

    def summary(self) -> dict:
        c = self.curves
        at = lambda arr, w: float(np.interp(w, c.travel, arr))
        sag = 0.3 * c.travel[-1]
        return {"bike": self.name, "kind": self.link.kind, "chainring_teeth": self.link.chainring,
                "cog_teeth": self.link.cog, "brake_on": self.link.brake_on,
                "wheel_travel_mm": float(c.travel[-1] / MM), "shock_stroke_mm": float(self.stroke / MM),
                "leverage_ratio": {"start": float(c.leverage_ratio[0]), "end": float(c.leverage_ratio[-1]),
                                   "progression_percent": float(100.0 * (c.leverage_ratio[0] - c.leverage_ratio[-1])
                                                                / c.leverage_ratio[0])},
                "at_30_percent_travel": {"anti_squat_percent": at(c.anti_squat, sag),
                                         "anti_rise_percent": at(c.anti_rise, sag),
                                         "pedal_kickback_deg": at(c.kickback_deg, sag)},
                "com_height_mm": float(c.com_height / MM), "tyre_radius_mm": float(self.tyre_radius / MM),
                "bike_pivot_mm": (self.pivot / MM).tolist(),
                "bike_axle_path_departure_mm": float(path_departure(self.link, c, self.pivot) / MM)}

    def line(self) -> str:
        s = self.summary()
        a = s["at_30_percent_travel"]
        lr = s["leverage_ratio"]
        return (f"linkage {self.name} ({self.link.kind}): {s['wheel_travel_mm']:.1f} mm of wheel travel on "
                f"{s['shock_stroke_mm']:g} mm of stroke, leverage ratio {lr['start']:.2f} to {lr['end']:.2f} "
                f"({lr['progression_percent']:.1f} % progressive); at 30 % travel anti-squat {a['anti_squat_percent']:.0f} % "
                f"({self.link.chainring}x{self.link.cog} T), anti-rise {a['anti_rise_percent']:.0f} %, pedal kickback "
                f"{a['pedal_kickback_deg']:.1f} deg")

    def figure(self):
        """Leverage ratio, axle path (with the bike's single-pivot circle), anti-squat and anti-rise,
        and pedal kickback against the rear wheel travel."""
        from matplotlib.figure import Figure

        c = self.curves
        w = c.travel / MM
        fig = Figure(figsize=(11, 8), layout="constrained")
        ax = fig.subplots(2, 2)
        ax[0, 0].plot(w, c.leverage_ratio, color="C0")
        ax[0, 0].set(xlabel="rear wheel travel (mm)", ylabel="leverage ratio (wheel / shock)",
                     title="Leverage ratio")
        x, z = circle_path(self.link, c, self.pivot)
        ax[0, 1].plot(c.axle_x / MM, c.axle_z / MM, color="C0", label="linkage")
        title = "Rear axle path"
        if self.link.kind in ("horst_link", "short_link"):
            off = path_departure(self.link, c, self.pivot) / MM
            ax[0, 1].plot(x / MM, z / MM, color="C3", linestyle="--",
                          label=f"the bike's circle ({off:.3f} mm at most from it)")
            ax[0, 1].legend(loc="best", fontsize=8)
            title += "\n(dashed: as the bike runs it, on the circle\nthat best fits the linkage's path)"
        ax[0, 1].set(xlabel="axle x in the frame (mm)", ylabel="axle z in the frame (mm)", title=title)
        ax[0, 1].set_aspect("equal", adjustable="datalim")
        ax[1, 0].plot(w, c.anti_squat, color="C2", label=f"anti-squat ({self.link.chainring}x{self.link.cog} T)")
        ax[1, 0].plot(w, c.anti_rise, color="C1", label=f"anti-rise (brake on the {self.link.brake_on.replace('_', ' ')})")
        ax[1, 0].axhline(100.0, color="0.5", linewidth=0.8)
        ax[1, 0].set(xlabel="rear wheel travel (mm)", ylabel="% of the centre of mass height",
                     title=f"Anti-squat and anti-rise (centre of mass {c.com_height / MM:.0f} mm)")
        ax[1, 0].legend(loc="best")
        ax[1, 1].plot(w, c.kickback_deg, color="C4")
        ax[1, 1].set(xlabel="rear wheel travel (mm)", ylabel="crank rotation (deg, backwards +)",
                     title="Pedal kickback (rear wheel held)")
        for a in ax.flat:
            if a is not ax[0, 1]:
                a.set_xlim(0.0, float(w[-1]))
            a.grid(alpha=0.3)
        fig.suptitle(f"{self.name}: {self.link.kind.replace('_', ' ')}")
        return fig

    def write(self, out_dir) -> list:
        import json

        from mtbmj import output
        from mtbmj.readout import quicklook  # the one figure writer: a "$" in a name drawn as written

        return output.write_atomically(out_dir, {"linkage.csv": self.csv_bytes(),
                                                 "linkage.png": quicklook.png(self.figure(), dpi=110),
                                                 "summary.json": (json.dumps(self.summary(), indent=2) + "\n").encode()})


def for_bike(ref: str, overrides=None, chainring: int | None = None, cog: int | None = None,
             com_height_mm: float | None = None) -> BikeLinkage:
    """The rear end of the bike ``ref`` (preset, file or ``mtbmj.bike.spec.ResolvedBike``: a file is
    read once) from its ``[linkage]``, solved over its travel, with the bike's tyre radius, front
    axle and centre of mass for anti-squat and anti-rise."""
    from mtbmj.bike import keys as keys_mod
    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod

    read, source = (ref.read, ref.source) if isinstance(ref, spec_mod.ResolvedBike) else spec_mod.read_table(str(ref))
    table = spec_mod.overridden(read, overrides)
    if "linkage" not in table:
        raise ConfigError(f"{ref}: has no [linkage] (the rear end's hardpoints); see docs/configuration.md")
    metres = keys_mod.metres_for_millimetres(table)  # before the points are checked in the wrong unit
    if metres is not None:
        raise ConfigError(metres)
    part = dict(table["linkage"])
    for key, value in (("chainring_teeth", chainring), ("cog_teeth", cog), ("com_height_mm", com_height_mm)):
        if value is not None:
            part[key] = value
    link = from_table(part)
    spec = spec_mod.derive(source, read, overrides).spec  # the file read once (mtbmj.bike.spec.resolve's steps)
    tyre = bike_run.setups(spec)[0].tire_radius
    height = part.get("com_height_mm")
    if height is not None:
        if not isinstance(height, (int, float)) or isinstance(height, bool) or not 300.0 <= height <= 2000.0:
            raise ConfigError(f"linkage.com_height_mm: must be within 300-2000 mm over the ground, got {height!r}")
        com = float(height) * MM
    else:
        com = com_height_of(spec, tyre)
    c = curves(link, spec.shock_stroke, tyre, float(spec.front_axle[0]), com)
    return BikeLinkage(source, link, c, np.asarray(spec.pivot, float), tyre, spec.shock_stroke)


__all__ = ["BikeLinkage", "for_bike", "com_height_of"]
