"""Command line: ``masonry-dem <command>``.

Each command lives in its own module of this package and exposes ``add_parser(subparsers)``
(which registers the sub-command and sets ``func``) so commands stay independent.

The program runs ``run``, ``limit`` and ``render`` in a child process under a small parent
that reports the child's death by a signal no process can handle (SIGKILL, SIGABRT, SIGSEGV:
:mod:`masonry_dem._supervisor`).

Errors that come from the input, the file system or the machine's resources end the command
with one line on stderr and exit code 2 (``--debug``: with the traceback); Ctrl-C and SIGTERM
end it with "interrupted" and 128 + the signal's number (130 for Ctrl-C). Any other exception
is a bug in the package and keeps its traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
import traceback

from masonry_dem._version import version as version

COMMANDS = (
    "run",
    "validate",
    "interface",
    "render",
    "paraview_state",
    "study",
    "limit",
    "assess",
    "report",
    "fragility",
    "sweep",
    "warmup",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="masonry-dem",
        description="Nonlinear 3D discrete element analysis of masonry walls.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    parser.add_argument(
        "--debug", action="store_true", help="show the traceback of an error, not one line"
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {version()}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"masonry_dem.cli.{name}")
        except ModuleNotFoundError as exc:  # a command not built yet
            if exc.name != f"masonry_dem.cli.{name}":
                raise
            continue
        module.add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    from masonry_dem._signals import exit_code, interruption, raise_on_signals

    debug = "--debug" in (sys.argv[1:] if argv is None else argv)
    try:
        # from the first line: a Ctrl-C while the parser loads the commands' modules (VTK,
        # numba) is one line and 130 as one during the run is
        with raise_on_signals():
            if argv is None:  # the program: run, limit and render under a supervising parent
                from masonry_dem._supervisor import supervised

                code = supervised(sys.argv[1:])
                if code is not None:
                    return code
            return _run(argv)
    except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM: the results folder says so too
        if debug:
            traceback.print_exc()
        print(f"masonry-dem: {exc or 'interrupted'}", file=sys.stderr)
        return _stopped(exit_code(exc), argv)
    except (SystemError, ImportError) as exc:  # a signal inside a kernel's call or an import
        signal = interruption(exc)
        if signal is None:
            raise
        if debug:
            traceback.print_exc()
        print(f"masonry-dem: {signal or 'interrupted'}", file=sys.stderr)
        return _stopped(exit_code(signal), argv)


def _stopped(code: int, argv: list[str] | None) -> int:
    """``code`` of an interrupted command. The program itself (``argv`` None: the console
    script, ``python -m``) ends at once, without the interpreter's teardown: what it must
    write is written (the results folder says ``interrupted``), and the teardown finalized
    objects a signal had left half made (llvmlite's "Exception ignored in OutputString.__del__"
    after a Ctrl-C in a render) while an abandoned solver thread could still be inside a C
    library (HiGHS, PARDISO) or VTK."""
    if argv is not None:
        return code
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more to say there
            pass
    logging.shutdown()
    os._exit(code)


def _run(argv: list[str] | None) -> int:
    """The command line after its signals are handled (see :func:`main`)."""
    from masonry_dem._threads import set_thread_wait_policy

    set_thread_wait_policy()  # before any kernel starts OpenMP (it reads the policy once)
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except USER_ERRORS as exc:
        if args.debug:
            traceback.print_exc()
        print(f"masonry-dem: error: {one_line(exc)}", file=sys.stderr)
        return 2


#: what a user's input, the file system or the machine can cause: never a traceback
USER_ERRORS = (ValueError, OSError, MemoryError, RecursionError)


def one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line; an OS error with the path it concerns."""
    if isinstance(exc, MemoryError):
        return "out of memory: the model is too large for this machine" + (
            f" ({exc})" if str(exc) else ""
        )
    if isinstance(exc, OSError) and exc.strerror:
        text = f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    else:
        text = str(exc) or type(exc).__name__
    return " ".join(part.strip() for part in text.splitlines() if part.strip())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
