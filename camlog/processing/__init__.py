"""Streaming a log through processors (process, resync) into a new log."""
