"""``camlog play``: replay a log in (scaled) real time, like ``ros2 bag play``.

Destinations: a live rerun viewer (``--spawn``, ``--connect``), an ``.rrd`` recording of the
replay, or a new log that receives each message when it is due, as a recorder listening to
the replay would. In a log output the header stamps and bytes are unchanged and the log time
is, by default, the wall-clock time the message was emitted (``log_time="replay"``);
``log_time="original"`` keeps the input's log times (shifted by a loop period per loop). In
rerun the recording has the ``log_time`` and ``header_stamp`` timelines of ``view`` plus
``replay_time`` (wall clock), which the viewer follows.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from tqdm import tqdm

from replay.atomic import check_not_input
from replay.errors import OptionError
from replay.format_names import LOG_TIMES
from replay.formats import open_writer
from replay.formats.base import LogWriter, RawMessage
from replay.pacing import Pacer, loop_period_ns
from rerun_export.blueprint import REPLAY_TIME, make_blueprint
from rerun_export.logger import LoggerOptions, SceneLogger
from rerun_export.sink import RecordingSink
from rerun_export.view import ExportSession, open_logs

from ..requests.play import PlayRequest

__all__ = ["LOG_TIMES", "REPLAY_TIME", "PlayResult", "play_log"]



class _Destination(Protocol):
    def emit(self, raw: RawMessage, wall_ns: int, shift_ns: int) -> None: ...


@dataclass(frozen=True)
class PlayResult:
    """What :func:`play_log` replayed: messages, loops, wall time and the worst lateness."""

    output: Path | None
    messages: int
    loops: int
    log_span_s: float
    wall_s: float
    late_s: float
    warnings: list[str] = field(default_factory=list)


class _LogDestination:
    """Writes each message to a log as it becomes due."""

    def __init__(self, writer: LogWriter, *, original: bool) -> None:
        self._writer = writer
        self._original = original
        self._last_ns = 0

    def emit(self, raw: RawMessage, wall_ns: int, shift_ns: int) -> None:
        if self._original:
            log_time = raw.log_time_ns + shift_ns
        else:
            log_time = self._last_ns = max(wall_ns, self._last_ns)  # never backwards
        self._writer.write_raw(RawMessage(raw.topic, raw.msgtype, log_time, raw.data,
                                          raw.serialization))


class _RerunDestination:
    """Logs each message to rerun with the replay's wall clock as a third timeline."""

    def __init__(self, logger: SceneLogger) -> None:
        self._logger = logger

    def emit(self, raw: RawMessage, wall_ns: int, shift_ns: int) -> None:
        self._logger.log(raw, replay_ns=wall_ns)


def _bounds_ns(session: ExportSession) -> tuple[int, int]:
    """First and last log time a replay can reach (the window cut to the logs)."""
    first = min(r.start_ns for r in session.readers if r.start_ns is not None)
    last = max(r.end_ns for r in session.readers if r.end_ns is not None)
    if session.start_ns is not None:
        first = max(first, session.start_ns)
    if session.end_ns is not None:
        last = min(last, session.end_ns - 1)
    return first, max(first, last)


def _loops(session: ExportSession, loops: int) -> Iterator[tuple[int, RawMessage]]:
    """``(shift_ns, raw)`` for every loop (``loops == 0``: forever)."""
    first, last = _bounds_ns(session)
    period = loop_period_ns(first, last, max(session.total, 1))
    k = 0
    while loops == 0 or k < loops:
        for raw in session.messages():
            yield k * period, raw
        k += 1


def play_log(request: PlayRequest, *, options: LoggerOptions | None = None,
             clock: Callable[[], float] = time.monotonic,
             sleep: Callable[[float], None] = time.sleep) -> PlayResult:
    """Replay the request's ``logs`` (merged like ``view``) at ``rate`` x real time, ``loop``
    times (0: until interrupted). ``output`` ending in ``.rrd`` is a rerun recording; any other
    output is a log (format from its name or ``format``). ``bind``, ``port``: where a
    spawned viewer listens."""
    paths, rate, start_s, end_s = request.logs, request.rate, request.start, request.end
    topics, loops, output, log_time = request.topics, request.loop, request.output, \
        request.log_time
    spawn, connect, bind, port = request.spawn, request.connect, request.bind, request.port
    fmt, overwrite, recover, progress = (request.format, request.overwrite, request.recover,
                                         request.progress)
    started = time.perf_counter()
    pacer = Pacer(rate, clock=clock, sleep=sleep)
    if loops < 0:
        raise OptionError(f"--loop takes a count >= 1 (or none: forever), got {loops}")
    if log_time not in LOG_TIMES:
        raise OptionError(f"log time must be {' or '.join(LOG_TIMES)}, got {log_time!r}")
    to_rerun = spawn or connect is not None or (output is not None and output.suffix == ".rrd")
    if output is None and not to_rerun:
        raise OptionError("choose where to play to: --spawn, --connect URL or -o OUT")
    if output is not None:
        check_not_input(output, paths)
    count = 0
    with contextlib.ExitStack() as stack:
        session = open_logs(stack, [Path(p) for p in paths], topics=topics, start_s=start_s,
                            end_s=end_s, recover=recover,
                            undistorted_scale=(options or LoggerOptions()).undistorted_scale)
        destination: _Destination
        logger: SceneLogger | None = None
        if to_rerun:
            blueprint = make_blueprint(session.plan, timeline=REPLAY_TIME, follow=True)
            sink = stack.enter_context(RecordingSink(
                output=output, connect=connect, spawn=spawn, overwrite=overwrite,
                blueprint=blueprint, bind=bind, port=port, inputs=paths))
            logger = SceneLogger(sink.rec, session.plan, options or LoggerOptions(),
                                 decode=session.decode, flush=sink.flush)
            logger.log_static()
            destination = _RerunDestination(logger)
        else:
            assert output is not None
            writer = stack.enter_context(open_writer(output, fmt=fmt, overwrite=overwrite,
                                                          inputs=paths, live=True))
            destination = _LogDestination(writer, original=log_time == "original")
        bar = stack.enter_context(tqdm(total=session.total * max(loops, 1) or None,
                                       unit="msg", desc="play", leave=False,
                                       disable=None if progress is None else not progress))
        wall_origin_ns = time.time_ns()
        clock_origin = clock()
        try:
            for shift_ns, raw in _loops(session, loops):
                pacer.wait(raw.log_time_ns + shift_ns)
                wall_ns = wall_origin_ns + round((clock() - clock_origin) * 1e9)
                destination.emit(raw, wall_ns, shift_ns)
                count += 1
                bar.update()
        except KeyboardInterrupt:
            if loops != 0:
                raise
            # an endless replay ends with Ctrl-C: keep what was played
        finally:
            if logger is not None:
                logger.close()
        warnings = [w for r in session.readers for w in r.warnings]
        if logger is not None:
            warnings += logger.warnings
        first, last = _bounds_ns(session)
    played = loops if loops else max(1, count // max(session.total, 1))
    return PlayResult(output, count, played, (last - first) / 1e9, time.perf_counter() - started,
                      pacer.late_s, warnings)
