"""``camlog view``: one or more logs as one rerun recording with a ready-made layout.

Several logs are merged in log time into one recording (e.g. a log and the outputs that
``camlog process --drop-input`` wrote for it); a topic present in several logs is taken from
the first. Messages stream from the readers to rerun one at a time, so memory does not grow
with the length of the logs.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from ..errors import LogReadError
from ..formats import LogReader, open_reader
from ..formats.base import RawMessage, TopicInfo
from ..selection import merge_in_time, select_topics, window_ns
from .blueprint import make_blueprint
from .logger import LoggerOptions, SceneLogger
from .scene import ScenePlan, plan_scene
from .sink import RecordingSink, default_output
from .survey import survey
from .viewer import DEFAULT_PORT, LOCALHOST

__all__ = ["ExportSession", "ViewResult", "open_logs", "view_logs"]


@dataclass(frozen=True)
class ViewResult:
    """What :func:`view_logs` logged: rows per entity, the cameras, what it left out
    (``skipped``: topic -> why; ``duplicates``: topics a later log repeats, not read)."""

    output: Path | None
    messages: int
    counts: dict[str, int]
    cameras: list[str]
    skipped: dict[str, str]
    warnings: list[str] = field(default_factory=list)
    duplicates: list[str] = field(default_factory=list)
    wall_s: float = 0.0


@dataclass
class ExportSession:
    """Open logs with their chosen topics, time window and scene plan (shared with play).

    ``chosen[i]`` lists the topics read from log ``i``; a topic found in several logs is
    read from the first (``owner``)."""

    readers: list[LogReader]
    chosen: list[list[str]]
    owner: dict[str, int]
    start_ns: int | None
    end_ns: int | None
    plan: ScenePlan
    total: int  # messages of the chosen topics (before the time window)
    duplicates: list[str] = field(default_factory=list)  # "topic (log)" read from an earlier log

    def messages(self) -> Iterable[RawMessage]:
        """Raw messages of every log in log-time order."""
        return merge_in_time(self.readers, self.chosen, self.start_ns, self.end_ns)

    def decode(self, raw: RawMessage) -> Any:
        """Decode with the reader that owns the topic (errors name that log)."""
        return self.readers[self.owner[raw.topic]].decode(raw)


def open_logs(stack: contextlib.ExitStack, paths: Sequence[Path], *,
              topics: Sequence[str] | None, start_s: float | None, end_s: float | None,
              recover: bool) -> ExportSession:
    """Open ``paths`` in ``stack``, choose topics and window, survey and plan the scene."""
    if not paths:
        raise LogReadError("no log given")
    readers = [stack.enter_context(open_reader(path, recover=recover)) for path in paths]
    for reader in readers:
        if reader.message_count == 0:
            raise LogReadError(f"{reader.path} is empty (no messages)")
    union: dict[str, TopicInfo] = {}
    for reader in readers:
        for name, info in reader.topics.items():
            union.setdefault(name, info)
    where = str(paths[0]) if len(paths) == 1 else f"{len(paths)} logs"
    wanted = select_topics(union, topics, where=where)
    chosen = [None if wanted is None else [t for t in wanted if t in reader.topics]
              for reader in readers]
    origin = min(r.start_ns for r in readers if r.start_ns is not None)
    start_ns, end_ns = window_ns(origin, start_s, end_s)
    found = survey(readers, chosen, start_ns, end_ns)
    plan = plan_scene(found)
    owned = [[t for t in found.topics if found.owner[t] == i] for i in range(len(readers))]
    total = sum(info.count for info in found.topics.values())
    return ExportSession(readers, owned, dict(found.owner), start_ns, end_ns, plan, total,
                         found.duplicates)


def view_logs(
    paths: Sequence[Path],
    *,
    output: Path | None = None,
    spawn: bool = False,
    connect: str | None = None,
    bind: str = LOCALHOST,
    port: int = DEFAULT_PORT,
    overwrite: bool = False,
    topics: Sequence[str] | None = None,
    start_s: float | None = None,
    end_s: float | None = None,
    options: LoggerOptions | None = None,
    recover: bool = False,
    progress: bool | None = None,
) -> ViewResult:
    """Export ``paths`` to an ``.rrd`` (default: the first log's name with ``.rrd``) or a
    viewer (a spawned one listens on ``bind:port``). ``progress``: None shows a bar only on a
    terminal."""
    started = time.perf_counter()
    options = options or LoggerOptions()
    if output is None and not spawn and connect is None:
        output = default_output(Path(paths[0])) if paths else None
    with contextlib.ExitStack() as stack:
        session = open_logs(stack, [Path(p) for p in paths], topics=topics, start_s=start_s,
                            end_s=end_s, recover=recover)
        sink = RecordingSink(output=output, connect=connect, spawn=spawn, overwrite=overwrite,
                             blueprint=make_blueprint(session.plan), bind=bind,
                             port=port, inputs=paths)
        bar = stack.enter_context(tqdm(total=session.total, unit="msg", desc="view",
                                       leave=False, disable=None if progress is None
                                       else not progress))
        with sink:
            logger = SceneLogger(sink.rec, session.plan, options, decode=session.decode,
                                 flush=sink.flush)
            logger.log_static()
            count = 0
            try:
                for raw in session.messages():
                    logger.log(raw)
                    count += 1
                    bar.update()
            finally:
                logger.close()
        warnings = [w for r in session.readers for w in r.warnings] + logger.warnings
    plan = session.plan
    return ViewResult(output, count, dict(logger.counts), list(plan.cameras), dict(plan.skipped),
                      warnings, session.duplicates, time.perf_counter() - started)
