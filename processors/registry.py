"""Processor name -> factory; a new processor is one module plus one entry here."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .base import Processor
from .edges import Edges
from .errors import ConfigError
from .rectify import Rectifier
from .red_pixels import RedPixels

#: name -> factory taking the processor's keyword options
PROCESSORS: dict[str, Callable[..., Processor]] = {
    RedPixels.name: RedPixels,
    Edges.name: Edges,
    Rectifier.name: Rectifier,
}


def make_processor(name: str, **options: Any) -> Processor:
    """Build a registered processor with its options."""
    if name not in PROCESSORS:
        raise ConfigError(f"unknown processor {name!r} (known: {', '.join(PROCESSORS)})")
    return PROCESSORS[name](**options)
