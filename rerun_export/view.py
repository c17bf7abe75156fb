"""``camlog view``: one or more logs as rerun recordings with a ready-made layout.

Related logs are merged in log time into one recording (e.g. a log and the outputs that
``camlog process --drop-input`` wrote for it); a topic present in several of them is taken
from the first. Unrelated logs (:mod:`rerun_export.groups`) get a recording each, under the
same application id and layout. Messages stream from the readers to rerun one at a time, so
memory does not grow with the length of the logs.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections import Counter
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from replay.errors import LogReadError
from replay.formats import LogReader, open_reader
from replay.formats.base import RawMessage, TopicInfo
from replay.selection import merge_in_time, select_topics, window_ns

from .blueprint import make_blueprint
from .groups import related_groups
from .logger import LoggerOptions, SceneLogger
from .options import UNDISTORTED_SCALE
from .paths import output_of
from .scene import ScenePlan, plan_scene
from .sink import Destination, RecordingSink
from .survey import Survey, survey
from .viewer import DEFAULT_PORT, LOCALHOST

__all__ = ["ExportSession", "ViewResult", "image_bytes", "open_logs", "size_note", "view_logs"]


@dataclass(frozen=True)
class ViewResult:
    """What :func:`view_logs` logged: rows per entity, the cameras, what it left out
    (``skipped``: topic -> why; ``duplicates``: topics a later log repeats, not read), how
    many raw images and how many images of pinhole views (``remapped``)."""

    output: Path | None
    messages: int
    counts: dict[str, int]
    cameras: list[str]
    skipped: dict[str, str]
    warnings: list[str] = field(default_factory=list)
    duplicates: list[str] = field(default_factory=list)
    wall_s: float = 0.0
    recordings: int = 1  # unrelated logs get a recording each (see rerun_export.groups)
    images: int = 0
    remapped: int = 0


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
    found: Survey | None = None  # the survey the plan was made from

    def messages(self) -> Iterable[RawMessage]:
        """Raw messages of every log in log-time order."""
        return merge_in_time(self.readers, self.chosen, self.start_ns, self.end_ns)

    def decode(self, raw: RawMessage) -> Any:
        """Decode with the reader that owns the topic (errors name that log)."""
        return self.readers[self.owner[raw.topic]].decode(raw)


def open_logs(stack: contextlib.ExitStack, paths: Sequence[Path], *,
              topics: Sequence[str] | None, start_s: float | None, end_s: float | None,
              recover: bool,
              undistorted_scale: float | None = UNDISTORTED_SCALE) -> ExportSession:
    """Open ``paths`` in ``stack``, choose topics and window, survey and plan the scene
    (pinhole views ``undistorted_scale`` times the raw images, see :func:`plan_scene`)."""
    readers = _open_readers(stack, paths, recover=recover)
    where = str(paths[0]) if len(paths) == 1 else f"{len(paths)} logs"
    return _session(readers, _chosen(readers, topics, where), start_s, end_s,
                    undistorted_scale)


def _open_readers(stack: contextlib.ExitStack, paths: Sequence[Path], *,
                  recover: bool) -> list[LogReader]:
    if not paths:
        raise LogReadError("no log given")
    readers = [stack.enter_context(open_reader(path, recover=recover)) for path in paths]
    for reader in readers:
        if reader.message_count == 0:
            raise LogReadError(f"{reader.path} is empty (no messages)")
    return readers


def _chosen(readers: Sequence[LogReader], topics: Sequence[str] | None,
            where: str) -> list[list[str]]:
    """The topics of each log that match ``topics`` (all of them for None)."""
    union: dict[str, TopicInfo] = {}
    for reader in readers:
        for name, info in reader.topics.items():
            union.setdefault(name, info)
    wanted = select_topics(union, topics, where=where)
    return [sorted(reader.topics) if wanted is None else
            [t for t in wanted if t in reader.topics] for reader in readers]


def _session(readers: list[LogReader], chosen: list[list[str]], start_s: float | None,
             end_s: float | None, undistorted_scale: float | None) -> ExportSession:
    """Survey and plan ``readers``; the time window counts from the earliest of them."""
    origin = min(r.start_ns for r in readers if r.start_ns is not None)
    start_ns, end_ns = window_ns(origin, start_s, end_s)
    found = survey(readers, chosen, start_ns, end_ns)
    plan = plan_scene(found, undistorted_scale=undistorted_scale)
    owned = [[t for t in found.topics if found.owner[t] == i] for i in range(len(readers))]
    total = sum(info.count for info in found.topics.values())
    return ExportSession(readers, owned, dict(found.owner), start_ns, end_ns, plan, total,
                         found.duplicates, found)


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
    recover: bool = False,
    options: LoggerOptions | None = None,
    progress: bool | None = None,
    say: Callable[[str], None] | None = None,
) -> ViewResult:
    """Export ``paths`` to an ``.rrd`` (default: the first log's name with ``.rrd``) or a
    live viewer: a spawned one (``spawn``, listening on ``bind:port``) or a running one at
    ``connect``. What is read: ``topics`` (names or globs; None: all), the window
    ``start_s``..``end_s`` after the first message, damaged logs ``recover``-ed.
    ``progress``: None shows a bar only on a terminal. ``say`` is told, before anything is
    written, how large the images will be."""
    started = time.perf_counter()
    options = options or LoggerOptions()
    paths = [Path(p) for p in paths]
    output = output_of(paths, output, live=spawn or connect is not None)
    with contextlib.ExitStack() as stack:
        readers = _open_readers(stack, paths, recover=recover)
        where = str(paths[0]) if len(paths) == 1 else f"{len(paths)} logs"
        chosen = _chosen(readers, topics, where)
        scale = options.undistorted_scale
        whole = _session(readers, chosen, start_s, end_s, scale)
        assert whole.found is not None
        groups = related_groups(readers, chosen, whole.found) if len(readers) > 1 else [[0]]
        sessions = [whole] if len(groups) == 1 else [
            _session([readers[i] for i in group], [chosen[i] for i in group], start_s, end_s,
                     scale)
            for group in groups if any(chosen[i] for i in group)]
        if say is not None:
            say(size_note(sessions, options))
        # one layout for every recording (they share the application id): a tab each
        tabs = [] if len(sessions) == 1 else [
            (", ".join(_name(r.path) for r in s.readers), s.plan) for s in sessions]
        blueprint = make_blueprint(whole.plan, recordings=tabs)
        destination = Destination(count=len(sessions), blueprint=blueprint,
                                  output=output, connect=connect, spawn=spawn, bind=bind,
                                  port=port, overwrite=overwrite, inputs=paths)
        bar = stack.enter_context(tqdm(total=sum(s.total for s in sessions), unit="msg",
                                       desc="view", leave=False, disable=None
                                       if progress is None else not progress))
        loggers: list[tuple[SceneLogger, int]] = []
        with destination:
            for session in sessions:
                with destination.sink() as sink:
                    loggers.append(_log_session(session, sink, options, bar))
        warnings = [w for r in readers for w in r.warnings]
        warnings += [w for logger, _ in loggers for w in logger.warnings]
    counts: Counter[str] = Counter()
    for logger, _ in loggers:
        counts.update(logger.counts)
    cameras = [c for session in sessions for c in session.plan.cameras]
    skipped = {t: why for session in sessions for t, why in session.plan.skipped.items()}
    duplicates = [d for session in sessions for d in session.duplicates]
    return ViewResult(output, sum(n for _, n in loggers), dict(counts),
                      cameras, skipped, warnings, duplicates, time.perf_counter() - started,
                      recordings=len(sessions), images=sum(lg.images for lg, _ in loggers),
                      remapped=sum(lg.remapped for lg, _ in loggers))


def _name(path: Path | str) -> str:
    """A log's file name (the last part of a URI)."""
    return path.name if isinstance(path, Path) else path.rstrip("/").rsplit("/", 1)[-1]


#: raw images above this size make a JPEG quality worth suggesting
LARGE_BYTES = 1_000_000_000


def image_bytes(session: ExportSession, every: int = 1) -> tuple[int, int]:
    """(all, raw) bytes of the images ``session`` will log, estimated from each image
    topic's first message, its count, the time window and ``every``."""
    found = session.found
    if found is None:
        return 0, 0
    total = raw = 0
    for topic, (size, is_raw) in found.image_bytes.items():
        if topic in session.plan.skipped:
            continue
        reader = session.readers[found.owner[topic]]
        count = math.ceil(found.topics[topic].count * _window_share(session, reader) / every)
        total += count * size
        raw += count * size if is_raw else 0
    return total, raw


def _window_share(session: ExportSession, reader: LogReader) -> float:
    """The share of ``reader``'s time range inside the session's window."""
    first, last = reader.start_ns, reader.end_ns
    if first is None or last is None or last <= first:
        return 1.0
    start = max(first, session.start_ns if session.start_ns is not None else first)
    end = min(last, session.end_ns if session.end_ns is not None else last)
    return max(0.0, min(1.0, (end - start) / (last - first)))


def size_note(sessions: Sequence[ExportSession], options: LoggerOptions) -> str:
    """One line: about how many bytes of images a recording of ``sessions`` holds (before
    rerun's own compression, which shrinks clean synthetic images far more than noisy real
    ones), and a hint at ``--jpeg-quality`` when raw images would pass :data:`LARGE_BYTES`."""
    total, raw = (sum(pair) for pair in zip(*(image_bytes(s, options.every) for s in sessions),
                                            strict=True))
    note = f"images to write: about {_size(total)} before compression"
    if options.jpeg_quality is not None and raw:
        note += f" (the raw ones as JPEG of quality {options.jpeg_quality})"
    elif raw > LARGE_BYTES:
        note += (f"; {_size(raw)} of raw images: --jpeg-quality 90 stores them as JPEG, "
                 "several times smaller, --every N keeps every N-th frame")
    return note


def _size(n: int) -> str:
    return f"{n / 1e9:.1f} GB" if n >= 1e9 else f"{n / 1e6:.0f} MB"


def _log_session(session: ExportSession, sink: RecordingSink, options: LoggerOptions,
                 bar: tqdm[Any]) -> tuple[SceneLogger, int]:
    """Log every message of ``session`` into ``sink``'s recording; the logger and how many
    messages it was given."""
    logger = SceneLogger(sink.rec, session.plan, options, decode=session.decode,
                         flush=sink.flush, columns=True)
    logger.log_static()
    count = 0
    try:
        for raw in session.messages():
            logger.log(raw)
            count += 1
            bar.update()
    finally:
        logger.close()
    return logger, count
