"""A long log made from a short recording repeated back to back (for cost-growth runs).

Every repetition shifts header stamps and log times by the recording's span plus one frame
period, so the result reads like one continuous recording ``TIMES`` times as long (the
scenario record is written once). Rendering 400 s of stereo would take most of an hour;
this takes seconds per minute of log.

    python -m benchmarks.longlog SOURCE OUTPUT --times N
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from replay import Text, open_reader, open_writer


def tile_log(source: Path, output: Path, times: int) -> None:
    """Write ``source`` ``times`` times in a row to ``output``, stamps shifted each time."""
    with open_reader(source) as reader:
        start_ns, end_ns = reader.start_ns or 0, reader.end_ns or 0
        frames = max(info.count for info in reader.topics.values())
        period_ns = (end_ns - start_ns) // max(frames - 1, 1)
        span_ns = end_ns - start_ns + period_ns
        with open_writer(output, overwrite=True) as writer:
            for k in range(times):
                shift_ns = k * span_ns
                for record in reader.messages():
                    message = record.message
                    if isinstance(message, Text):
                        if k == 0:
                            writer.write(record.topic, message, log_time_ns=record.log_time_ns)
                        continue
                    shifted = dataclasses.replace(message, stamp_ns=message.stamp_ns + shift_ns)
                    writer.write(record.topic, shifted, log_time_ns=record.log_time_ns + shift_ns)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", type=Path)
    parser.add_argument("output", type=Path)
    parser.add_argument("--times", type=int, required=True)
    args = parser.parse_args()
    tile_log(args.source, args.output, args.times)


if __name__ == "__main__":
    main()
