"""``clearance``: the command-line program (one subcommand per job; :mod:`robot.cli.registry`).

Every subcommand shares the exit codes of :mod:`robot.cli.common` and prints a
one-line message, never a traceback, for a user error (a bad scene, option,
input file or output folder): :class:`robot.errors.RobotError` and
:class:`clearance_contact.errors.ContactError` are user errors; anything else is a
bug (exit 3, with the traceback).
"""

from __future__ import annotations

import argparse
import gc
import importlib
import sys
import traceback
from typing import NoReturn

from robot.cli.common import EXIT_BAD_INPUT, EXIT_CODES_HELP, EXIT_INTERNAL, EXIT_INTERRUPTED
from robot.cli.registry import COMMANDS, KERNEL_COMMANDS, SUMMARIES

EXAMPLES = """examples:
  clearance paper                                   # the seed paper's study into results/paper
  clearance run --scene compound_misaligned --t-end 0.2 --out results
  clearance run --scene my_scene.toml --check       # validate a scene, build its model, run nothing
  clearance animate results/compound_misaligned.npz --html anim.html --exaggerate 150 --speed 0.1
  clearance describe --clearance R1,S1
  clearance COMMAND --help                          # options, examples and exit codes of a command
"""


class _Parser(argparse.ArgumentParser):
    """argparse exits with status 2 on a bad option (our bad-input code); keep its message, drop the usage noise."""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The top-level parser; the subparser of ``command`` (only that one) gets its options (imports its module)."""
    parser = _Parser(
        prog="clearance",
        description="Dynamics of spatial mechanisms with 3D clearance joints.",
        epilog=EXAMPLES + "\n" + EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMANDS:
        if name != command:
            sub.add_parser(name, help=SUMMARIES[name], add_help=False)
            continue
        module = importlib.import_module(COMMANDS[name])
        command_parser = sub.add_parser(
            name,
            help=SUMMARIES[name],
            description=module.__doc__,
            epilog=EXIT_CODES_HELP,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        module.add_arguments(command_parser)
        command_parser.set_defaults(execute=module.execute)
    return parser


def _command_of(argv: list[str]) -> str | None:
    first = next((arg for arg in argv if not arg.startswith("-")), None)
    return first if first in COMMANDS else None


def _warning_line(message, category, filename, lineno, line=None) -> str:
    """A warning as the commands print it: one line with its class, without the source line Python would echo."""
    return f"warning: {category.__name__}: {message}\n"


def main(argv: list[str] | None = None) -> int:
    """Run ``clearance ARGV``; return the exit code (never raises for a user error)."""
    import warnings

    previous, warnings.formatwarning = warnings.formatwarning, _warning_line
    try:
        return _command(argv)
    finally:
        warnings.formatwarning = previous


def _command(argv: list[str] | None) -> int:
    """:func:`main`'s work: the command's exit code."""
    from clearance_contact.errors import ContactError
    from robot.errors import RobotError
    from robot.extensions import load_extensions

    argv = sys.argv[1:] if argv is None else list(argv)
    command = _command_of(argv)
    if command in KERNEL_COMMANDS and not {"-h", "--help"} & set(argv):
        # before the command's module imports a kernel (some do at import: so before parsing, too),
        # so that its process loads the library, not numba; once per version of the sources
        from robot.dynamics.kernel_build import ensure_library

        try:
            ensure_library()
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
    try:  # before parsing: a command's options may list registered names (integrators, analyses)
        load_extensions()
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    parser = build_parser(command)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a bad option (2)
        return int(exc.code or 0)
    if args.command is None:
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return int(args.execute(args) or 0)
    except (RobotError, ContactError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemExit as exc:  # a library's own exit with a message is a user error
        if isinstance(exc.code, str):
            print(f"error: {exc.code}", file=sys.stderr)
            return EXIT_BAD_INPUT
        return int(exc.code or 0)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception:  # noqa: BLE001 - a bug: say so, with the traceback
        traceback.print_exc()
        print("internal error: this is a bug of the simulator; please report it with the traceback above", file=sys.stderr)
        return EXIT_INTERNAL


def exit_process(code: int) -> NoReturn:
    """End the process with exit status ``code`` once a command has returned (its files written, its output printed).

    At exit Python collects the garbage of every object left, numba's and LLVM's
    object graphs included: 0.25-0.35 s of CPU after ``clearance run``, more than
    its imports. ``gc.freeze()`` first puts them out of the collector's reach, and
    the interpreter exits in ~0.03 s. The rest of a normal exit stays (unlike
    ``os._exit``): atexit handlers, the flush of stdout and stderr, the exit
    status. A command's files are closed and in place (atomic writes) before it
    returns, so no unfinalised object holds unwritten data.
    """
    gc.freeze()
    sys.exit(code)


def console_main() -> None:
    """Entry point of the ``clearance`` console script."""
    exit_process(main())


if __name__ == "__main__":
    console_main()
