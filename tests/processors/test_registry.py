"""The processor registry: every declaration honoured by its implementation; docstrings run.

Parametrized over the registry, so a new processor is checked here without editing this
file: its outputs match their declaration for every encoding the log layer reads.
"""

from __future__ import annotations

import doctest
import json
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

import processors.red_pixels
import processors.resync
from processors import PROCESSORS, ConfigError, OptionValueError, configure, make_processor
from processors.spec import Option, OptionKind, ProcessorSpec
from replay import IMAGE_ENCODINGS, CameraInfo, Image
from replay.frames import Frame, decode_frame
from replay.frames.raw import RAW_ENCODINGS
from replay.wire import msgtype_of

W, H = 32, 24
K = np.array([[50.0, 0, 15.5], [0, 50.0, 11.5], [0, 0, 1]])
CAMERA = CameraInfo(0, "", W, H, "plumb_bob", np.array([-0.1, 0.01, 0, 0, 0]), K, np.eye(3),
                    np.hstack([K, np.zeros((3, 1))]))
COMPUTING = sorted(name for name, spec in PROCESSORS.items() if not spec.selects)


def example(option: Option) -> Any:
    """A value for a required option: a camera for this test's image size, else the
    option's declared example."""
    if option.kind is OptionKind.CAMERA_INFO:
        return CAMERA
    assert option.example, f"required option {option.name} declares no example"
    return option.parse_text(option.example)


def sample_options(spec: ProcessorSpec) -> dict[str, Any]:
    return {o.name: example(o) for o in spec.options if o.required}


def red_square(encoding: str = "rgb8") -> Frame:
    rgb = np.zeros((H, W, 3), np.uint8)
    rgb[5:10, 5:10] = (255, 0, 0)
    return decode_frame(Image(42, "cam", encoding, rgb))


@pytest.mark.parametrize("name", COMPUTING)
def test_every_processor_writes_what_it_declares(name: str) -> None:
    spec = PROCESSORS[name]
    processor = make_processor(name, **sample_options(spec))
    outputs = processor(red_square())
    declared = {o.name: o.msgtype for o in spec.outputs}
    assert outputs and [n for n, _ in outputs] == [n for n in declared if n in dict(outputs)]
    assert {n for n, _ in outputs} == set(declared)  # a red square: every output has a value
    for output, message in outputs:
        assert declared[output] == msgtype_of(message)
        assert (message.stamp_ns, message.frame_id) == (42, "cam")  # type: ignore[union-attr]
    assert all(o.label and spec.entity(o) for o in spec.outputs)


@pytest.mark.parametrize("encoding", sorted(IMAGE_ENCODINGS))
@pytest.mark.parametrize("name", COMPUTING)
def test_every_encoding_the_log_layer_supports(name: str, encoding: str) -> None:
    dtype, channels = IMAGE_ENCODINGS[encoding]
    rows = int(H * RAW_ENCODINGS[encoding].rows)  # semi-planar YUV: chroma rows below
    shape = (rows, W) if channels == 1 else (rows, W, channels)
    top = 10.0 if dtype.kind == "f" else np.iinfo(dtype).max
    pixels = (np.random.default_rng(0).uniform(0, 1, shape) * top).astype(dtype)
    processor = make_processor(name, **sample_options(PROCESSORS[name]))
    outputs = processor(decode_frame(Image(1, "", encoding, pixels)))
    assert outputs and all(isinstance(m, Image) or msgtype_of(m) for _, m in outputs)


def test_throttle_selects_in_stream_order() -> None:
    throttle = configure("throttle", every=3).build()
    assert [throttle.keep(s) for s in range(7)] == [True, False, False, True, False, False,
                                                   True]
    assert PROCESSORS["throttle"].selects and not PROCESSORS["throttle"].outputs


def test_unknown_processor_and_option() -> None:
    with pytest.raises(ConfigError, match="red_pixels"):
        make_processor("blur")
    with pytest.raises(OptionValueError, match="low, high"):
        configure("edges", sigma=3)


@pytest.mark.parametrize(("name", "options", "at_fault"), [
    ("edges", {"low": -1.0}, ("low",)),
    ("edges", {"low": "x"}, ("low",)),
    ("edges", {"low": 200.0, "high": 100.0}, ("low", "high")),
    ("red_pixels", {"ratio": 2.5}, ("ratio",)),
    ("red_pixels", {"ratio": True}, ("ratio",)),
    ("rectify", {}, ("camera_info",)),
    ("rectify", {"camera_info": "ost.yaml"}, ("camera_info",)),
    ("throttle", {"every": 0}, ("every",)),
    ("throttle", {"rate": 0.0}, ("rate",)),
    ("throttle", {"every": 2, "rate": 5.0}, ("every", "rate")),
])
def test_bad_options_name_the_option_never_a_flag(name: str, options: dict[str, Any],
                                                   at_fault: tuple[str, ...]) -> None:
    with pytest.raises(OptionValueError) as err:
        make_processor(name, **options)
    assert err.value.processor == name and err.value.options == at_fault
    assert "--" not in str(err.value)


def test_defaults_are_filled_in_and_valid() -> None:
    for spec in PROCESSORS.values():
        configured = spec.configure(sample_options(spec))
        assert set(configured.options) == {o.name for o in spec.options}
        for option in spec.options:
            if option.default is not None:
                assert option.problem(option.default) is None, (spec.name, option.name)
        json.dumps(configured.described_options())  # the record holds them as JSON


def test_flags_and_pipeline_keys_are_unique() -> None:
    from camlog.cli import build_parser

    flags = [s.cli_flag for s in PROCESSORS.values() if s.flag]
    flags += [o.cli_flag for s in PROCESSORS.values() for o in s.options if o.name != s.primary]
    assert len(flags) == len(set(flags))
    keys = [s.name for s in PROCESSORS.values() if s.flag]
    keys += [o.name for s in PROCESSORS.values() if not s.flag for o in s.options]
    assert len(keys) == len(set(keys))
    build_parser()  # argparse refuses a flag that clashes with the command's own


@pytest.mark.slow
def test_declarations_load_no_numerical_library() -> None:
    """The registry is read to build the command line: it must not import OpenCV, numpy or
    rerun beyond what the log layer itself imports."""
    code = ("import json, sys; import replay; before = set(sys.modules); "
            "import processors.registry, processors.spec, replay.display; "
            "print(json.dumps(sorted(set(sys.modules) - before))); "
            "print('rerun' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    added = set(json.loads(out[0]))
    assert "processors.registry" in added
    assert not {m for m in added if m.split(".")[0] in {"cv2", "numpy", "rerun"}}
    assert out[1] == "False"
    assert not any(m.startswith(("processors.edges", "processors.red_pixels",
                                 "processors.rectify")) for m in added)


@pytest.mark.parametrize("module", [processors.red_pixels, processors.resync])
def test_docstring_examples(module: object) -> None:
    result = doctest.testmod(module)  # type: ignore[arg-type]
    assert result.attempted > 0 and result.failed == 0
