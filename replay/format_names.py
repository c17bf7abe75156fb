"""Names of the log formats camlog writes, without loading any format's library (for
argument parsers: ``--format`` choices)."""

from __future__ import annotations

__all__ = ["WRITE_FORMATS"]

#: ``--format`` names, in the order of :data:`replay.formats.FORMATS`
WRITE_FORMATS = ("mcap", "rosbag2", "rosbag2-sqlite3", "ros1")
