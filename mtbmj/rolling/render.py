"""Headless video of a run: ``mujoco.Renderer`` on EGL or OSMesa, frames written as MP4 or GIF.

A drop is replayed, not re-simulated, when a run directory holds ``timeseries_raw.csv``: the
sled and fork positions set ``qpos`` frame by frame (positions interpolated to the frame times;
the free fall from the drop height before tire touch is prepended). A preset or TOML file is run
on the MuJoCo engine first. A rolling run directory (``manifest.json`` with ``"kind": "roll"``
or a ``"scenario"``) is re-simulated, deterministically, through
``mtbmj.rolling.frontend.roll_trajectory(scenario, speed, config=..., head_angle_deg=..., duration=..., fps=...)
-> (model, times, qpos)`` when that module is present; the scene's camera "side" is used if it has one.

GL backend: MuJoCo picks its OpenGL context class from ``MUJOCO_GL`` when ``mujoco`` is first
imported, and PyOpenGL binds to one platform (``PYOPENGL_PLATFORM``) for the life of the
process. ``gl_backend`` therefore honours ``MUJOCO_GL=egl|osmesa`` (or an already bound
PyOpenGL platform) when set; otherwise it probes EGL in a short subprocess and falls back to
OSMesa, sets both variables for this process and hands the chosen context class to
``mujoco.Renderer`` (Debian: ``libegl1 libegl-mesa0 libgl1-mesa-dri`` for EGL, ``libosmesa6``
for OSMesa).
"""
from __future__ import annotations

import importlib
import json
import math
import os
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mtbmj.errors import MtbmjError
from mtbmj.output import check_file_target, staged_file
from mtbmj.textfile import run_file_text

FORMATS = (".mp4", ".gif")
BACKENDS = ("egl", "osmesa")
_PROBE = ("import os, sys; os.environ['MUJOCO_GL'] = sys.argv[1]; import importlib; "
          "c = importlib.import_module('mujoco.' + sys.argv[1]).GLContext(16, 16); c.make_current(); c.free()")
_chosen: str | None = None


class RenderError(MtbmjError):
    """A video cannot be made: bad output name or size, no GL backend, an unreadable run."""


def _probe(name: str) -> str | None:
    """None when a ``name`` GL context can be created (in a subprocess), else the reason."""
    env = dict(os.environ, MUJOCO_GL=name)
    env.pop("PYOPENGL_PLATFORM", None)
    try:
        done = subprocess.run([sys.executable, "-c", _PROBE, name], env=env, capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return str(exc)
    if done.returncode == 0:
        return None
    lines = [line for line in done.stderr.strip().splitlines() if line.strip()]
    return lines[-1] if lines else f"exit status {done.returncode}"


def gl_backend() -> str:
    """The headless GL backend this process renders with: "egl" or "osmesa" (see module doc)."""
    global _chosen
    if _chosen is not None:
        return _chosen
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    bound = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower() if "OpenGL" in sys.modules else ""
    if requested in BACKENDS:
        candidates = [requested]
    elif requested not in ("", "glfw", "enable", "enabled", "on", "true", "1"):
        raise RenderError(f"MUJOCO_GL={requested}: no headless rendering (use egl or osmesa)")
    elif bound in BACKENDS:
        candidates = [bound]
    else:
        candidates = list(BACKENDS)
    if bound and bound not in candidates:
        raise RenderError(f"MUJOCO_GL={requested}: OpenGL is already bound to {bound} in this process")
    reasons = []
    for name in candidates:
        if len(candidates) > 1:
            why = _probe(name)
            if why is not None:
                reasons.append(f"{name}: {why}")
                continue
        os.environ["MUJOCO_GL"] = name
        try:
            importlib.import_module(f"mujoco.{name}")
        except Exception as exc:  # noqa: BLE001 - any import failure means this backend is unusable
            reasons.append(f"{name}: {exc}")
            continue
        _chosen = name
        return name
    raise RenderError("no headless GL backend (" + "; ".join(reasons) + "); install libegl1 libegl-mesa0 "
                      "libgl1-mesa-dri (EGL) or libosmesa6 (OSMesa)")


@contextmanager
def _context_class(name: str):
    """Let ``mujoco.Renderer`` create a ``name`` context whatever MUJOCO_GL was at import time."""
    from mujoco.rendering.classic import gl_context

    chosen = importlib.import_module(f"mujoco.{name}").GLContext
    missing = object()
    previous = getattr(gl_context, "GLContext", missing)
    gl_context.GLContext = chosen
    try:
        yield
    finally:
        if previous is missing:
            del gl_context.GLContext
        else:
            gl_context.GLContext = previous


@dataclass
class Trajectory:
    """What to show: a compiled model, frame times (s) and one qpos row per frame."""

    model: object  # mujoco.MjModel
    times: np.ndarray
    qpos: np.ndarray
    label: str
    track_body: int | None = None  # follow this body horizontally (rolling runs)
    touch_s: float = 0.0  # the time the caption counts from


def _read_columns(path: Path, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    try:
        lines = [line for line in run_file_text(path, RenderError, "record").splitlines() if line.strip() and not line.startswith("#")]
        header = [n.strip() for n in lines[0].split(",")]
        table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    except (OSError, ValueError, IndexError) as exc:
        raise RenderError(f"{path}: cannot read ({exc})") from None
    missing = [n for n in names if n not in header]
    if missing or table.shape[1] != len(header):
        raise RenderError(f"{path}: needs columns {', '.join(names)}" + (f" (missing {', '.join(missing)})" if missing else ""))
    return {n: table[:, header.index(n)] for n in names}


def _run_name(run_dir: Path) -> str | None:
    try:
        return str(json.loads(run_file_text(run_dir / "manifest.json", RenderError, "config"))["name"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def drop_trajectory(source: str | Path, fps: float = 30.0, duration: float | None = None,
                    include_fall: bool = True) -> Trajectory:
    """Frames of a drop from a run directory (replayed) or a preset/TOML file (run on MuJoCo)."""
    from mtbmj import compose, config as config_mod
    from mtbmj.drop import engine_mujoco
    from mtbmj.drop import scene as scene_mod

    path = Path(source)
    if path.is_dir() and str(source).strip():  # Path("") is the current folder: config.load names the empty name
        config_path = path / "config.toml"
        if not config_path.is_file():
            raise RenderError(f"{path}: not a run directory (no config.toml)")
        cfg = config_mod.load(str(config_path))
        setup = compose.setup(cfg)
        csv = path / "timeseries_raw.csv"
        if not csv.is_file():
            csv = path / "timeseries.csv"
        if not csv.is_file():
            raise RenderError(f"{path}: no timeseries_raw.csv or timeseries.csv")
        cols = _read_columns(csv, ("time_s", "sled_mm", "fork_mm"))
        t, sled, fork = cols["time_s"], cols["sled_mm"] * 1e-3, cols["fork_mm"] * 1e-3
        label = f"{_run_name(path) or cfg.name} ({path.name})"
    else:
        cfg = config_mod.load(str(source))
        setup = compose.setup(cfg)
        trace = engine_mujoco.run(setup, duration)
        t, sled, fork = trace.time, trace.sled, trace.fork
        label = cfg.name
    sc = scene_mod.build(setup)
    end = float(t[-1]) if duration is None else min(float(t[-1]), float(duration))
    fall = math.sqrt(2.0 * setup.drop_height / setup.gravity) if include_fall and setup.drop_height > 0 else 0.0
    times = np.arange(-fall, end + 1e-9, 1.0 / fps)
    qpos = np.tile(sc.model.qpos0, (times.size, 1))
    after = times >= 0
    qpos[after, sc.sled_qpos] = np.interp(times[after], t, sled)
    qpos[after, sc.fork_qpos] = np.interp(times[after], t, fork)
    # Free fall from the drop height (sled descent negative above touch), fork unloaded.
    qpos[~after, sc.sled_qpos] = -setup.drop_height + 0.5 * setup.gravity * (times[~after] + fall) ** 2
    qpos[~after, sc.fork_qpos] = 0.0
    return Trajectory(sc.model, times, qpos, label)


def roll_trajectory(run_dir: Path, fps: float = 30.0, duration: float | None = None) -> Trajectory:
    """Frames of a rolling run directory, re-simulated (deterministic) by
    ``mtbmj.rolling.frontend.roll_trajectory`` from its manifest (scenario), summary (speed, head angle,
    duration) and resolved config.toml."""
    run_dir = Path(run_dir)
    try:
        rolling = importlib.import_module("mtbmj.rolling.frontend")
        source = rolling.roll_trajectory
    except (ImportError, AttributeError):
        raise RenderError(f"{run_dir}: a rolling run, but this mtbmj has no mtbmj.rolling.frontend.roll_trajectory") from None
    try:
        manifest = json.loads(run_file_text(run_dir / "manifest.json", RenderError, "config"))
        summary = json.loads(run_file_text(run_dir / "summary.json", RenderError, "config"))
        scenario, speed = manifest["scenario"], float(summary["speed_m_per_s"])
        head = summary.get("head_angle_deg")
        end = float(summary.get("duration_s", 0)) or None
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise RenderError(f"{run_dir}: not a complete rolling run ({exc.__class__.__name__}: {exc})") from None
    end = duration if duration is not None else end
    kwargs = {"config": str(run_dir / "config.toml"), "duration": end, "fps": fps}
    if head is not None:
        kwargs["head_angle_deg"] = float(head)
    kwargs["drive"] = _drive(summary.get("drive"))
    try:
        model, t, q = source(scenario, speed, **kwargs)
    except MtbmjError:
        raise
    except (TypeError, ValueError) as exc:
        raise RenderError(f"{run_dir}: cannot replay scenario {scenario!r} ({exc})") from None
    return rolling_frames(model, t, q, fps, duration, f"roll {scenario} ({run_dir.name})")


def rolling_frames(model, t, q, fps: float = 30.0, duration: float | None = None, label: str = "roll") -> Trajectory:
    """A ``Trajectory`` from (model, times, qpos) as ``mtbmj.rolling.frontend.roll_trajectory`` returns them."""
    t = np.asarray(t, dtype=float).ravel()
    q = np.asarray(q, dtype=float).reshape(t.size, -1)
    end = float(t[-1]) if duration is None else min(float(t[-1]), float(t[0]) + float(duration))
    times = np.arange(float(t[0]), end + 1e-9, 1.0 / fps)
    qpos = np.column_stack([np.interp(times, t, q[:, j]) for j in range(q.shape[1])])
    track = None
    if model.nbody > 1:
        names = [model.body(i).name for i in range(model.nbody)]
        track = names.index("chassis") if "chassis" in names else 1
    return Trajectory(model, times, qpos, label, track_body=track, touch_s=float(t[0]))


def trajectory(source: str | Path, fps: float = 30.0, duration: float | None = None) -> Trajectory:
    """Drop or rolling run by the run directory's manifest; a preset/TOML file is a drop."""
    path = Path(source)
    manifest = path / "manifest.json"
    if path.is_dir() and manifest.exists():
        try:
            manifest_data = json.loads(run_file_text(manifest, RenderError, "config"))
        except (OSError, ValueError, RecursionError) as exc:
            raise RenderError(f"{manifest}: cannot read ({exc})") from None
        if not isinstance(manifest_data, dict):
            raise RenderError(f"{manifest}: not the manifest of an mtbmj run (a JSON object is expected)")
        kind = manifest_data.get("kind", "drop")
        if kind == "roll" or "scenario" in manifest_data:
            return roll_trajectory(path, fps, duration)
    return drop_trajectory(source, fps, duration)


def _camera(model, track_body: int | None):
    import mujoco

    cam = mujoco.MjvCamera()
    names = [model.cam(i).name for i in range(model.ncam)]
    if "side" in names:  # the scene's own side-on camera (the rolling scene has one)
        cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        cam.fixedcamid = names.index("side")
        return cam
    # Side-on: looking along +y at the x-z plane the sled moves in, slightly from above.
    cam.azimuth, cam.elevation = 90.0, -8.0
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    top = float(np.max(data.xpos[1:, 2])) if model.nbody > 1 else 1.0
    height = max(top, 0.5) + 0.25
    cam.lookat[:] = (0.0, 0.0, height / 2.0)
    cam.distance = 0.7 * height / math.tan(math.radians(model.vis.global_.fovy) / 2.0)
    if track_body is not None:
        cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        cam.trackbodyid = track_body
    else:
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    return cam


def frames(traj: Trajectory, width: int = 640, height: int = 480, caption: bool = True):
    """Yield one RGB uint8 (height, width, 3) image per frame of ``traj``."""
    import mujoco

    backend = gl_backend()
    model = traj.model
    model.vis.global_.offwidth = max(int(model.vis.global_.offwidth), width)
    model.vis.global_.offheight = max(int(model.vis.global_.offheight), height)
    data = mujoco.MjData(model)
    cam = _camera(model, traj.track_body)
    try:
        with _context_class(backend):
            renderer = mujoco.Renderer(model, height, width)
    except Exception as exc:  # noqa: BLE001 - a context that cannot be made is one line for the user
        raise RenderError(f"cannot create an {backend.upper()} GL context ({exc})") from None
    # Software GL (llvmpipe, OSMesa) spends most of a frame on shadows and the floor reflection.
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
    try:
        for t, q in zip(traj.times, traj.qpos):
            data.qpos[:] = q
            data.time = t
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, cam)
            image = renderer.render()
            yield _caption(image, f"{traj.label}  t = {t - traj.touch_s:+.3f} s") if caption else image
    finally:
        renderer.close()


def _caption(image: np.ndarray, text: str) -> np.ndarray:
    from PIL import Image, ImageDraw

    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    draw.text((8, 6), text, fill=(255, 255, 255))
    return np.asarray(img)


def _write_gif(path: str, images, fps: float) -> int:
    from PIL import Image

    pictures = [Image.fromarray(i).convert("P", palette=Image.Palette.ADAPTIVE) for i in images]
    if not pictures:
        raise RenderError("no frames to write")
    pictures[0].save(path, format="GIF", save_all=True, append_images=pictures[1:],
                     duration=max(20, int(round(1000.0 / fps))), loop=0)
    return len(pictures)


def _write_mp4(path: str, images, fps: float, width: int, height: int) -> int:
    import imageio_ffmpeg  # present: check_output asked for it before any work
    writer = imageio_ffmpeg.write_frames(path, (width, height), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
                                         quality=7, macro_block_size=2, ffmpeg_log_level="error")
    writer.send(None)
    count = 0
    try:
        for image in images:
            writer.send(np.ascontiguousarray(image))
            count += 1
    finally:
        writer.close()
    return count


def check_output(out: str | Path, width: int, height: int, fps: float) -> str:
    """The format (".mp4"/".gif") of ``out``; raises on a bad name, size or rate."""
    ext = Path(out).suffix.lower()
    if ext not in FORMATS:
        raise RenderError(f"{out}: unknown video format {ext or '(no extension)'!r} (use .mp4 or .gif)")
    if not (isinstance(width, int) and isinstance(height, int) and 16 <= width <= 4096 and 16 <= height <= 4096):
        raise RenderError(f"--width/--height: must be whole numbers of pixels in 16..4096, got {width}x{height}")
    if ext == ".mp4" and (width % 2 or height % 2):
        raise RenderError(f"--width/--height: MP4 (H.264, yuv420p) needs even sizes, got {width}x{height}")
    if ext == ".mp4":
        from mtbmj.extras import require

        require("video", "MP4 video", otherwise="write a .gif")
    if not (math.isfinite(fps) and 1 <= fps <= 240):
        raise RenderError(f"--fps: must be in 1..240, got {fps:g}")
    check_file_target(out, error=RenderError)  # a file that is not mtbmj's: refused before any work
    return ext


def render(source: "str | Path | Trajectory", out: str | Path, fps: float = 30.0, width: int = 640, height: int = 480,
           duration: float | None = None) -> dict:
    """Write a video of a drop (run directory, preset or TOML), a rolling run directory or a
    ``Trajectory`` to ``out``
    (.mp4 or .gif, chosen by the extension), atomically; returns what was written."""
    ext = check_output(out, width, height, fps)
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise RenderError(f"--duration: must be positive, got {duration}")
    gl_backend()  # fail before any simulation when there is no GL backend
    traj = source if isinstance(source, Trajectory) else trajectory(source, fps, duration)
    out = Path(out)
    with staged_file(out, command="render", error=RenderError) as tmp:
        images = frames(traj, width, height)
        count = _write_gif(str(tmp), images, fps) if ext == ".gif" else _write_mp4(str(tmp), images, fps, width, height)
    return {"path": str(out), "frames": count, "fps": fps, "width": width, "height": height,
            "duration_s": count / fps, "backend": gl_backend(), "label": traj.label}


def _drive(summary_drive):
    """The drive a rolling run was made with, from its summary: a run from before the drive was
    recorded was driven by the ideal servo."""
    from mtbmj.controllers.drive import Drive

    if not isinstance(summary_drive, dict) or "mode" not in summary_drive:
        return "servo"
    if summary_drive["mode"] != "rider":
        return summary_drive["mode"]
    return Drive("rider", push=float(summary_drive["push_limit_N"]), power=float(summary_drive["power_limit_W"]),
                 brake=float(summary_drive["brake_limit_N"]))
