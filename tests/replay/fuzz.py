"""Seeded mutation of small valid logs, and what reading a mutant must do (test_fuzz.py).

Each format's seed log is written by camlog with a chunk (or commit) every two messages and
holds raw and JPEG images, camera info and text. A mutant is the seed with one damage done to
one of its files: bits flipped, the end cut off, a range zeroed, a length-sized field set to a
huge value (at the offsets of the format's own length fields half the time), a range
repeated, or — metadata.yaml of a rosbag2 folder — a line repeated, dropped or changed.
Reading a mutant goes the whole way a command does: open (with and without ``recover``),
summarize from the index and by reading every message, decode every message and frame.

Run as ``python -m tests.replay.fuzz FORMAT CASES SEED FOLDER``, it fuzzes in a fresh process
and prints its :class:`Tally` as JSON: the memory bound is on the process's peak virtual
memory (``VmPeak``), which counts every allocation (Python's, and C libraries' such as
SQLite, zstd or OpenCV) even where no page of it is touched, at no cost per allocation.
"""

from __future__ import annotations

import dataclasses
import json
import random
import shutil
import signal
import struct
import sys
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType

import numpy as np

from camlog.logs.info import summarize
from replay import CameraInfo, CompressedImage, Image, Text, open_reader, open_writer
from replay.errors import ReplayError
from replay.frames import decode_frame, encode_compressed

from .samples import T0_NS

#: fuzzed formats: name -> (writer format, output name, writer options)
SEEDS: dict[str, tuple[str, str, dict[str, str]]] = {
    "mcap": ("mcap", "seed.mcap", {}),
    "rosbag2 (mcap)": ("rosbag2", "seed", {}),
    "rosbag2 (sqlite3)": ("rosbag2-sqlite3", "seed", {}),
    "ros1": ("ros1", "seed.bag", {"compression": "none"}),
}
#: values a damaged length, offset or count field takes
HUGE = (0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFFFFFFFFFF, 0x7FFFFFFFFFFFFFFF, 1 << 40,
        1 << 33)


class Hang(BaseException):
    """A case ran past its time bound (a BaseException: readers' handlers do not catch it)."""


def write_seed(name: str, folder: Path) -> Path:
    """The valid log of one fuzzed format, written under ``folder``."""
    fmt, output, options = SEEDS[name]
    path = folder / output
    _write_seed(path, fmt, options)  # chunks (commits) by size only: the same bytes each time
    return path


def _write_seed(path: Path, fmt: str, options: dict[str, str]) -> None:
    rgb = np.random.default_rng(1).integers(0, 256, (6, 8, 3), dtype=np.uint8)
    jpeg = encode_compressed(decode_frame(Image(T0_NS, "cam", "rgb8", rgb)))
    info = CameraInfo(stamp_ns=T0_NS, frame_id="cam", width=8, height=6,
                      distortion_model="plumb_bob", d=np.zeros(5),
                      k=np.array([[10.0, 0, 3.5], [0, 10.0, 2.5], [0, 0, 1]]), r=np.eye(3),
                      p=np.array([[10.0, 0, 3.5, 0], [0, 10.0, 2.5, 0], [0, 0, 1, 0]]))
    with open_writer(path, fmt=fmt, **options) as writer:
        writer.write("/scenario", Text("name: fuzz"), log_time_ns=T0_NS)
        writer.write("/cam/camera_info", info)
        for index in range(6):
            stamp_ns = T0_NS + (index + 1) * 33_000_000
            pixels = np.random.default_rng(index).integers(0, 256, (6, 8), dtype=np.uint8)
            writer.write("/cam/image", Image(stamp_ns, "cam", "mono8", pixels))
            writer.write("/cam/compressed", CompressedImage(stamp_ns, "cam", jpeg.format,
                                                            jpeg.data))
            if index % 2:
                writer.flush()  # a chunk (a commit) every two frames


def length_offsets(data: bytes) -> list[tuple[int, int]]:
    """``(offset, size)`` of the length fields of an MCAP file's or a ROS1 bag's records,
    found by walking its top-level records (empty for other files)."""
    found: list[tuple[int, int]] = []
    if data.startswith(b"\x89MCAP0\r\n"):
        offset = 8
        while offset + 9 <= len(data):
            found.append((offset + 1, 8))
            (length,) = struct.unpack_from("<Q", data, offset + 1)
            offset += 9 + length
    elif data.startswith(b"#ROSBAG V2.0\n"):
        offset = 13
        while offset + 4 <= len(data):
            found.append((offset, 4))
            (header,) = struct.unpack_from("<I", data, offset)
            found += _ros1_header_fields(data, offset + 4, header)
            offset += 4 + header
            if offset + 4 > len(data):
                break
            found.append((offset, 4))
            offset += 4 + struct.unpack_from("<I", data, offset)[0]
    return found


def _ros1_header_fields(data: bytes, start: int, size: int) -> list[tuple[int, int]]:
    """Field-length prefixes and 4- and 8-byte values (sizes, counts, positions) of one
    ROS1 record header."""
    found: list[tuple[int, int]] = []
    offset = start
    while offset + 4 <= min(start + size, len(data)):
        (length,) = struct.unpack_from("<I", data, offset)
        found.append((offset, 4))
        name_end = data.find(b"=", offset + 4, offset + 4 + length)
        if name_end > 0 and offset + 4 + length - (name_end + 1) in (4, 8):
            found.append((name_end + 1, offset + 4 + length - (name_end + 1)))
        offset += 4 + length
    return found


def mutate_bytes(data: bytes, rng: random.Random) -> tuple[str, bytes]:
    """One damage done to a file's bytes: ``(kind, mutant)``."""
    size = len(data)
    buf = bytearray(data)
    kind = rng.choice(("flip", "truncate", "zero", "huge", "duplicate"))
    if kind == "flip":
        for _ in range(rng.randint(1, 8)):
            buf[rng.randrange(size)] ^= 1 << rng.randrange(8)
    elif kind == "truncate":
        del buf[rng.randrange(size):]
    elif kind == "zero":
        at = rng.randrange(size)
        end = min(size, at + rng.randint(1, 256))
        buf[at:end] = bytes(end - at)
    elif kind == "huge":
        fields = length_offsets(data)
        if fields and rng.random() < 0.5:
            at, width = rng.choice(fields)
        else:
            at, width = rng.randrange(max(1, size - 8)), rng.choice((4, 8))
        value = rng.choice(HUGE) & ((1 << (8 * width)) - 1)
        buf[at:at + width] = value.to_bytes(width, "little")
    else:
        at = rng.randrange(size)
        piece = data[at:at + rng.randint(1, 512)]
        where = rng.choice((at, at + len(piece), rng.randrange(size)))
        buf[where:where] = piece
    return kind, bytes(buf)


def mutate_yaml(text: str, rng: random.Random) -> tuple[str, str]:
    """One damage done to a metadata.yaml: a line repeated, dropped, cut or its value
    changed; ``(kind, mutant)``."""
    lines = text.splitlines(keepends=True)
    at = rng.randrange(len(lines))
    kind = rng.choice(("yaml-repeat", "yaml-drop", "yaml-cut", "yaml-value"))
    if kind == "yaml-repeat":
        lines.insert(at, lines[at])
    elif kind == "yaml-drop":
        del lines[at]
    elif kind == "yaml-cut":
        lines[at] = lines[at][:rng.randrange(len(lines[at]) + 1)]
    else:
        key, sep, _value = lines[at].partition(":")
        value = rng.choice(("", " -1", " 18446744073709551616", " 1e400", " nan", " []",
                            " {}", " ~", " 'x'", " [1, 2", " *a", " !!binary AAAA"))
        lines[at] = f"{key}{sep or ':'}{value}\n"
    return kind, "".join(lines)


def make_mutant(seed_path: Path, target: Path, rng: random.Random) -> str:
    """Copy the seed log to ``target`` with one damage done to one of its files; returns
    what was done (e.g. ``truncate seed.mcap``)."""
    if seed_path.is_dir():
        shutil.copytree(seed_path, target)
        files = sorted(p for p in target.iterdir() if p.is_file())
        victim = rng.choice(files)
    else:
        shutil.copyfile(seed_path, target)
        victim = target
    if victim.name == "metadata.yaml":
        kind, text = mutate_yaml(victim.read_text(), rng)
        victim.write_text(text)
    else:
        kind, data = mutate_bytes(victim.read_bytes(), rng)
        victim.write_bytes(data)
    return f"{kind} {victim.name}"


def read_everything(path: Path, *, recover: bool) -> None:
    """Everything commands do with a log: open, summarize (index and full read), decode
    every message and every frame."""
    with open_reader(path, recover=recover) as reader:
        summarize(reader)
        summarize(reader, verify=True)
        for _record in reader.messages():
            pass
        for _frame in reader.frames(skipped={}):
            pass


@dataclass
class Tally:
    """What the cases of one format ended in."""

    cases: int = 0
    read: int = 0  # read to the end without an error
    errors: int = 0  # ended in one camlog error line
    failures: list[str] = field(default_factory=list)  # tracebacks, hangs, memory
    peak_bytes: int = 0  # the most a case raised the process's peak virtual memory by


def vm_peak_bytes() -> int:
    """The process's peak virtual memory (Linux ``VmPeak``)."""
    with open("/proc/self/status") as status:  # noqa: PTH123 (a proc file, read once)
        for line in status:
            if line.startswith("VmPeak:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmPeak in /proc/self/status")


def _alarm(_signum: int, _frame: FrameType | None) -> None:
    raise Hang


def run_case(read: Callable[[], None], tally: Tally, label: str, *, time_s: float,
             memory_bytes: int) -> None:
    """Run one read under a time bound and a memory bound and count how it ended (the
    process's peak virtual memory may rise by at most ``memory_bytes``)."""
    tally.cases += 1
    base = vm_peak_bytes()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, time_s)
    try:
        read()
        tally.read += 1
    except ReplayError as err:
        text = str(err)
        if not text or "\n" in text:
            tally.failures.append(f"{label}: {type(err).__name__} not one line: {text!r}")
        else:
            tally.errors += 1
    except Hang:
        tally.failures.append(f"{label}: no answer in {time_s} s")
    except Exception as err:  # what the fuzzing looks for
        tally.failures.append(f"{label}: {type(err).__name__}: {err}")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    peak = vm_peak_bytes() - base
    tally.peak_bytes = max(tally.peak_bytes, peak)
    if peak > memory_bytes:
        tally.failures.append(f"{label}: {peak / 1e6:.0f} MB allocated")


def mutants(seed_path: Path, folder: Path, count: int, seed: int) -> Iterator[tuple[Path, str]]:
    """``count`` mutants of a seed log, each in its own subfolder of ``folder`` (removed
    when the next one is made)."""
    rng = random.Random(seed)
    for index in range(count):
        case = folder / f"case{index}"
        target = case / seed_path.name
        case.mkdir()
        what = make_mutant(seed_path, target, rng)
        yield target, f"case {index} ({what})"
        shutil.rmtree(case)


def fuzz(name: str, cases: int, seed: int, folder: Path, *, time_s: float,
         memory_bytes: int) -> Tally:
    """Read ``cases`` mutants of the seed log of format ``name`` (every other one with
    ``recover``) and count how they ended; Python warnings count as failures."""
    seed_folder = folder / "seed"
    seed_folder.mkdir()
    seed_path = write_seed(name, seed_folder)
    for recover in (False, True):  # start-up allocations (thread pools...) before measuring
        read_everything(seed_path, recover=recover)
    tally = Tally()
    work = folder / "cases"
    work.mkdir()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for index, (path, label) in enumerate(mutants(seed_path, work, cases, seed)):
            recover = index % 2 == 1
            run_case(lambda p=path, r=recover: read_everything(p, recover=r), tally,  # type: ignore[misc]
                     f"{name} {label}{' recover' if recover else ''}",
                     time_s=time_s, memory_bytes=memory_bytes)
    return tally


if __name__ == "__main__":
    fmt, count, number, where, bound_s, bound_bytes = sys.argv[1:]
    result = fuzz(fmt, int(count), int(number), Path(where), time_s=float(bound_s),
                  memory_bytes=int(bound_bytes))
    print(json.dumps(dataclasses.asdict(result)))
