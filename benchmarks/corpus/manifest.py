"""The corpus manifest (``manifest.toml``): typed entries, checked when read."""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

MANIFEST_PATH = Path(__file__).with_name("manifest.toml")
#: licences an entry may carry: SPDX ids, or none stated by the repository
LICENCES = frozenset({"CC-BY-4.0", "BSD-3-Clause", "Apache-2.0", "MIT", "none-stated"})
MODELS = frozenset({"plumb_bob", "rational_polynomial", "equidistant"})
PATTERNS = frozenset({"chessboard", "charuco", "circles", "acircles"})
REQUIRED = ("name", "description", "repo", "commit", "path", "licence", "licence_source",
            "model", "stereo", "board", "files")


class CorpusError(Exception):
    """A manifest entry, a fetched file or a cache that is not what the corpus expects."""


@dataclass(frozen=True)
class Board:
    """The target in a dataset; ``size`` in inner corners (circles: centres; ChArUco:
    squares) COLSxROWS; a ChArUco board's ``legacy_pattern``: its markers laid out as OpenCV
    before 4.6 did."""

    pattern: str
    size: str
    square_m: float
    square_source: str  # "published" or "assumed"
    note: str
    diameter_m: float | None = None
    marker_m: float | None = None
    dictionary: str | None = None
    legacy_pattern: bool = False

    @property
    def cols_rows(self) -> tuple[int, int]:
        """``(cols, rows)`` of ``size``."""
        cols, rows = (int(n) for n in self.size.split("x"))
        return cols, rows


@dataclass(frozen=True)
class Reference:
    """A calibration the source repository publishes (left camera first for a pair)."""

    source: str
    model: str
    fx: float
    fy: float
    cx: float
    cy: float
    right_fx: float | None = None
    right_cx: float | None = None
    baseline_m: float | None = None


@dataclass(frozen=True)
class Dataset:
    """One dataset: where it lives, under which licence, and how to calibrate it."""

    name: str
    description: str
    repo: str
    commit: str
    path: str
    licence: str
    licence_source: str
    model: str
    stereo: bool
    board: Board
    files: dict[str, str]  # path below ``path`` -> sha256
    reference: Reference | None = None

    @property
    def url(self) -> str:
        """The repository's https address."""
        return f"https://github.com/{self.repo}.git"


def default_cache() -> Path:
    """``$CAMLOG_CORPUS``, else ``~/.cache/camlog/corpus``."""
    return Path(os.environ.get("CAMLOG_CORPUS") or Path.home() / ".cache/camlog/corpus")


def _dataset(entry: dict[str, Any]) -> Dataset:
    name = entry.get("name", "?")
    missing = [key for key in REQUIRED if key not in entry]
    if missing:
        raise CorpusError(f"{MANIFEST_PATH}: dataset {name}: missing {', '.join(missing)}")
    if not re.fullmatch(r"[0-9a-f]{40}", entry["commit"]):
        raise CorpusError(f"{MANIFEST_PATH}: dataset {name}: commit is not a 40-digit sha")
    for key, allowed in (("licence", LICENCES), ("model", MODELS)):
        if entry[key] not in allowed:
            raise CorpusError(f"{MANIFEST_PATH}: dataset {name}: {key} {entry[key]!r} is not "
                              f"one of {sorted(allowed)}")
    board = Board(**entry["board"])
    if board.pattern not in PATTERNS or board.square_source not in {"published", "assumed"}:
        raise CorpusError(f"{MANIFEST_PATH}: dataset {name}: board {board}")
    files = dict(entry["files"])
    if not files or not all(re.fullmatch(r"[0-9a-f]{64}", h) for h in files.values()):
        raise CorpusError(f"{MANIFEST_PATH}: dataset {name}: files need a sha256 each")
    if entry["stereo"]:
        lefts = sorted(Path(f).name[4:] for f in files if Path(f).name.startswith("left"))
        rights = sorted(Path(f).name[5:] for f in files if Path(f).name.startswith("right"))
        if not lefts or lefts != rights or len(lefts) * 2 != len(files):
            raise CorpusError(f"{MANIFEST_PATH}: dataset {name}: stereo files must be "
                              "left*/right* pairs with the same rest of the name")
    reference = entry.get("reference")
    return Dataset(**{k: v for k, v in entry.items() if k not in {"board", "reference", "files"}},
                   board=board, files=files,
                   reference=Reference(**reference) if reference else None)


def load_manifest(path: Path = MANIFEST_PATH) -> list[Dataset]:
    """Every dataset of the manifest, each checked; names are unique."""
    with path.open("rb") as file:
        entries = tomllib.load(file).get("dataset", [])
    datasets = [_dataset(entry) for entry in entries]
    names = [d.name for d in datasets]
    if len(set(names)) != len(names):
        raise CorpusError(f"{path}: dataset names repeat")
    return datasets
