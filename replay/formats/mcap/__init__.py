"""MCAP files: the reader (:mod:`.reader`, with the damage checks, chunk ordering and index
it reads through) and the writer (:mod:`.writer`, chunks finished on a worker thread by
:mod:`.chunks`)."""

from .reader import MAGIC, McapLogReader, is_mcap

__all__ = ["MAGIC", "McapLogReader", "is_mcap"]
