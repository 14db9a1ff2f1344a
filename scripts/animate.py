"""Play a saved simulation in meshcat.

    python scripts/animate.py RESULT.npz [--html FILE] [--live] [--speed S] [--exaggerate K]
                              [--fps F] [--focus JOINT] [--urdf FILE]

--html writes one self-contained HTML file (plays in a browser, no server, no
network); --live serves the scene with meshcat's server and prints the URL to
open (Ctrl-C to stop). Without either, --live is assumed. --exaggerate K
magnifies the motion inside the clearance joints (gaps and relative
displacements, K >= 1; links stay true to scale): see docs/animation.md.

Exit status 0 on success, 2 on bad input (missing, malformed or foreign result
file, bad option).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robot.cli.common import exit_on_error  # noqa: E402
from robot.viz.animation import AnimationSummary, export_html, serve_live, wait_forever  # noqa: E402


def describe(summary: AnimationSummary) -> str:
    lines = [
        f"  {summary.n_frames} frames at {summary.fps:g} fps: simulated t = {summary.t_start:.4g} .. {summary.t_end:.4g} s "
        f"played in {summary.playback_seconds:.1f} s (speed x{summary.speed:g}), clearance motion x{summary.exaggerate:g}"
    ]
    for name, size in summary.sizes.items():
        lines.append(f"  {name} ({size.kind}): element sizes from {size.source}")
    lines += [f"  note: {note}" for note in summary.notes]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("result", type=Path, help="result file written by scripts/simulate.py (.npz)")
    parser.add_argument("--html", type=Path, default=None, help="write a self-contained HTML file")
    parser.add_argument("--live", action="store_true", help="serve the scene with meshcat's server and print the URL")
    parser.add_argument("--speed", type=float, default=1.0, help="simulated seconds per second of playback (default 1; 0.1 = 10x slow motion)")
    parser.add_argument("--exaggerate", type=float, default=1.0, help="magnification K >= 1 of the motion inside the clearance joints (default 1)")
    parser.add_argument("--fps", type=float, default=30.0, help="frames per second of playback (default 30)")
    parser.add_argument("--focus", default=None, metavar="JOINT", help="look at this clearance joint from close by (default: whole mechanism)")
    parser.add_argument("--urdf", type=Path, default=None, help="mechanism file (default: urdf/<the result's mechanism>)")
    args = parser.parse_args()
    options = dict(urdf=args.urdf, exaggerate=args.exaggerate, speed=args.speed, fps=args.fps, focus=args.focus)
    live = args.live or args.html is None
    if args.html is not None:
        summary = export_html(args.result, args.html, **options)
        print(f"wrote {summary.html_path} ({summary.html_bytes / 1e6:.1f} MB)\n{describe(summary)}")
    if live:
        _, summary = serve_live(args.result, **options)
        print(f"open {summary.url} in a browser (Ctrl-C to stop)\n{describe(summary)}", flush=True)
        wait_forever()
    return 0


if __name__ == "__main__":
    exit_on_error(main)
