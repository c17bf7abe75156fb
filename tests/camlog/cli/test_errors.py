"""Every package's errors reach the user as one line on stderr and exit status 1."""

from __future__ import annotations

from pathlib import Path

import pytest

from camlog import errors
from camlog.cli import main
from camlog.requests.fields import RequestError


@pytest.mark.parametrize(("argv", "needle"), [
    pytest.param(["calibrate", "{tmp}/x.mcap", "--size", "7x6", "--square", "0.01", "--left",
                  "/a"], "stereo needs both --left and --right", id="camlog"),
    pytest.param(["calibrate", "{tmp}/x.mcap", "--size", "1x6", "--square", "0.01",
                  "--camera", "/a"], "1x6", id="processors"),
    pytest.param(["info", "{tmp}/missing.mcap"], "does not exist", id="replay"),
    pytest.param(["record", "no_such_scenario", "-o", "{tmp}/x.mcap"], "no_such_scenario",
                 id="recorder"),
])
def test_one_line_per_error_tree(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                 argv: list[str], needle: str) -> None:
    code = main([a.format(tmp=tmp_path) for a in argv])
    out, err = capsys.readouterr()
    assert code == 1 and out == ""
    assert err.startswith(f"camlog {argv[0]}: error: ") and err.count("\n") == 1
    assert needle in err
    assert list(tmp_path.iterdir()) == []


def test_camlog_errors_form_one_tree() -> None:
    leaves = [errors.InputError, errors.UsageError, errors.CalibrationError,
              errors.ProcessingError, errors.SyncError, errors.PipelineError,
              errors.GoldenError, errors.ClusterError]
    assert all(issubclass(leaf, errors.CamlogError) for leaf in leaves)
    assert sorted(errors.__all__) == sorted([errors.CamlogError.__name__,
                                             *(leaf.__name__ for leaf in leaves)])
    assert issubclass(RequestError, errors.UsageError)  # declared with the requests
