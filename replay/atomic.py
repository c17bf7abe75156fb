"""One way to write outputs atomically: a hidden, unique temporary sibling renamed into place.

Every output camlog writes (a log file or rosbag2 directory, an ``.rrd``, a calibration
folder, a YAML or JSON file) is first written under a temporary name next to its final
name, ``.NAME.camlog-<16 hex digits>.tmp``, and renamed to ``NAME`` only when it is
complete. The rules:

- a temporary name is hidden and unique to one run, so it can never be a user's file (nor
  another run's leftover: a recording killed mid-way leaves its temporary output, which
  still opens, and a later run never touches it);
- an output that is one of the run's inputs, lies inside one (a rosbag2 directory) or would
  replace a directory holding one is refused before anything is written;
- only what this run created is ever deleted: its own temporary output, and — with
  ``overwrite`` — the previous output under the final name, which the user asked to replace;
- a run about to write ``NAME`` says in one line which temporary outputs earlier runs left
  for it, and how to recover them (:mod:`replay.leftovers`).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterable
from pathlib import Path
from types import TracebackType
from typing import Self

from .errors import OutputError
from .leftovers import warn_leftovers
from .temp_names import is_temp_output, temp_output_of, temp_sibling

__all__ = [
    "AtomicFolder",
    "AtomicOutput",
    "check_not_input",
    "is_temp_output",
    "refuse_existing",
    "temp_output_of",
    "temp_sibling",
    "write_bytes_atomic",
    "write_text_atomic",
]

def _real(path: Path) -> Path:
    """Absolute path with symlinks resolved, for paths that may not exist yet."""
    return Path(os.path.realpath(path))


def check_not_input(output: Path, inputs: Iterable[Path]) -> None:
    """Refuse an output that is an input, lies inside one, or is a directory holding one."""
    out = _real(output)
    for given in inputs:
        source = _real(given)
        same = out == source
        if not same and out.exists() and source.exists():
            same = out.samefile(source)
        if same:
            raise OutputError(f"output {output} is the input {given}; choose another path")
        if source in out.parents:
            raise OutputError(f"output {output} lies inside the input {given}; "
                              "choose a path outside it")
        if out in source.parents:
            raise OutputError(f"output {output} holds the input {given}; choose another path")


def refuse_existing(final: Path, *, overwrite: bool, inputs: Iterable[Path] = ()) -> None:
    """Refuse an output that is an input (see :func:`check_not_input`), or that exists
    without ``overwrite``: the checks a command can make before its slow start-up."""
    check_not_input(final, inputs)
    if not overwrite and (final.exists() or final.is_symlink()):
        raise OutputError(f"{final} exists (pass --overwrite to replace it)")


def _check_parent(final: Path) -> None:
    parent = final.parent
    if parent.exists() and not parent.is_dir():
        raise OutputError(f"cannot write {final}: {parent} is not a directory")
    if not parent.is_dir():
        raise OutputError(f"cannot write {final}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise OutputError(f"cannot write {final}: directory {parent} is not writable")


def _remove(path: Path) -> None:
    """Delete a file or directory tree this run created."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    elif path.exists() or path.is_symlink():
        path.unlink(missing_ok=True)


def _never(_path: Path) -> bool:
    return False


class _Staged:
    """Commit when the ``with`` block succeeds, discard otherwise; OS errors name ``target``."""

    target: Path

    def commit(self) -> object:
        """Move the output into place."""
        raise NotImplementedError

    def discard(self) -> None:
        """Delete the temporary output."""
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        if et is None:
            try:
                self.commit()
            except OSError as err:
                self.discard()
                raise OutputError(f"cannot write {self.target}: {err.strerror or err}") \
                    from None
            except BaseException:  # Ctrl-C while moving into place
                self.discard()
                raise
        else:
            self.discard()


class AtomicOutput(_Staged):
    """A file or directory written under :attr:`temp` that replaces ``final`` on commit.

    ``temp`` does not exist yet: the writer creates it (a file, or a directory). An existing
    ``final`` is replaced only with ``overwrite``, and an existing directory only when
    ``replaceable_dir(final)`` says so (e.g. a rosbag2 log, not an arbitrary folder). As a
    context manager it commits when the block succeeds and discards otherwise.
    """

    def __init__(self, final: Path, *, overwrite: bool, inputs: Iterable[Path] = (),
                 replaceable_dir: Callable[[Path], bool] = _never,
                 what: str = "a log") -> None:
        self.final = self.target = final
        refuse_existing(final, overwrite=overwrite, inputs=inputs)
        if final.is_dir() and not final.is_symlink() and not replaceable_dir(final):
            raise OutputError(f"refusing to replace {final}: it is a directory but not "
                              f"{what}")
        _check_parent(final)
        warn_leftovers(final)
        self.temp = temp_sibling(final)
        self.done = False

    def commit(self, source: Path | None = None) -> None:
        """Move the output (``temp``, or ``source`` inside it) to the final name."""
        if self.done:
            return
        source = self.temp if source is None else source
        final = self.final
        present = final.exists() or final.is_symlink()
        if present and (source.is_dir() or (final.is_dir() and not final.is_symlink())):
            # a directory cannot be replaced in one rename: move the old one aside first
            old = temp_sibling(final)
            final.rename(old)
            source.rename(final)
            _remove(old)
        else:
            source.replace(final)
        if source != self.temp:
            _remove(self.temp)
        self.done = True

    def discard(self) -> None:
        """Delete the temporary output (only ever this run's own)."""
        if not self.done:
            self.done = True
            _remove(self.temp)


class AtomicFolder(_Staged):
    """Named files written into a temporary folder and moved into ``folder`` together.

    A folder that does not exist yet appears in one rename; into an existing one, each named
    file is replaced in one rename (other files in it are left alone). Existing files among
    ``names`` are replaced only with ``overwrite``.
    """

    def __init__(self, folder: Path, names: Iterable[str], *, overwrite: bool,
                 inputs: Iterable[Path] = ()) -> None:
        self.folder = self.target = folder
        self.names = list(names)
        inputs = list(inputs)
        # the folder may hold inputs (only the named files are replaced)
        check_not_input(folder, [p for p in inputs if _real(folder) not in _real(p).parents])
        for name in self.names:
            check_not_input(folder / name, inputs)
        if folder.exists() and not folder.is_dir():
            raise OutputError(f"output {folder} exists and is not a directory")
        existing = [n for n in self.names if (folder / n).exists()]
        if existing and not overwrite:
            raise OutputError(f"{folder} already holds {', '.join(existing)} "
                              "(pass --overwrite to replace them)")
        _check_parent(folder)
        warn_leftovers(folder)
        self.path = temp_sibling(folder)
        self.path.mkdir()
        self.done = False
        self.files: list[Path] = []  # final paths of the committed files

    def commit(self) -> list[Path]:
        """Move the written files into place; returns their final paths."""
        if self.done:
            return []
        written = sorted(item.name for item in self.path.iterdir())
        if not self.folder.exists():
            self.path.rename(self.folder)
        else:
            for name in written:
                (self.path / name).replace(self.folder / name)
            _remove(self.path)
        self.done = True
        self.files = [self.folder / name for name in written]
        return self.files

    def discard(self) -> None:
        """Delete the temporary folder (only ever this run's own)."""
        if not self.done:
            self.done = True
            _remove(self.path)


def write_bytes_atomic(path: Path, data: bytes, *, overwrite: bool = True,
                       inputs: Iterable[Path] = ()) -> None:
    """Write a small file in one piece: the old content or the new, never half of it."""
    output = AtomicOutput(path, overwrite=overwrite, inputs=inputs)
    try:
        output.temp.write_bytes(data)
        output.commit()
    except OSError as err:
        output.discard()
        raise OutputError(f"cannot write {path}: {err.strerror or err}") from None
    except BaseException:  # Ctrl-C: no temporary file stays
        output.discard()
        raise


def write_text_atomic(path: Path, text: str, *, overwrite: bool = True,
                      inputs: Iterable[Path] = ()) -> None:
    """Write a small text file (UTF-8) in one piece."""
    write_bytes_atomic(path, text.encode(), overwrite=overwrite, inputs=inputs)
