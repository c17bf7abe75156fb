"""Time offsets between cameras measured from what they saw: a moving board
(:mod:`.board`) or natural features of a moving rig (:mod:`.features`)."""

from .board import BoardTrack, estimate_board_offset
from .estimate import NotObservableError, OffsetEstimate

__all__ = ["BoardTrack", "NotObservableError", "OffsetEstimate", "estimate_board_offset"]
