"""Golden artifacts on disk and their comparison with tolerances.

An artifact is one golden output, named by its path below the expected folder
(``INPUT_STEM/JOB/FILE``); its kind follows from the suffix: ``.txt`` text (exact, shown as
a unified diff), ``.json`` and ``.yaml`` trees (strings and structure exact, numbers within
:data:`TOLERANCES`), ``.png`` images (RMS within :data:`TOLERANCES`; a failure writes the
expected, actual and difference images next to each other). In memory a text or YAML
artifact is a ``str``, a JSON artifact its decoded tree, an image an ``(H, W)`` or
``(H, W, 3)`` RGB uint8 array.
"""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import cv2
import numpy as np

from replay.atomic import write_bytes_atomic, write_text_atomic
from replay.bounded import json_loads, yaml_load

from ..errors import GoldenError
from .tolerances import tolerance_for

__all__ = [
    "Artifacts",
    "Difference",
    "artifacts_equal",
    "compare",
    "dumps_json",
    "read_artifact",
    "update",
    "write_artifact",
]

#: artifact name (``INPUT_STEM/JOB/FILE``) -> value
Artifacts = dict[str, Any]
#: differences reported per artifact before the rest are only counted
MAX_LINES = 8


@dataclass(frozen=True)
class Difference:
    """One way an artifact differs from its expected file; ``detail`` is e.g. a diff."""

    artifact: str
    what: str
    detail: str = ""

    def __str__(self) -> str:
        return f"{self.artifact}: {self.what}"


# --- reading and writing -------------------------------------------------------------------

def dumps_json(value: Any) -> str:
    """Indented JSON with lists of scalars and flat objects on one line (short git diffs)."""

    def flat(item: Any) -> bool:
        values = item.values() if isinstance(item, dict) else item
        return all(not isinstance(v, dict | list) for v in values)

    def render(item: Any, indent: str) -> str:
        if isinstance(item, dict | list) and (flat(item) or not item):
            return json.dumps(item, allow_nan=False)
        inner = indent + " "
        if isinstance(item, dict):
            rows = [f"{inner}{json.dumps(k)}: {render(v, inner)}" for k, v in item.items()]
            return "{\n" + ",\n".join(rows) + f"\n{indent}}}"
        if isinstance(item, list):
            return "[\n" + ",\n".join(inner + render(v, inner) for v in item) + f"\n{indent}]"
        return json.dumps(item, allow_nan=False)

    return render(value, "") + "\n"


def _read_png(path: Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise OSError(f"cannot read image {path}")
    return np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2RGB) if image.ndim == 3 else image)


def _write_png(path: Path, image: np.ndarray) -> None:
    bgr = cv2.cvtColor(image, cv2.COLOR_RGB2BGR) if image.ndim == 3 else image
    ok, png = cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:
        raise OSError(f"cannot encode image {path}")
    write_bytes_atomic(path, png.tobytes())


def _yaml_tree(name: str, text: str) -> Any:
    return yaml_load(text, name, GoldenError)


class _Kind(NamedTuple):
    read: Callable[[Path], Any]
    write: Callable[[Path, Any], None]
    compare: Callable[[str, Any, Any, Path | None], list[Difference]]


def read_artifact(path: Path) -> Any:
    """An expected artifact file as the value :func:`compare` takes."""
    return _kind(path.name).read(path)


def write_artifact(path: Path, value: Any) -> None:
    """Write an artifact value to ``path`` (folders created)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    _kind(path.name).write(path, value)


def _kind(name: str) -> _Kind:
    suffix = Path(name).suffix
    if suffix not in _KINDS:
        raise ValueError(f"{name}: golden artifacts are {', '.join(_KINDS)} files")
    return _KINDS[suffix]


# --- comparing -----------------------------------------------------------------------------

def _compare_text(name: str, expected: str, actual: str, _diff_dir: Path | None
                  ) -> list[Difference]:
    if expected == actual:
        return []
    diff = list(difflib.unified_diff(expected.splitlines(), actual.splitlines(),
                                     f"expected/{name}", f"actual/{name}", lineterm=""))
    changed = sum(1 for line in diff[2:] if line[:1] in "+-")
    return [Difference(name, f"text differs ({changed} lines added or removed)",
                       "\n".join(diff))]


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _tree_lines(name: str, key: str, expected: Any, actual: Any, out: list[str]) -> None:
    where = key or "(top)"
    if isinstance(expected, dict) and isinstance(actual, dict):
        for k in expected:
            sub = f"{key}.{k}" if key else str(k)
            if k not in actual:
                out.append(f"{sub}: missing (expected {_short(expected[k])})")
            else:
                _tree_lines(name, sub, expected[k], actual[k], out)
        out.extend(f"{key}.{k}: unexpected ({_short(actual[k])})" if key else
                   f"{k}: unexpected ({_short(actual[k])})" for k in actual if k not in expected)
    elif isinstance(expected, list) and isinstance(actual, list):
        if len(expected) != len(actual):
            out.append(f"{where}: expected {len(expected)} items, got {len(actual)}")
        for i, (e, a) in enumerate(zip(expected, actual, strict=False)):
            _tree_lines(name, f"{key}[{i}]", e, a, out)
    elif _is_number(expected) and _is_number(actual):
        tolerance = tolerance_for(f"{name}:{key}")
        if not tolerance.allows(expected, actual):
            out.append(f"{where}: expected {expected!r}, got {actual!r} (|diff| "
                       f"{abs(actual - expected):.3g} > {tolerance.describe()})")
    elif expected != actual or type(expected) is not type(actual):
        out.append(f"{where}: expected {_short(expected)}, got {_short(actual)}")


def _short(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, np.ndarray) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _capped(name: str, lines: list[str]) -> list[Difference]:
    out = [Difference(name, line) for line in lines[:MAX_LINES]]
    if len(lines) > MAX_LINES:
        out.append(Difference(name, f"... and {len(lines) - MAX_LINES} more differences"))
    return out


def _compare_json(name: str, expected: Any, actual: Any, _diff_dir: Path | None
                  ) -> list[Difference]:
    lines: list[str] = []
    _tree_lines(name, "", expected, actual, lines)
    return _capped(name, lines)


def _compare_yaml(name: str, expected: str, actual: str, diff_dir: Path | None
                  ) -> list[Difference]:
    return _compare_json(name, _yaml_tree(f"expected {name}", expected),
                         _yaml_tree(f"computed {name}", actual), diff_dir)


def _compare_png(name: str, expected: np.ndarray, actual: np.ndarray, diff_dir: Path | None
                 ) -> list[Difference]:
    if expected.shape != actual.shape or expected.dtype != actual.dtype:
        what = (f"image is {actual.dtype}{list(actual.shape)}, expected "
                f"{expected.dtype}{list(expected.shape)}")
        return [Difference(name, what + _write_diff_images(name, expected, actual, diff_dir))]
    delta = expected.astype(np.float64) - actual.astype(np.float64)
    rms = math.sqrt(float(np.mean(delta**2)))
    tolerance = tolerance_for(name)
    if rms <= tolerance.abs:
        return []
    changed = np.any(delta != 0, axis=-1) if delta.ndim == 3 else delta != 0
    what = (f"RMS {rms:.3f} {tolerance.unit} > {tolerance.abs:g} ({int(changed.sum())} of "
            f"{changed.size} pixels differ, max |diff| {int(np.abs(delta).max())})")
    return [Difference(name, what + _write_diff_images(name, expected, actual, diff_dir))]


def _write_diff_images(name: str, expected: np.ndarray, actual: np.ndarray,
                       diff_dir: Path | None) -> str:
    if diff_dir is None:
        return ""
    base = diff_dir / name.removesuffix(".png")
    write_artifact(base.with_name(base.name + ".expected.png"), expected)
    write_artifact(base.with_name(base.name + ".actual.png"), actual)
    if expected.shape == actual.shape:
        difference = cv2.absdiff(expected, actual)
        write_artifact(base.with_name(base.name + ".difference.png"), difference)
    return f"; wrote {base}.{{expected,actual,difference}}.png"


def _read_text(path: Path) -> str:
    return path.read_text()


def _write_text(path: Path, text: str) -> None:
    write_text_atomic(path, text)


def _read_json(path: Path) -> Any:
    return json_loads(path.read_text(), str(path), GoldenError)


def _write_json(path: Path, value: Any) -> None:
    write_text_atomic(path, dumps_json(value))


#: suffix -> how an artifact of that kind is read, written and compared
_KINDS: dict[str, _Kind] = {
    ".txt": _Kind(_read_text, _write_text, _compare_text),
    ".json": _Kind(_read_json, _write_json, _compare_json),
    ".yaml": _Kind(_read_text, _write_text, _compare_yaml),
    ".png": _Kind(_read_png, _write_png, _compare_png),
}


def _expected_names(expected_dir: Path, stems: Iterable[str]) -> list[str]:
    names = []
    for stem in stems:
        folder = expected_dir / stem
        if folder.is_dir():
            names += [p.relative_to(expected_dir).as_posix() for p in folder.rglob("*")
                      if p.is_file() and not p.name.startswith(".")]
    return sorted(names)


def _stems(artifacts: Artifacts) -> list[str]:
    return sorted({name.split("/", 1)[0] for name in artifacts})


def compare(expected_dir: Path, artifacts: Artifacts, diff_dir: Path | None = None, *,
            stems: Iterable[str] | None = None) -> list[Difference]:
    """Differences of ``artifacts`` from the files under ``expected_dir``.

    Only the inputs named by ``stems`` are compared (default: those the artifacts cover);
    an expected file without an artifact, or an artifact without an expected file, is a
    difference too. Image failures write their images to ``diff_dir`` when given.
    """
    stems = sorted(stems) if stems is not None else _stems(artifacts)
    expected_names = _expected_names(expected_dir, stems)
    differences: list[Difference] = []
    for name in expected_names:
        if name not in artifacts:
            differences.append(Difference(name, "expected file has no computed artifact"))
            continue
        expected = read_artifact(expected_dir / name)
        differences += _kind(name).compare(name, expected, artifacts[name], diff_dir)
    for name in sorted(set(artifacts) - set(expected_names)):
        if name.split("/", 1)[0] in stems:
            differences.append(Difference(name, "computed artifact has no expected file "
                                          "(camlog golden update adds it)"))
    return differences


def update(expected_dir: Path, artifacts: Artifacts, *,
           stems: Iterable[str] | None = None) -> list[str]:
    """Write the artifacts that differ from ``expected_dir`` and remove stale files.

    Files equal within tolerance are left alone, so an update never churns numbers that
    only moved by noise. Returns one line per added, changed (with its differences) and
    removed file, and a count of the unchanged ones.
    """
    stems = sorted(stems) if stems is not None else _stems(artifacts)
    existing = set(_expected_names(expected_dir, stems))
    lines: list[str] = []
    unchanged = 0
    for name in sorted(artifacts):
        path = expected_dir / name
        if name not in existing:
            write_artifact(path, artifacts[name])
            lines.append(f"added    {name}")
            continue
        changes = _kind(name).compare(name, read_artifact(path), artifacts[name], None)
        if not changes:
            unchanged += 1
            continue
        write_artifact(path, artifacts[name])
        lines.append(f"changed  {name}")
        for change in changes:
            lines.append(f"           {change.what}")
            lines += [f"           {line}" for line in change.detail.splitlines()]
    for name in sorted(existing - set(artifacts)):
        (expected_dir / name).unlink()
        lines.append(f"removed  {name}")
    lines.append(f"unchanged {unchanged} files (equal within tolerance)")
    return lines


def artifacts_equal(a: Artifacts, b: Artifacts) -> list[str]:
    """Names of the artifacts that are not bit-identical (or present in only one)."""
    differ = sorted(set(a) ^ set(b))
    for name in sorted(set(a) & set(b)):
        x, y = a[name], b[name]
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            same = isinstance(x, np.ndarray) and isinstance(y, np.ndarray) and \
                x.dtype == y.dtype and np.array_equal(x, y)
        else:
            same = type(x) is type(y) and x == y
        if not same:
            differ.append(name)
    return differ
