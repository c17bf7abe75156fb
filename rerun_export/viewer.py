"""Live rerun viewers: addresses, reaching one, and starting one for ``--spawn``.

camlog starts the viewer itself rather than through ``rerun.spawn``, for two reasons: the
viewer listens on 127.0.0.1 unless asked otherwise (rerun's default is every interface),
and a viewer that cannot start (no display, no GPU) is reported within seconds, with the
viewer's own reason, instead of leaving the recording waiting for it.
"""

from __future__ import annotations

import os
import re
import socket
import ssl
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from urllib.parse import urlsplit

from .errors import ViewerError

__all__ = ["DEFAULT_PORT", "LOCALHOST", "grpc_url", "require_viewer", "spawn_viewer"]

DEFAULT_PORT = 9876
LOCALHOST = "127.0.0.1"
#: how long a viewer may take to accept a connection, and then to answer its greeting
CONNECT_S = 5.0
ANSWER_S = 5.0
#: HTTP/2's client preface and an empty SETTINGS frame, to which a server answers with its
#: own SETTINGS frame (a 9-byte frame header first)
_HTTP2_GREETING = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
_FRAME_HEADER_BYTES = 9
#: a viewer that is not listening this long after it was started is not going to
SPAWN_TIMEOUT_S = 20.0
#: a viewer listens before it opens its window: it must still run this long after
SETTLE_S = 1.5
_SCHEMES = ("rerun://", "rerun+http://", "rerun+https://")
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def grpc_url(text: str) -> str:
    """A viewer address: ``rerun+http://host:port/proxy``, or ``host:port`` for short.

    >>> grpc_url("127.0.0.1:9876")
    'rerun+http://127.0.0.1:9876/proxy'
    """
    if text.startswith(_SCHEMES):
        return text
    host, _, port = text.rpartition(":")
    if host and port.isdigit():
        return f"rerun+http://{host}:{port}/proxy"
    raise ViewerError(f"not a viewer address: {text!r} (use rerun+http://HOST:PORT/proxy or "
                      "HOST:PORT)")


def require_viewer(url: str, *, connect_s: float = CONNECT_S,
                   answer_s: float = ANSWER_S) -> None:
    """Fail early, with the address, when nothing at ``url`` accepts a connection within
    ``connect_s`` and answers an HTTP/2 greeting (as a viewer's gRPC server does at once)
    within ``answer_s``: rerun itself would buffer the recording for a server that never
    answers, and drop it silently where none listens."""
    parts = urlsplit(url.replace("rerun+", "", 1).replace("rerun://", "https://", 1))
    host, port = parts.hostname or LOCALHOST, parts.port or DEFAULT_PORT
    try:
        connection = socket.create_connection((host, port), timeout=connect_s)
    except TimeoutError:
        raise ViewerError(f"no rerun viewer answers at {url}: connecting took longer than "
                          f"{connect_s:g} s") from None
    except OSError as err:
        raise ViewerError(f"no rerun viewer is listening at {url} ({err.strerror or err}); "
                          "start one with `rerun` or use --spawn") from None
    try:
        connection.settimeout(answer_s)
        if parts.scheme == "https":
            context = ssl.create_default_context()
            context.check_hostname, context.verify_mode = False, ssl.CERT_NONE  # rerun checks
            context.set_alpn_protocols(["h2"])
            connection = context.wrap_socket(connection, server_hostname=host)
        connection.sendall(_HTTP2_GREETING)
        answer = connection.recv(_FRAME_HEADER_BYTES)
    except TimeoutError:
        raise ViewerError(f"the rerun viewer at {url} accepted the connection but did not "
                          f"answer within {answer_s:g} s") from None
    except OSError as err:
        answer = b""
        why = f" ({err.strerror or err})"
    else:
        why = ""
    finally:
        connection.close()
    if not answer:
        raise ViewerError(f"the rerun viewer at {url} closed the connection without "
                          f"answering{why}")


def _listening(host: str, port: int) -> bool:
    try:
        socket.create_connection((host, port), timeout=0.5).close()
    except OSError:
        return False
    return True


def _has_display() -> bool:
    if sys.platform != "linux":
        return True  # macOS and Windows viewers open windows without a display variable
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _reason(log: Path) -> str:
    """The viewer's own explanation: the last error or panic line of its log."""
    try:
        lines = [_ANSI.sub("", line).strip() for line in log.read_text(errors="replace")
                 .splitlines()]
    except OSError:
        return "no log"
    for line in reversed(lines):
        if line.startswith("Error:") or "panicked at" in line or " ERROR " in line:
            return line[:300]
    return next((line[:300] for line in reversed(lines) if line), "nothing logged")


def spawn_viewer(*, bind: str = LOCALHOST, port: int = DEFAULT_PORT,
                 timeout_s: float = SPAWN_TIMEOUT_S) -> str:
    """Start a rerun viewer listening on ``bind:port`` (or use the one already there) and
    return the URL to send to; :class:`ViewerError` when it cannot start."""
    host = LOCALHOST if bind in ("0.0.0.0", "::", "") else bind
    url = f"rerun+http://{host}:{port}/proxy"
    if _listening(host, port):
        return url  # a viewer is running there: rerun.spawn would reuse it as well
    if not _has_display():
        raise ViewerError("cannot start a rerun viewer: there is no display (DISPLAY and "
                          "WAYLAND_DISPLAY are unset); write an .rrd with -o, or --connect "
                          "to a viewer that runs elsewhere")
    with tempfile.NamedTemporaryFile(prefix="camlog-viewer-", suffix=".log",
                                     delete=False) as log:
        # the viewer logs at its own default level unless the user chose one
        env = {k: v for k, v in os.environ.items() if (k, v) != ("RUST_LOG", "off")}
        process = subprocess.Popen(
            [sys.executable, "-m", "rerun", "--port", str(port), "--bind", bind,
             "--memory-limit", "75%"],
            stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, env=env,
            start_new_session=True)  # the viewer outlives camlog, as with rerun.spawn
    log_path = Path(log.name)
    deadline = time.monotonic() + timeout_s
    listening_since: float | None = None
    while time.monotonic() < deadline:
        status = process.poll()
        if status is not None:
            raise ViewerError(f"the rerun viewer stopped at start-up (exit status {status}): "
                              f"{_reason(log_path)} (its log: {log_path})")
        if listening_since is None and _listening(host, port):
            listening_since = time.monotonic()
        if listening_since is not None and time.monotonic() - listening_since >= SETTLE_S:
            log_path.unlink(missing_ok=True)  # the viewer keeps writing to its open file
            return url
        time.sleep(0.1)
    process.kill()
    process.wait()
    raise ViewerError(f"the rerun viewer did not start within {timeout_s:g} s: "
                      f"{_reason(log_path)} (its log: {log_path})")
