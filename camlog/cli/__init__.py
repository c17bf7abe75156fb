"""The ``camlog`` command line: each subcommand parses arguments and calls one function."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from processors.errors import ProcessorError
from recorder.errors import RecorderError
from replay.errors import ReplayError

#: subcommand name -> (one-line help, add-arguments function, run function)
Command = tuple[str, Callable[[argparse.ArgumentParser], None], Callable[[argparse.Namespace], int]]


def _commands() -> dict[str, Command]:
    from . import (
        batch as cmd_batch,
    )
    from . import (
        calibrate as cmd_calibrate,
    )
    from . import (
        convert as cmd_convert,
    )
    from . import (
        demo as cmd_demo,
    )
    from . import (
        golden as cmd_golden,
    )
    from . import (
        import_images as cmd_import,
    )
    from . import (
        info as cmd_info,
    )
    from . import (
        play as cmd_play,
    )
    from . import (
        process as cmd_process,
    )
    from . import (
        record as cmd_record,
    )
    from . import (
        resync as cmd_resync,
    )
    from . import (
        view as cmd_view,
    )

    return {
        "demo": (
            "run the whole workflow on built-in scenarios: record, resync, calibrate, "
            "process, view",
            cmd_demo.add_arguments, cmd_demo.run,
        ),
        "record": (
            "simulate a scenario in MuJoCo and write its camera log",
            cmd_record.add_arguments, cmd_record.run,
        ),
        "info": (
            "summarise a log: format, duration, topics, rates, encodings",
            cmd_info.add_arguments, cmd_info.run,
        ),
        "process": (
            "run image processors (red pixels, edges, rectify) over one topic of a log",
            cmd_process.add_arguments, cmd_process.run,
        ),
        "resync": (
            "pair and re-stamp the images of two unsynchronised cameras",
            cmd_resync.add_arguments, cmd_resync.run,
        ),
        "batch": (
            "run a pipeline (resync, calibrate, process, ...) over many logs in parallel",
            cmd_batch.add_arguments, cmd_batch.run,
        ),
        "calibrate": (
            "calibrate a mono camera or stereo pair from a log (or --check a calibration)",
            cmd_calibrate.add_arguments, cmd_calibrate.run,
        ),
        "view": (
            "show logs in rerun: write an .rrd or stream to a viewer, with a ready layout",
            cmd_view.add_arguments, cmd_view.run,
        ),
        "play": (
            "replay a log in (scaled) real time to a viewer, an .rrd or a new log",
            cmd_play.add_arguments, cmd_play.run,
        ),
        "convert": (
            "convert a log between MCAP, rosbag2 and ROS1, filtered, images re-encoded",
            cmd_convert.add_arguments, cmd_convert.run,
        ),
        "import": (
            "turn a folder of image files (mono or left/right stereo) into a log",
            cmd_import.add_arguments, cmd_import.run,
        ),
        "golden": (
            "golden-log regression: check, update or re-record the committed golden logs",
            cmd_golden.add_arguments, cmd_golden.run,
        ),
    }


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="camlog",
        description="Log-first record/replay toolchain for robot cameras.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (summary, add_arguments, run) in _commands().items():
        p = sub.add_parser(name, help=summary, description=summary[0].upper() + summary[1:] + ".")
        add_arguments(p)
        p.set_defaults(run=run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: known errors become one line on stderr and exit status 1."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args))
    except (ReplayError, RecorderError, ProcessorError) as err:
        print(f"camlog {args.command}: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"camlog {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
