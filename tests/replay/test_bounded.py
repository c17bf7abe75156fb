"""Bounded parsing: text nested deeper than MAX_DEPTH, or larger than its limit, is refused
with the caller's error naming the input, before any parser recurses through it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from replay.bounded import (
    MAX_DEPTH,
    check_depth,
    json_loads,
    read_text,
    reindent_json,
    toml_loads,
    yaml_load,
)
from replay.formats import open_reader, open_writer
from replay.messages import Text
from replay.topics import CameraTopics
from tests.conftest import REPO_ROOT


class RefusedError(Exception):
    pass


DEEP = 3000
TOO_DEEP = f"nests lists or tables more than {MAX_DEPTH} levels deep"


@pytest.mark.slow
@pytest.mark.parametrize(("load", "text"), [
    (toml_loads, "a = " + "[" * DEEP + "]" * DEEP),
    (toml_loads, "a = " + "{b = " * DEEP + "1" + "}" * DEEP),
    (toml_loads, ".".join(["a"] * DEEP) + " = 1"),
    (toml_loads, "[" + ".".join(["a"] * DEEP) + "]"),
    (yaml_load, "a: " + "[" * DEEP + "]" * DEEP),
    (yaml_load, "- " * DEEP + "x"),
    (yaml_load, "a: &a [1, *a]"),  # holds itself
    (yaml_load, "\n".join(  # each alias one level deeper than the last
        [f"a0: &a0 {'[' * 40}1{']' * 40}"]
        + [f"a{i}: &a{i} {'[' * 40}*a{i - 1}{']' * 40}" for i in range(1, 4)])),
    (json_loads, "[" * DEEP + "]" * DEEP),
    (json_loads, '{"a": ' * DEEP + "1" + "}" * DEEP),
])
def test_deep_text_is_refused_with_its_name(load: object, text: str) -> None:
    with pytest.raises(RefusedError, match=f"^the input {TOO_DEEP}: refused$"):
        load(text, "the input", RefusedError)  # type: ignore[operator]


@pytest.mark.parametrize(("load", "text", "value"), [
    (toml_loads, 'a = "[[[[" # [[[[\nb = [[1, 2]]\n', {"a": "[[[[", "b": [[1, 2]]}),
    (toml_loads, "a = '''\n[[[[\n'''\n", {"a": "[[[[\n"}),
    (yaml_load, "a: '[[[['\nb: &x [1]\nc: [*x, *x]\n", {"a": "[[[[", "b": [1], "c": [[1], [1]]}),
    (json_loads, '{"a": "[[[[\\"[[", "b": [[1]]}', {"a": '[[[["[[', "b": [[1]]}),
])
def test_brackets_in_strings_and_shared_parts_are_fine(load: object, text: str,
                                                       value: object) -> None:
    assert load(text, "the input", RefusedError) == value  # type: ignore[operator]


def test_exactly_the_limit_is_accepted() -> None:
    deepest = "[" * MAX_DEPTH + "]" * MAX_DEPTH
    assert json_loads(deepest, "x", RefusedError) is not None
    with pytest.raises(RefusedError):
        json_loads("[" + deepest + "]", "x", RefusedError)
    nested: list[object] = []
    for _ in range(MAX_DEPTH - 1):
        nested = [nested]
    check_depth(nested, "x", RefusedError)
    with pytest.raises(RefusedError):
        check_depth([nested], "x", RefusedError)


def test_billion_laughs_is_walked_in_linear_time() -> None:
    text = "\n".join(["a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"]
                     + [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 9)])
    assert len(yaml_load(text, "x", RefusedError)["a8"]) == 10


def test_size_limits(tmp_path: Path) -> None:
    with pytest.raises(RefusedError, match=r"^big is larger than 100 bytes: refused$"):
        json_loads("[" + "1," * 100 + "1]", "big", RefusedError, max_bytes=100)
    path = tmp_path / "a.toml"
    path.write_text("x = 1\n" * 100)
    with pytest.raises(RefusedError, match=f"^spec {path} is larger than"):
        read_text(path, RefusedError, what="spec", max_bytes=599)
    assert read_text(path, RefusedError, max_bytes=600) == "x = 1\n" * 100
    with pytest.raises(RefusedError, match="does not exist"):
        read_text(tmp_path / "none", RefusedError)


def test_reindent_json_shows_only_bounded_json() -> None:
    assert reindent_json('{"a": [1]}') == '{\n "a": [\n  1\n ]\n}'
    assert reindent_json("not json") is None
    assert reindent_json("[" * DEEP + "]" * DEEP) is None


def camlog(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "camlog", *args], cwd=REPO_ROOT,
                          capture_output=True, text=True, timeout=120, check=False)


@pytest.mark.slow
def test_a_deep_json_manifest_is_one_line(tmp_path: Path) -> None:
    manifest = tmp_path / "manifest.json"
    manifest.write_text('{"inputs": ' + "[" * DEEP + "]" * DEEP + "}")
    result = camlog("golden", "check", "--inputs", str(tmp_path))
    assert result.returncode == 1
    assert result.stderr.splitlines() == [f"camlog golden: error: {manifest} {TOO_DEEP}: refused"]


@pytest.mark.slow
def test_a_deep_scenario_spec_is_one_line(tmp_path: Path) -> None:
    spec = tmp_path / "deep.toml"
    spec.write_text("seed = " + "[" * DEEP + "]" * DEEP + "\n")
    result = camlog("record", str(spec), "-o", str(tmp_path / "out.mcap"), "--frames", "1")
    assert result.returncode == 1
    assert result.stderr.splitlines() == [f"camlog record: error: {spec} {TOO_DEEP}: refused"]


@pytest.mark.slow
def test_a_deep_json_record_in_a_log_is_left_out_with_a_warning(red_log: Path,
                                                                tmp_path: Path) -> None:
    residuals = CameraTopics("/stereo_camera/left").residuals
    log = tmp_path / "deep.mcap"
    with open_reader(red_log) as reader, open_writer(log) as writer:
        for raw in reader.raw_messages():
            writer.write_raw(raw)
        writer.write(residuals, Text("[" * DEEP + "]" * DEEP),
                     log_time_ns=reader.start_ns or 0)
    result = camlog("view", str(log), "-o", str(tmp_path / "out.rrd"), "--no-progress")
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    (warning,) = [line for line in result.stderr.splitlines() if residuals in line]
    assert f"residuals record {TOO_DEEP}: refused" in warning
