"""Log locations: local paths, ``file://`` URIs and object storage (``s3://``, ``gs://``, …).

Object storage goes through fsspec (optional: ``pip install 'camlog[cloud]'``, which brings
s3fs; ``gcsfs`` and others plug in the same way). A location is a :class:`~pathlib.Path`
or a string; strings with a scheme other than ``file`` are remote. Credentials and
endpoints come from each backend's usual configuration (for S3: ``AWS_*`` variables,
``AWS_ENDPOINT_URL`` for an S3-compatible server).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any, TypeVar

from .errors import StorageError

Location = str | Path
Result = TypeVar("Result")

#: read-ahead of a remote file: a range request fetches at least this much, so that an
#: MCAP reader's many small reads inside one chunk do not each become a request
BLOCK_SIZE = 4 * 1024 * 1024
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.-]*)://")


def scheme(location: Location) -> str:
    """URI scheme of a location (``""`` for a plain path)."""
    match = _SCHEME.match(str(location)) if isinstance(location, str) else None
    return match.group(1).lower() if match else ""


def is_remote(location: Location) -> bool:
    """True for a URI that is not a local file (``s3://…``, ``gs://…``, ``memory://…``)."""
    return scheme(location) not in ("", "file")


def local_path(location: Location) -> Path:
    """The local path of a plain path or a ``file://`` URI."""
    if is_remote(location):
        raise StorageError(f"{location} is not a local path")
    text = str(location)
    return Path(text[len("file://"):] if scheme(text) == "file" else text)


def local_paths(*locations: Location) -> list[Path]:
    """The local ones among ``locations``, as paths (the inputs an output must not replace:
    an object is never a local output)."""
    return [local_path(loc) for loc in locations if not is_remote(loc)]


def join(base: Location, *parts: str) -> Location:
    """``base/part/…`` for a path (a :class:`Path`) or a URI (a string)."""
    if not is_remote(base):
        return local_path(base).joinpath(*parts)
    return "/".join([str(base).rstrip("/"), *parts])


def _filesystem(uri: str) -> tuple[Any, str]:
    try:
        from fsspec.core import url_to_fs
    except ImportError:
        raise StorageError(f"{uri}: object storage needs fsspec "
                           "(pip install 'camlog[cloud]')") from None
    try:
        fs, path = url_to_fs(uri)
    except (ImportError, ValueError) as err:  # e.g. "Install s3fs to access S3"
        raise StorageError(f"{uri}: {_one_line(err)}") from None
    return fs, str(path)


def _one_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__


def _failed(uri: str, what: str, err: Exception) -> StorageError:
    return StorageError(f"cannot {what} {uri}: {type(err).__name__}: {_one_line(err)}")


@contextmanager
def _remote(uri: str, what: str, *, must_exist: bool = False) -> Iterator[tuple[Any, str]]:
    """The filesystem and path of ``uri``; what its backend raises inside becomes one
    :class:`StorageError` line: that it cannot ``what`` the URI, or with ``must_exist``, for
    a missing one, that it does not exist."""
    fs, path = _filesystem(uri)
    try:
        yield fs, path
    except FileNotFoundError as err:
        raise (StorageError(f"{uri} does not exist") if must_exist
               else _failed(uri, what, err)) from None
    except Exception as err:  # backends raise their own types (botocore, aiohttp, …)
        raise _failed(uri, what, err) from None


def _local_or_remote(location: Location, what: str, local: Callable[[Path], Result],
                     remote: Callable[[Any, str], Result], *, must_exist: bool = False) -> Result:
    """``local(path)`` for a local location, else ``remote(filesystem, path)`` inside
    :func:`_remote`."""
    if not is_remote(location):
        return local(local_path(location))
    with _remote(str(location), what, must_exist=must_exist) as (fs, path):
        result = remote(fs, path)
    return result


def open_remote(uri: str) -> IO[bytes]:
    """A seekable binary file on object storage, read with range requests."""
    with _remote(uri, "open", must_exist=True) as (fs, path):
        file: IO[bytes] = fs.open(path, "rb", block_size=BLOCK_SIZE, cache_type="readahead")
    return file


def is_dir(uri: str) -> bool:
    """True when a remote location is a folder (a prefix with objects below it)."""
    with _remote(uri, "look up") as (fs, path):
        found = bool(fs.isdir(path))
    return found


def exists(location: Location) -> bool:
    """True when a file or folder is at the location."""
    return _local_or_remote(location, "look up", Path.exists,
                            lambda fs, path: bool(fs.exists(path)))


def identity(location: Location) -> dict[str, int | str]:
    """What tells a log's content apart: bytes plus newest mtime (local) or ETags (remote).

    A folder (rosbag2) counts every file below it.
    """
    return _local_or_remote(location, "look up", _local_identity, _remote_identity,
                            must_exist=True)


def _local_identity(root: Path) -> dict[str, int | str]:
    files = [p for p in root.rglob("*") if p.is_file()] if root.is_dir() else [root]
    stats = [p.stat() for p in files]
    return {"bytes": sum(s.st_size for s in stats),
            "mtime_ns": max((s.st_mtime_ns for s in stats), default=0)}


def _remote_identity(fs: Any, path: str) -> dict[str, int | str]:
    infos = list(fs.find(path, detail=True).values()) if fs.isdir(path) else [fs.info(path)]
    tags = sorted(str(i.get("ETag") or i.get("etag") or i.get("md5Hash") or i.get("mtime")
                      or i.get("LastModified") or "") for i in infos)
    return {"bytes": sum(int(i.get("size") or 0) for i in infos), "etag": ",".join(tags)}


def size(location: Location) -> int:
    """Bytes of a file, or of all files below a folder."""
    return int(identity(location)["bytes"])


def download(uri: str, folder: Path) -> Path:
    """Copy a remote file or folder into ``folder``; the local copy's path."""
    with _remote(uri, "download", must_exist=True) as (fs, path):
        target = folder / (path.rstrip("/").rsplit("/", 1)[-1] or "log")
        if fs.isdir(path):
            fs.get(path.rstrip("/") + "/", str(target) + "/", recursive=True)
        else:
            fs.get(path, str(target))
    return target


def upload(folder: Path, uri: str) -> list[str]:
    """Copy every file below a local folder to the same names below ``uri``; their URIs."""
    done = []
    with _remote(uri, "upload to") as (fs, path):
        for file in sorted(p for p in folder.rglob("*") if p.is_file()):
            relative = file.relative_to(folder).as_posix()
            fs.put_file(str(file), f"{path.rstrip('/')}/{relative}")
            done.append(f"{uri.rstrip('/')}/{relative}")
    return done


def read_bytes(location: Location) -> bytes:
    """Whole content of a (small) file."""
    return _local_or_remote(location, "read", Path.read_bytes,
                            lambda fs, path: bytes(fs.cat_file(path)), must_exist=True)


def write_bytes(location: Location, data: bytes) -> None:
    """Write a (small) file whole: it appears complete or not at all.

    Locally through :mod:`replay.atomic`; an object store's single PUT is atomic.
    """
    def local(path: Path) -> None:
        from .atomic import write_bytes_atomic

        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(path, data)

    _local_or_remote(location, "write", local, lambda fs, path: fs.pipe_file(path, data))


def remove(location: Location) -> None:
    """Delete a file if it exists."""
    _local_or_remote(location, "delete", lambda path: path.unlink(missing_ok=True),
                     _remove_remote)


def _remove_remote(fs: Any, path: str) -> None:
    if fs.exists(path):
        fs.rm_file(path)


def expand(pattern: str) -> list[str]:
    """The URIs a remote pattern with ``*``, ``?`` or ``[…]`` names (sorted); others as given."""
    if not is_remote(pattern) or not any(c in pattern for c in "*?["):
        return [pattern]
    with _remote(pattern, "list") as (fs, path):
        found = sorted(fs.glob(path))
    if not found:
        raise StorageError(f"{pattern} matches nothing")
    prefix = pattern[: pattern.index("://") + 3]
    return [p if "://" in p else prefix + p.lstrip("/") for p in found]
