"""The log fixtures of the log layer's tests, shared with the commands over whole logs."""

from tests.replay.conftest import log_path, sample_entries

__all__ = ["log_path", "sample_entries"]
