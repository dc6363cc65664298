"""``mtbmj render RUN_OR_CONFIG --out video.mp4|.gif``: a headless video of a drop, rolling or bike run.
"""
from __future__ import annotations

from pathlib import Path

from mtbmj.cli.common import out_path


def add_parser(subparsers):
    """Add the ``render`` sub-command to an argparse sub-parser collection."""
    p = subparsers.add_parser(
        "render", help="write an MP4 or GIF of a drop, rolling or bike run (headless, EGL or OSMesa)",
        description="Render a run headless through mujoco.Renderer (EGL, else OSMesa; MUJOCO_GL=egl|osmesa forces "
                    "one): a run directory written by mtbmj drop/roll/bike is replayed, a preset or TOML file is run "
                    "on MuJoCo first. The format follows the extension of --out: .gif, or .mp4 (H.264; the [video] extra).")
    p.add_argument("source", metavar="RUN_OR_CONFIG", help="run directory, preset name (S1..S14) or TOML file")
    p.add_argument("--out", type=out_path, default=Path("out/render.gif"), help="video file, .gif or .mp4 (default out/render.gif)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second of simulated time (default 30)")
    p.add_argument("--width", type=int, default=640, help="pixels (default 640)")
    p.add_argument("--height", type=int, default=480, help="pixels (default 480)")
    p.add_argument("--duration", type=float, help="simulated time after touch in s (default: the whole run)")
    p.set_defaults(func=cmd_render)
    return p


def cmd_render(args) -> int:
    from mtbmj.bike.replay import is_bike_dir, rerun
    from mtbmj.rolling.render import RenderError, check_output, gl_backend, render

    source = args.source
    if is_bike_dir(source):  # mtbmj bike --out: re-simulated (mtbmj.bike.replay), drawn as bike --video draws it
        check_output(args.out, args.width, args.height, args.fps)
        if args.duration is not None and not (args.duration > 0):
            raise RenderError(f"--duration: must be positive, got {args.duration}")
        gl_backend()  # no headless OpenGL: one line before any work
        result = rerun(source, args.duration, RenderError)
        source = result.trajectory(args.fps, args.duration,
                                   f"bike {result.name} over {result.scenario} ({Path(args.source).name})")
    done = render(source, args.out, fps=args.fps, width=args.width, height=args.height, duration=args.duration)
    print(f"{done['label']}: {done['frames']} frames, {done['width']}x{done['height']} at {done['fps']:g} fps "
          f"({done['duration_s']:.2f} s, {done['backend']}); wrote {done['path']}")
    return 0
