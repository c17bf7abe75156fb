"""Pipeline files: parsing, validation and step wiring."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from camlog.batch.pipeline import STEPS, load_pipeline, parse_pipeline
from camlog.errors import PipelineError
from replay.bounded import MAX_DEPTH, MAX_FILE_BYTES
from tests.conftest import REPO_ROOT

GOOD = """
[[steps]]
run = "resync"

[[steps]]
run = "calibrate"
size = "7x6"
square = 0.01
left = "/stereo_sync/left"
right = "/stereo_sync/right"

[[steps]]
run = "process"
name = "edges_on_input"
input = "log"
topic = "/unsynced/left/image_raw"
edges = {low = 40, high = 120}
"""


def test_toml_and_yaml_give_the_same_pipeline(tmp_path: Path) -> None:
    toml = tmp_path / "p.toml"
    toml.write_text(GOOD)
    yaml = tmp_path / "p.yaml"
    yaml.write_text(
        "steps:\n"
        "  - run: resync\n"
        "  - {run: calibrate, size: 7x6, square: 0.01, left: /stereo_sync/left,"
        " right: /stereo_sync/right}\n"
        "  - {run: process, name: edges_on_input, input: log, topic: /unsynced/left/image_raw,"
        " edges: {low: 40, high: 120}}\n"
    )
    a, b = load_pipeline(toml), load_pipeline(yaml)
    assert [(s.name, s.run, s.input, s.options) for s in a.steps] == \
        [(s.name, s.run, s.input, s.options) for s in b.steps]
    assert [s.input for s in a.steps] == ["previous", "previous", "log"]
    assert a.digest() == b.digest()


def test_digest_changes_with_any_option() -> None:
    import tomllib

    raw = tomllib.loads(GOOD)
    base = parse_pipeline(raw, "p").digest()
    raw["steps"][1]["square"] = 0.02
    assert parse_pipeline(raw, "p").digest() != base


@pytest.mark.parametrize(("text", "message"), [
    ("", "non-empty list"),
    ("[[steps]]\nsize = 1\n", "needs run"),
    ("[[steps]]\nrun = 'fly'\n", "unknown step 'fly'"),
    ("[[steps]]\nrun = 'resync'\nspeed = 3\n", "resync has no option 'speed'"),
    ("[[steps]]\nrun = 'resync'\ninput = 'calibrate'\n", "input 'calibrate'"),
    ("[[steps]]\nrun = 'resync'\n[[steps]]\nrun = 'resync'\n", "used twice"),
    ("steps = 3\n", "non-empty list"),
    ("[[steps]\n", "not valid TOML"),
])
def test_bad_pipelines_name_the_problem(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(PipelineError, match=message):
        load_pipeline(path)


def test_missing_pipeline_file(tmp_path: Path) -> None:
    with pytest.raises(PipelineError, match="does not exist"):
        load_pipeline(tmp_path / "none.toml")


def test_process_keys_come_from_the_registry() -> None:
    from camlog.batch.pipeline import STEPS
    from processors.registry import PROCESSORS

    keys = STEPS["process"].keys
    for spec in PROCESSORS.values():
        if spec.flag:
            assert spec.name in keys
        else:
            assert {o.name for o in spec.options} <= keys
    assert {"topic", "output_ns", "compress", "drop_input"} <= keys
    assert STEPS["throttle"].keys == {"topic", "every", "rate", "recover"}


@pytest.mark.parametrize(("options", "chosen"), [
    ({"edges": True}, [("edges", {"low": 50.0, "high": 150.0})]),
    ({"edges": {"low": 40, "high": 120}, "every": 3},
     [("edges", {"low": 40.0, "high": 120.0}), ("throttle", {"every": 3, "rate": None})]),
    ({"red_pixels": {"ratio": 5}, "edges": False}, [("red_pixels", {"ratio": 5})]),
])
def test_process_step_options_configure_processors(options: dict[str, object],
                                                   chosen: list[tuple[str, object]]) -> None:
    from camlog.batch.pipeline import step_processors
    from processors.registry import SPECS

    got = step_processors(dict(options), SPECS)
    assert [(c.name, dict(c.options)) for c in got] == chosen


@pytest.mark.parametrize(("options", "message"), [
    ({"edges": {"low": -1}}, "process: edges.low: must be >= 0"),
    ({"edges": {"low": 200, "high": 100}}, "process: edges.low, edges.high: Canny"),
    ({"edges": {"sigma": 1}}, "process: edges.sigma: no such option"),
    ({"red_pixels": "yes"}, "red_pixels must be true, false or a table"),
    ({"every": 0}, "process: every: must be >= 1"),
    ({"rectify": 3}, "process: rectify: expected a camera model"),
])
def test_process_step_option_errors_name_the_keys(options: dict[str, object],
                                                  message: str) -> None:
    from camlog.batch.pipeline import keys_worded, step_processors
    from processors.registry import SPECS

    with pytest.raises(PipelineError, match=message) as err, keys_worded("process", SPECS):
        for configured in step_processors(dict(options), SPECS):
            configured.build()
    assert "--" not in str(err.value)


def camlog_batch(pipeline: Path, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "camlog", "batch", str(pipeline),
                           str(tmp_path / "any.mcap"), "-o", str(tmp_path / "out")],
                          cwd=REPO_ROOT, capture_output=True, text=True, timeout=120,
                          check=False)


@pytest.mark.parametrize(("name", "text"), [
    ("deep.toml", "a = " + "[" * 3000 + "]" * 3000 + "\n"),
    ("dotted.toml", ".".join(["a"] * 3000) + " = 1\n"),
    ("deep.yaml", "a: " + "[" * 3000 + "]" * 3000 + "\n"),
    ("block.yaml", "- " * 3000 + "x\n"),
    ("aliases.yaml", "a: &a [1, *a]\n"),
])
def test_a_deeply_nested_pipeline_is_one_line(tmp_path: Path, name: str, text: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    result = camlog_batch(path, tmp_path)
    assert result.returncode == 1
    assert result.stderr.splitlines() == [
        f"camlog batch: error: pipeline file {path} nests lists or tables more than "
        f"{MAX_DEPTH} levels deep: refused"]


def test_a_pipeline_file_of_many_megabytes_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "huge.toml"
    path.write_text("# padding\n" * (MAX_FILE_BYTES // 10 + 1))
    result = camlog_batch(path, tmp_path)
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert f"pipeline file {path} is larger than 4 MiB" in line, line


def test_the_docs_and_the_docstring_list_every_step_and_its_keys() -> None:
    import camlog.batch.pipeline
    from camlog.batch.steps import keys_lines, keys_table

    page = (REPO_ROOT / "docs" / "batch.md").read_text()
    assert "\n".join(keys_table()) in page, "docs/batch.md: paste camlog.batch.steps.keys_table()"
    doc = camlog.batch.pipeline.__doc__ or ""
    assert "\n".join(keys_lines()) in doc, "pipeline.py: paste camlog.batch.steps.keys_lines()"
    for step in STEPS:
        assert f"| `{step}` |" in page and f"- {step}: " in doc


def test_a_request_error_found_when_the_step_runs_names_the_key(tmp_path: Path) -> None:
    from camlog.batch.pipeline import run_step

    (step,) = parse_pipeline({"steps": [{"run": "calibrate", "size": "7x6", "square": 0.01,
                                         "diameter": 0.005}]}, "p.toml").steps
    with pytest.raises(PipelineError) as err:
        run_step(step, tmp_path / "never_read.mcap", tmp_path / "out", 1)
    assert str(err.value) == ("calibrate: diameter belongs to circle grids (pattern circles "
                              "or acircles)")
