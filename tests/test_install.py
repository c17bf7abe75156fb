"""What an installed camlog finds without its checkout: scenarios and golden data ship in
the wheel; the golden commands that rewrite the committed files need a checkout and say so.
(`.ci/wheel-smoke` builds the wheel, installs it in a fresh venv and runs it for real.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from camlog.cli import main
from camlog.golden import run as golden


def test_this_checkout_is_recognised() -> None:
    assert golden.in_checkout()
    assert (golden.golden_dir() / golden.MANIFEST).is_file()


@pytest.mark.parametrize("action", ["update", "record"])
def test_rewriting_goldens_outside_a_checkout_is_refused_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
    action: str,
) -> None:
    installed = tmp_path / "site-packages" / "camlog_datasets" / "golden"
    installed.mkdir(parents=True)
    monkeypatch.setattr(golden, "golden_dir", lambda: installed)
    assert main(["golden", action]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "run it in a camlog checkout" in err and "datasets/golden" in err
    assert list(installed.iterdir()) == []


def test_the_wheel_ships_the_golden_data() -> None:
    import tomllib

    root = Path(__file__).resolve().parents[1]
    data = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["camlog_datasets"]
    datasets = root / "datasets"
    shipped = {p for pattern in data for p in datasets.glob(pattern) if p.is_file()}
    golden_files = {p for p in (datasets / "golden").rglob("*") if p.is_file()}
    assert golden_files
    assert golden_files <= shipped, sorted(golden_files - shipped)
