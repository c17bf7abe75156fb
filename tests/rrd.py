"""Reading ``.rrd`` files back with rerun's own loader, and running the rerun CLI.

``Recording`` is what a test checks: per entity path, the archetypes logged there, the
number of rows of each component column and the component values.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rerun.chunk import RrdReader

#: columns whose values are pixel buffers: only their rows are counted
BULKY = (":buffer", ":blob")


@dataclass
class Recording:
    """The chunks of one recording store, summarised per entity and component column."""

    rows: dict[str, dict[str, int]] = field(default_factory=dict)  # entity -> column -> rows
    static: dict[str, set[str]] = field(default_factory=dict)  # entity -> static columns
    timelines: dict[str, set[str]] = field(default_factory=dict)  # entity -> timelines
    values: dict[tuple[str, str], list[Any]] = field(default_factory=dict)
    times: dict[tuple[str, str], list[int]] = field(default_factory=dict)  # ns per row
    blueprints: int = 0

    def count(self, entity: str, column: str) -> int:
        """Rows of ``column`` (e.g. ``Image:buffer``) at ``entity`` (0 when absent)."""
        return self.rows.get(entity, {}).get(column, 0)

    def entities_with(self, column: str) -> list[str]:
        return sorted(e for e, cols in self.rows.items() if column in cols)

    def time(self, entity: str, timeline: str) -> list[int]:
        """Times (ns) of the rows at ``entity`` on ``timeline``, in log order."""
        return self.times.get((entity, timeline), [])

    def column(self, entity: str, column: str) -> list[Any]:
        """Values of a (non-pixel) component column in log order, one list per row."""
        return self.values.get((entity, column), [])


def load_rrd(path: Path) -> Recording:
    """Load an .rrd with :class:`rerun.chunk.RrdReader` (rerun's loader)."""
    reader = RrdReader(path)
    (store,) = reader.recordings()
    out = Recording(blueprints=len(reader.blueprints()))
    for chunk in reader.stream(store=store):
        entity = chunk.entity_path
        batch = chunk.to_record_batch()
        out.timelines.setdefault(entity, set()).update(chunk.timeline_names)
        for timeline in chunk.timeline_names:
            stamps = batch.column(timeline).cast("int64").to_pylist()
            out.times.setdefault((entity, timeline), []).extend(stamps)
        rows = out.rows.setdefault(entity, {})
        for name in (n for n in batch.schema.names if ":" in n):
            column = batch.column(name)
            rows[name] = rows.get(name, 0) + len(column) - column.null_count
            if chunk.is_static:
                out.static.setdefault(entity, set()).add(name)
            if not name.endswith(BULKY):  # pixel buffers are only counted
                values = out.values.setdefault((entity, name), [])
                values.extend(v for v in column.to_pylist() if v is not None)
    return out


def rerun_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """Run the rerun CLI of this environment with its config and caches under ``cwd``."""
    exe = shutil.which("rerun", path=str(Path(sys.executable).parent)) or "rerun"
    home = cwd / "rerun_home"
    env = os.environ | {"HOME": str(home), "RERUN_CONFIG_DIR": str(home / "config")} | {
        f"XDG_{kind}_HOME": str(home / kind.lower()) for kind in ("CONFIG", "DATA", "CACHE")}
    return subprocess.run([exe, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=120, check=False)


class Receiver:
    """A headless ``rerun`` process that listens on a loopback port and saves what it
    receives to an .rrd: a stand-in for a live viewer in tests."""

    def __init__(self, folder: Path) -> None:
        import socket

        with socket.socket() as probe:  # a free loopback port
            probe.bind(("127.0.0.1", 0))
            self.port = probe.getsockname()[1]
        self.path = folder / "received.rrd"
        exe = shutil.which("rerun", path=str(Path(sys.executable).parent)) or "rerun"
        home = folder / "rerun_home"
        env = os.environ | {"HOME": str(home), "RERUN_CONFIG_DIR": str(home / "config")}
        # a session of its own: the `rerun` script runs the viewer binary as a child, and
        # stopping must end both
        self.process = subprocess.Popen(
            [exe, "--port", str(self.port), "--bind", "127.0.0.1", "--save", str(self.path)],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True)
        self._wait_listening()

    @property
    def url(self) -> str:
        return f"rerun+http://127.0.0.1:{self.port}/proxy"

    def _wait_listening(self, timeout_s: float = 20.0) -> None:
        import socket
        import time

        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", self.port)) == 0:
                    return
            time.sleep(0.05)
        self.stop()
        raise AssertionError(f"rerun did not listen on port {self.port}")

    def stop(self) -> None:
        """End the process group this receiver started (the script and the binary)."""
        import signal

        for sig in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(self.process.pid, sig)
            except ProcessLookupError:
                break
            try:
                self.process.wait(timeout=10)
                break
            except subprocess.TimeoutExpired:
                continue
