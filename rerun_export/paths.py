"""The ``.rrd`` file a view writes: its default name, and the checks made before rerun loads.

Light on purpose (no rerun, numpy or readers), so that ``camlog view`` refuses an output it
would not write before spending its start-up on the rerun SDK.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from replay.atomic import refuse_existing

__all__ = ["default_output", "output_of", "refuse_output"]


def default_output(log: Path) -> Path:
    """``run.mcap`` -> ``run.rrd``; a rosbag2 directory ``run`` -> ``run.rrd`` beside it."""
    return log.with_name(log.name + ".rrd") if log.is_dir() else log.with_suffix(".rrd")


def output_of(paths: Sequence[Path], output: Path | None, *, live: bool) -> Path | None:
    """The file a view of ``paths`` writes: ``output``, else (unless it goes to a ``live``
    viewer) the first log's name with ``.rrd``."""
    if output is None and not live and paths:
        return default_output(Path(paths[0]))
    return output


def refuse_output(paths: Sequence[Path], output: Path | None, *, live: bool,
                  overwrite: bool) -> None:
    """:class:`~replay.errors.OutputError` for an output that exists (without
    ``overwrite``) or is one of the logs."""
    final = output_of(paths, output, live=live)
    if final is not None:
        refuse_existing(final, overwrite=overwrite, inputs=[Path(p) for p in paths])
