"""Play a saved simulation in meshcat.

--html writes one self-contained HTML file (plays in a browser, no server, no
network); --live serves the scene with meshcat's server, on this machine only
(127.0.0.1) unless --host says otherwise, and prints the URL to open (Ctrl-C to
stop). Without either, --live is assumed. --exaggerate K magnifies the motion
inside the clearance joints (gaps and relative displacements, 1 <= K <= 1e6;
links stay true to scale): see docs/animation.md. The mechanism file is the one
the run read, else the shipped file of that name, whichever has the result's
fingerprint. --html never overwrites the result file itself.

examples:
  clearance animate results/compound_misaligned.npz --html anim.html --exaggerate 150 --speed 0.1
  clearance animate results/compound.npz --live --focus R1
  clearance animate results/compound.npz --live --host 0.0.0.0   # reachable from other machines
"""

from __future__ import annotations

import argparse
from pathlib import Path

from robot.cli.common import EXIT_OK, positive_number, writable_file


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("result", type=Path, help="result file written by 'clearance run' (.npz)")
    parser.add_argument("--html", type=Path, default=None, help="write a self-contained HTML file")
    parser.add_argument("--live", action="store_true", help="serve the scene with meshcat's server and print the URL")
    parser.add_argument("--host", default="127.0.0.1", help="address the live server listens on (default 127.0.0.1: this machine only)")
    parser.add_argument("--speed", type=positive_number, default=1.0, help="simulated seconds per second of playback (default 1; 0.1 = 10x slow motion)")
    parser.add_argument("--exaggerate", type=float, default=1.0, help="magnification K of the motion inside the clearance joints, 1 <= K <= 1e6 (default 1: true scale)")
    parser.add_argument("--fps", type=positive_number, default=30.0, help="frames per second of playback (default 30)")
    parser.add_argument("--focus", default=None, metavar="JOINT", help="look at this clearance joint from close by (default: whole mechanism)")
    parser.add_argument("--urdf", type=Path, default=None, help="mechanism file (default: the file the run read, else the shipped file of that name; its fingerprint must match the result's)")


def describe(summary) -> str:
    lines = [
        f"  {summary.n_frames} frames at {summary.fps:g} fps: simulated t = {summary.t_start:.4g} .. {summary.t_end:.4g} s "
        f"played in {summary.playback_seconds:.1f} s (speed x{summary.speed:g}), clearance motion x{summary.exaggerate:g}"
    ]
    for name, size in summary.sizes.items():
        lines.append(f"  {name} ({size.kind}): element sizes from {size.source}")
    lines += [f"  note: {note}" for note in summary.notes]
    return "\n".join(lines)


def execute(args: argparse.Namespace) -> int:
    from robot.viz.animation import check_not_the_result, export_html, serve_live, wait_forever

    options = dict(urdf=args.urdf, exaggerate=args.exaggerate, speed=args.speed, fps=args.fps, focus=args.focus)
    live = args.live or args.html is None
    if args.html is not None:
        check_not_the_result(args.result, args.html, "--html")
        writable_file(args.html, "--html")
        summary = export_html(args.result, args.html, **options)
        print(f"wrote {summary.html_path} ({summary.html_bytes / 1e6:.1f} MB)\n{describe(summary)}")
    if live:
        from robot.viz.live_server import start_server

        _, summary = serve_live(args.result, zmq_url=start_server(args.host), **options)
        print(f"open {summary.url} in a browser (Ctrl-C to stop)\n{describe(summary)}", flush=True)
        wait_forever()
    return EXIT_OK
