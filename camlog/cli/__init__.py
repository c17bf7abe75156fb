"""The ``camlog`` command line: each subcommand parses arguments and calls one function.

Start-up stays small: a command's module (and what it imports) is loaded only when that
command runs, and its arguments are registered only then; ``camlog --help`` loads none.
Heavy libraries (numpy, OpenCV, rerun, MuJoCo) are imported inside the functions that use
them, never to build the parser. This module imports only the standard library, so that
Ctrl-C while the packages load is handled like Ctrl-C at any later moment.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Collection, Sequence
from typing import Any, NoReturn

from .decoder_messages import filter_decoder_messages
from .memory import keep_freed_memory

#: subcommand name -> (one-line help, module under camlog.cli with add_arguments and run)
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("run the whole workflow on built-in scenarios: record, resync, calibrate, "
             "process, view", "demo"),
    "record": ("simulate a scenario in MuJoCo and write its camera log", "record"),
    "info": ("summarise a log: format, duration, topics, rates, encodings", "info"),
    "process": ("run image processors (red pixels, edges, rectify, ...) over image topics of "
                "a log", "process"),
    "throttle": ("thin topics of a log to every N-th message or at most HZ (copied as stored)",
                 "throttle"),
    "resync": ("pair and re-stamp the images of two unsynchronised cameras", "resync"),
    "batch": ("run a pipeline (resync, calibrate, process, ...) over many logs in parallel",
              "batch"),
    "calibrate": ("calibrate a mono camera, a stereo pair or a rig from a log (or --check a "
                  "calibration)", "calibrate"),
    "check": ("is every log still calibrated? drift of stereo pairs and board cameras, window "
              "by window", "check"),
    "view": ("show logs in rerun: write an .rrd or stream to a viewer, with a ready layout",
             "view"),
    "play": ("replay a log in (scaled) real time to a viewer, an .rrd or a new log", "play"),
    "convert": ("convert a log between MCAP, rosbag2 and ROS1, filtered, images re-encoded",
                "convert"),
    "export": ("write the images of a topic as PNG/JPEG files named by stamp, or one MP4",
               "export"),
    "import": ("turn a folder of image files (mono or left/right stereo) into a log",
               "import_images"),
    "golden": ("golden-log regression: check, update or re-record the committed golden logs",
               "golden"),
}

#: (module, exception) of every package's error tree: one line on stderr, exit status 1
KNOWN_ERRORS = (("camlog.errors", "CamlogError"), ("replay.errors", "ReplayError"),
                ("recorder.errors", "RecorderError"), ("processors.errors", "ProcessorError"),
                ("rerun_export.errors", "RerunExportError"))


class _Parser(argparse.ArgumentParser):
    """argparse with its errors in one line, like every other camlog error."""

    def error(self, message: str) -> NoReturn:
        """Print ``PROG: error: MESSAGE (see PROG --help)`` and exit with status 2."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(commands: Collection[str] = COMMANDS) -> argparse.ArgumentParser:
    """The parser with every subcommand, and the arguments of ``commands`` (default: all)."""
    parser = _Parser(
        prog="camlog",
        description="Log-first record/replay toolchain for robot cameras.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (summary, module_name) in COMMANDS.items():
        p = sub.add_parser(name, help=summary, description=summary[0].upper() + summary[1:] + ".")
        if name in commands:
            module = importlib.import_module(f"{__name__}.{module_name}")
            module.add_arguments(p)
            p.set_defaults(run=module.run)
    return parser


def _command_in(argv: Sequence[str]) -> str | None:
    """The subcommand argparse will pick: the first argument that is not an option."""
    first = next((arg for arg in argv if not arg.startswith("-")), None)
    return first if first in COMMANDS else None


def known_error(err: BaseException) -> bool:
    """Whether ``err`` belongs to one of the packages' error trees (a package that was never
    imported cannot have raised, so nothing is imported to tell)."""
    for module_name, class_name in KNOWN_ERRORS:
        module = sys.modules.get(module_name)
        if module is not None and isinstance(err, getattr(module, class_name)):
            return True
    return False


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: known errors, and OS errors, become one line on stderr and exit status 1;
    Ctrl-C at any moment (start-up included) ends with one line and exit status 130.

    Called as the program (no ``argv``), the process exits once the command is over: Ctrl-C
    is then ignored, so that one arriving during the interpreter's exit (libraries' exit
    handlers, e.g. tqdm's monitor) prints no traceback."""
    as_program, where = argv is None, "camlog"
    try:  # a Ctrl-C before the handlers are in is one line too
        argv = sys.argv[1:] if argv is None else list(argv)
        command = _command_in(argv)
        where = f"camlog {command}" if command else "camlog"
        if as_program:
            sys.unraisablehook = _interrupt_where_it_can_be_handled(sys.unraisablehook)
            signal.signal(signal.SIGINT, _note_interrupt)
        return _run(argv, command, where, as_program=as_program)
    except KeyboardInterrupt:
        return _interrupted(where)
    finally:
        if as_program:
            signal.signal(signal.SIGINT, signal.SIG_IGN)


#: whether Ctrl-C has come (set by camlog's own process's handler)
_INTERRUPTED = threading.Event()


def _note_interrupt(signum: int, frame: Any) -> None:
    """Python's own Ctrl-C handler, remembering that the signal came: an extension module
    that imports from C turns the KeyboardInterrupt into an ImportError of its own (numpy's
    ``PyCapsule_Import could not import module "datetime"``), which is still Ctrl-C."""
    _INTERRUPTED.set()
    signal.default_int_handler(signum, frame)


#: how long after an undeliverable Ctrl-C it is sent again (the hook has returned by then)
REDELIVER_S = 0.01


def _interrupt_where_it_can_be_handled(
        previous: Callable[[Any], object]) -> Callable[[Any], object]:
    """An unraisable-exception hook: a Ctrl-C that lands in a callback Python cannot raise
    from (e.g. an import lock's cleanup at start-up) is delivered again to the main thread,
    where it ends the command in one line, instead of printing "Exception ignored".

    The signal is sent again from another thread, a moment later: raised here, in the main
    thread, its handler would run inside this hook, which cannot raise either."""
    main_thread = threading.main_thread().ident

    def interrupt_again() -> None:
        if main_thread is not None:
            signal.pthread_kill(main_thread, signal.SIGINT)

    def hook(unraisable: Any) -> object:
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            later = threading.Timer(REDELIVER_S, interrupt_again)
            later.daemon = True
            later.start()
            return None
        return previous(unraisable)
    return hook


def _run(argv: list[str], command: str | None, where: str, *, as_program: bool) -> int:
    """:func:`main` without its exit handler."""
    try:
        # rerun's Rust side logs a failure (disk full, lost viewer) as several lines of its
        # own; camlog reports it in one. RUST_LOG=warn (or any value) brings them back.
        os.environ.setdefault("RUST_LOG", "off")
        if as_program:  # process-wide settings: only in camlog's own process
            # camlog's dense linear algebra is small (the joint solve's reduced system):
            # OpenBLAS's worker threads would only add their start-up (60 ms at numpy's
            # import) and spin beside camlog's own threads. Read once, when numpy loads; a
            # user's setting stands.
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
            # damaged frames are camlog's to report, in one line per topic: OpenCV's own
            # warnings about them are left out (a user's setting stands), and so are the
            # lines its libjpeg and libpng print from C
            os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
            filter_decoder_messages()
        args = build_parser([command] if command else []).parse_args(argv)
        args.as_program = as_program  # the process is camlog's own (see camlog.lean)
        if as_program:
            keep_freed_memory()
        return int(args.run(args))
    except KeyboardInterrupt:
        return _interrupted(where)
    except BrokenPipeError:  # e.g. `camlog info LOG | head -1`
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # exit writes too
        return 1
    except Exception as err:
        return _failed(err, where)


def _interrupted(where: str) -> int:
    """Ctrl-C: one line, exit status 130."""
    print(f"{where}: interrupted", file=sys.stderr)
    return 130


def _failed(err: Exception, where: str) -> int:
    """A known error, an OS error or memory running out as one line and exit status 1;
    Ctrl-C that C code turned into another error as Ctrl-C; anything else raised again."""
    if _INTERRUPTED.is_set():
        return _interrupted(where)
    if isinstance(err, OSError) and not known_error(err):
        # disk full, permissions, names too long: with the path
        print(f"{where}: error: {os_error_text(err)}", file=sys.stderr)
    elif isinstance(err, MemoryError):
        print(f"{where}: error: out of memory", file=sys.stderr)
    elif isinstance(err, OSError) or known_error(err):
        print(f"{where}: error: {err}", file=sys.stderr)
    else:
        raise err
    return 1


def os_error_text(err: OSError) -> str:
    """``PATH: reason`` of an OS error (both paths of a failed rename or copy)."""
    reason = err.strerror or str(err) or type(err).__name__
    paths = [str(p) for p in (err.filename, err.filename2) if p is not None]
    return f"{' -> '.join(paths)}: {reason}" if paths else reason


if __name__ == "__main__":
    sys.exit(main())
