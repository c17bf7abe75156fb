"""Every registered processor end to end: ``camlog process``, a batch pipeline and ``view``.

Parametrized over the registry: a new processor is exercised here through the command
line, a pipeline step and the rerun export without editing this file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from processors.registry import SPECS
from processors.spec import OptionKind, OutputSpec, ProcessorSpec
from replay import CameraInfo, Image, open_reader, open_writer
from replay.calibration_yaml import save_calibration
from replay.display import Display
from replay.records import ProcessedOutputs
from replay.topics import PROCESSED
from rerun_export import view_logs
from tests.rrd import load_rrd

W, H, FRAMES = 48, 36, 3
K = np.array([[60.0, 0, 23.5], [0, 60.0, 17.5], [0, 0, 1]])
TOPIC = "/cam/image_raw"
COMPUTING = [spec for spec in SPECS if not spec.selects]


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A 48x36 rgb8 camera log with a red square (3 frames) and its calibration file."""
    tmp = tmp_path_factory.mktemp("every_processor")
    info = CameraInfo(0, "cam", W, H, "plumb_bob", np.array([-0.1, 0.02, 0, 0, 0]), K,
                      np.eye(3), np.hstack([K, np.zeros((3, 1))]))
    log = tmp / "tiny.mcap"
    with open_writer(log) as writer:
        for i in range(FRAMES):
            stamp = 1_000_000_000 + i * 100_000_000
            rgb = np.full((H, W, 3), 40, np.uint8)
            rgb[10 + i: 20 + i, 12:24] = (230, 10, 10)
            writer.write("/cam/camera_info", CameraInfo(stamp, "cam", W, H, "plumb_bob",
                                                        info.d, K, info.r, info.p))
            writer.write(TOPIC, Image(stamp, "cam", "rgb8", rgb))
    yaml = tmp / "cam.yaml"
    save_calibration(yaml, info, camera_name="cam")
    return log, yaml


def values(spec: ProcessorSpec, yaml: Path) -> dict[str, str]:
    """Required options as a user writes them: the calibration file, else the example."""
    return {o.name: str(yaml) if o.kind is OptionKind.CAMERA_INFO else o.example
            for o in spec.options if o.required}


def cli_flags(spec: ProcessorSpec, yaml: Path) -> list[str]:
    given = values(spec, yaml)
    flags = [spec.cli_flag] + ([given.pop(spec.primary)] if spec.primary else [])
    return flags + [word for name, value in given.items()
                    for word in (spec.option(name).cli_flag, value)]


def drawn(output: OutputSpec, entity: str, topic: str) -> tuple[str, str]:
    """(rerun entity, column) where ``view`` draws an output of the camera ``/cam``: its lens
    is distorted, so overlays of its raw image are drawn in its raw space, ``raw/cam``
    (``world/cam`` is its pinhole view)."""
    base = topic.removesuffix("/compressed").strip("/")
    return {
        Display.IMAGE: (f"/processed/{base}/image", "Image:buffer"),
        Display.RECTIFIED: (f"/rectified/{base}/image", "Image:buffer"),
        Display.MASK: (f"/raw/cam/{entity}", "SegmentationImage:buffer"),
        Display.EDGES: (f"/raw/cam/{entity}", "SegmentationImage:buffer"),
        Display.POINT_2D: (f"/raw/cam/{entity}", "Points2D:positions"),
        Display.SCALAR: (f"/metrics/{entity}/cam", "Scalars:scalars"),
        Display.POINT_SERIES: (f"/metrics/points/{base}", "Scalars:scalars"),
    }[output.display]


@pytest.mark.parametrize("spec", COMPUTING, ids=[s.name for s in COMPUTING])
def test_process_records_and_view_draws_every_output(spec: ProcessorSpec,
                                                     tiny: tuple[Path, Path],
                                                     tmp_path: Path) -> None:
    log, yaml = tiny
    out = tmp_path / "out.mcap"
    assert main(["process", str(log), "--topic", TOPIC, *cli_flags(spec, yaml),
                 "-o", str(out)]) == 0
    with open_reader(out) as reader:
        for output in spec.outputs:
            info = reader.topics[f"/cam/{output.name}"]
            assert (info.msgtype, info.count) == (output.msgtype, FRAMES)
        (record,) = [r.message for r in reader.messages([PROCESSED])]
    recorded = {o.output: o for o in ProcessedOutputs.from_message(record).outputs}
    assert set(recorded) == {o.name for o in spec.outputs}
    rec = load_rrd(view_logs([out], output=tmp_path / "out.rrd", progress=False).output
                   or tmp_path / "missing.rrd")
    for output in spec.outputs:
        mine = recorded[output.name]
        assert (mine.topic, mine.source, mine.processor) == (f"/cam/{output.name}", TOPIC,
                                                             spec.name)
        assert (mine.shown_as, mine.entity, mine.label) == (output.display,
                                                            spec.entity(output), output.label)
        entity, column = drawn(output, mine.entity, mine.topic)
        assert rec.count(entity, column) == FRAMES, (entity, sorted(rec.rows))


@pytest.mark.slow
def test_a_pipeline_runs_every_processor(tiny: tuple[Path, Path], tmp_path: Path) -> None:
    log, yaml = tiny
    steps = []
    for spec in COMPUTING:
        given = values(spec, yaml)
        value = f'"{given.pop(spec.primary)}"' if spec.primary else "true"
        if given:
            value = "{" + ", ".join(f'{k} = "{v}"' for k, v in given.items()) + "}"
        steps.append(f'[[steps]]\nrun = "process"\nname = "{spec.name}"\ninput = "log"\n'
                     f'topic = "{TOPIC}"\nevery = 2\n{spec.name} = {value}\n')
    pipeline = tmp_path / "every.toml"
    pipeline.write_text("\n".join(steps))
    out = tmp_path / "out"
    assert main(["batch", str(pipeline), str(log), "-o", str(out), "-j", "1",
                 "--no-progress"]) == 0
    for index, spec in enumerate(COMPUTING, start=1):
        with open_reader(out / "tiny" / f"{index:02d}_{spec.name}" / "processed.mcap") as reader:
            for output in spec.outputs:
                assert reader.topics[f"/cam/{output.name}"].count == 2  # frames 0 and 2
