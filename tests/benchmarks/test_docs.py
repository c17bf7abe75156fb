"""Benchmark tables written into the docs: a block between markers is replaced, a
benchmark's rows of a shared table are replaced and nothing else, and a page without the
markers is one error line with the page left as it was."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from benchmarks import report
from benchmarks.docs import (
    PAGE,
    TABLES,
    DocsTableError,
    markdown_table,
    replace_rows,
    replace_table,
    write_rows,
    write_table,
)

PAGE_TEXT = """# Figures

Before.

<!-- table: speed -->

| benchmark | figure |
| --- | --- |
| `a`: first | 1 |
| `b`: second | 2 |
| `a`: third | 3 |

<!-- /table: speed -->

<!-- table: cases -->

| case | figure | value |
| --- | --- | --- |
| `x`: one | fx | 1 |
| | cx | 2 |
| `y`: two | fx | 3 |
| | cx | 4 |

<!-- /table: cases -->

After.
"""


def test_a_table_between_its_markers_is_replaced_and_nothing_else() -> None:
    new = replace_table(PAGE_TEXT, "speed", markdown_table(["benchmark", "figure"], [["c", "9"]]))
    assert "| c | 9 |" in new
    assert "| `a`: first | 1 |" not in new and "| `b`: second | 2 |" not in new
    before, _, after = PAGE_TEXT.partition("<!-- table: speed -->")
    assert new.startswith(before) and new.endswith(after.partition("<!-- /table: speed -->")[2])
    assert replace_table(new, "speed", markdown_table(["benchmark", "figure"], [["c", "9"]])) \
        == new


def test_a_benchmarks_rows_are_replaced_where_they_were_and_the_others_stay() -> None:
    new = replace_rows(PAGE_TEXT, "speed", "`a`:", ["| `a`: new | 7 |"])
    table = new.split("<!-- table: speed -->")[1].split("<!-- /table: speed -->")[0]
    rows = [line for line in table.splitlines() if line.startswith("| `")]
    assert rows == ["| `a`: new | 7 |", "| `b`: second | 2 |"]
    assert new.split("<!-- /table: speed -->")[1] == PAGE_TEXT.split("<!-- /table: speed -->")[1]


def test_rows_of_a_new_benchmark_go_after_the_last_row() -> None:
    new = replace_rows(PAGE_TEXT, "speed", "`c`:", ["| `c`: new | 5 |"])
    table = new.split("<!-- table: speed -->")[1].split("<!-- /table: speed -->")[0]
    assert table.strip().splitlines()[-1] == "| `c`: new | 5 |"
    assert "| `a`: third | 3 |" in table


def test_a_case_is_replaced_with_the_rows_that_continue_it() -> None:
    new = replace_rows(PAGE_TEXT, "cases", "`x`:", ["| `x`: one | fx | 10 |", "| | cx | 20 |"])
    table = new.split("<!-- table: cases -->")[1].split("<!-- /table: cases -->")[0]
    assert [line for line in table.splitlines() if line.startswith("| ")][2:] == [
        "| `x`: one | fx | 10 |", "| | cx | 20 |", "| `y`: two | fx | 3 |", "| | cx | 4 |"]


@pytest.mark.parametrize("text", [
    PAGE_TEXT.replace("<!-- table: speed -->\n", ""),
    PAGE_TEXT.replace("<!-- /table: speed -->", ""),
    PAGE_TEXT + "<!-- table: speed -->\n",
    PAGE_TEXT.replace("<!-- table: speed -->\n", "").replace(
        "<!-- /table: speed -->", "<!-- /table: speed -->\n<!-- table: speed -->"),
], ids=["no opening", "no closing", "twice", "closed before opened"])
def test_markers_missing_or_repeated_are_one_error_naming_the_table(text: str) -> None:
    with pytest.raises(DocsTableError, match=r"^page.md has no single '<!-- table: speed -->'"):
        replace_table(text, "speed", ["| x |"], where="page.md")
    with pytest.raises(DocsTableError):
        replace_rows(text, "speed", "`a`:", ["| x |"], where="page.md")


def test_writing_replaces_the_page_in_one_piece(tmp_path: Path) -> None:
    page = tmp_path / "benchmarks.md"
    page.write_text(PAGE_TEXT)
    write_rows("speed", "`b`:", ["| `b`: again | 8 |"], page=page)
    assert "| `b`: again | 8 |" in page.read_text()
    write_table("cases", ["| case |", "| --- |"], page=page)
    assert "| `x`: one |" not in page.read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["benchmarks.md"]


def test_a_page_without_the_markers_ends_in_one_line_and_is_left_alone(tmp_path: Path) -> None:
    page = tmp_path / "benchmarks.md"
    page.write_text("# Figures\n")
    with pytest.raises(SystemExit) as ended:
        write_table("speed", ["| x |"], page=page)
    assert str(ended.value).startswith("error: ") and "\n" not in str(ended.value)
    assert "<!-- table: speed -->" in str(ended.value)
    assert page.read_text() == "# Figures\n"


def test_a_benchmark_writes_its_results_as_its_rows_of_the_summary(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    page = tmp_path / "benchmarks.md"
    page.write_text(PAGE_TEXT.replace("table: speed", f"table: {report.SUMMARY}"))
    monkeypatch.setattr(report, "RESULTS", [])
    monkeypatch.setattr("benchmarks.docs.PAGE", page)
    report.emit("bare vs camlog", baseline="bare", baseline_value=10.0, measured="camlog",
                measured_value=8.0, unit="fps", ratio=0.8, target=">= 0.7")
    report.write_summary_rows("a", argparse.Namespace(write_docs=False))
    assert page.read_text() == PAGE_TEXT.replace("table: speed", f"table: {report.SUMMARY}")
    report.write_summary_rows("a", argparse.Namespace(write_docs=True))
    rows = [line for line in page.read_text().splitlines() if line.startswith("| `")][:3]
    assert rows == ["| `a`: bare vs camlog | bare 10.0 fps | camlog 8.00 fps | 0.80 | >= 0.7 |",
                    "| `b`: second | 2 |", "| `x`: one | fx | 1 |"]


def test_every_table_the_benchmarks_write_has_its_markers_in_the_docs() -> None:
    text = PAGE.read_text()
    for name in TABLES:
        replace_table(text, name, ["| x |"], where=str(PAGE))  # raises without its markers


def test_the_mrcal_comparison_writes_each_case_as_a_group_of_rows() -> None:
    from benchmarks.calibration_truth import Accuracy
    from benchmarks.docs import markdown_row
    from benchmarks.spread import markdown_rows

    seeds = [Accuracy(0.02 * s, 0.1, 0.2, [0.1 * s], fx_percent=0.02 * s, fy_percent=0.01,
                      principal_px=0.3) for s in (1, 2, 3)]
    rows = markdown_rows({"heldout": {"camlog": seeds, "OpenCV": seeds[:1]}},
                         ["camlog", "OpenCV", "mrcal"], {"heldout": "`heldout`: mono_heldout"},
                         {("heldout", "OpenCV"): 2})["heldout"]
    assert rows[0][:3] == ["`heldout`: mono_heldout", "fx %", "0.04 / 0.052"]
    assert all(row[0] == "" for row in rows[1:])
    assert rows[-1] == ["", "seeds", "n 3", "n 1, 2 failed", "-"]
    page = replace_rows(PAGE.read_text(), "vs_mrcal", "`heldout`:", [markdown_row(r) for r in rows])
    table = page.split("<!-- table: vs_mrcal -->")[1].split("<!-- /table: vs_mrcal -->")[0]
    assert table.count("| `heldout`: mono_heldout |") == 1 and "| | seeds | n 3 |" in table
    assert "| `stereo`: stereo_heldout |" in table  # the other cases keep their rows


def test_the_accuracy_row_holds_the_worst_figures_and_the_opencv_ratios() -> None:
    from benchmarks.calibrate_speed import CASES, Worst, docs_row

    mine, theirs = Worst(), Worst()
    mine.add(fx_fy_pct=0.021, cx_px=-0.146, cy_px=0.143, maxdiff_px=0.191, rot_deg=0.019,
             baseline_pct=0.027, err_sigma=2.47, unc_ratio=1.7, cv_ratio=2.4,
             maxdiff_left_px=0.101, maxdiff_right_px=0.191)
    theirs.add(maxdiff_px=0.38, rot_deg=0.034, baseline_pct=0.020)
    case = next(c for c in CASES if c.name == "stereo")
    row = docs_row(case, mine, theirs, [1.01, 1.23, 0.35], [])
    assert row[0].startswith("`stereo`: stereo_checkerboard (`--left ")
    assert row[1:] == ["0.021 %", "0.146 px", "0.143 px", "0.101 / 0.191 px", "0.019°, 0.027 %",
                       "2.47", "1.7×, 2.4×", "0.38 px, 0.034°, 0.020 % (camlog 1.01×, 1.23×, "
                       "0.35×)"]


def test_the_peers_tables_give_both_sides_and_the_cost_of_a_minute() -> None:
    from benchmarks.peers import Case, Result, growth_rows, markdown_rows
    from benchmarks.processes import Run

    case = Case("convert ROS1 -> rosbag2", [], "rosbags-convert", [], [], "<= 1.0")
    def result(camlog_s: float, peer_s: float) -> Result:
        return Result(case, Run(camlog_s, camlog_s, 60, 0), Run(peer_s, peer_s, 50, 0),
                      camlog_s / peer_s, 1.2)
    rows = markdown_rows([result(0.33, 0.43)])
    assert rows[2] == ("| convert ROS1 -> rosbag2 | rosbags-convert: 0.43 s, 0.43 s, 50 MB | "
                       "0.33 s, 0.33 s, 60 MB | 0.77 | 0.77 | 1.20 | <= 1.0 |")
    growth = growth_rows({case.name: {4: result(0.3, 0.28), 40: result(0.56, 0.5),
                                      400: result(3.48, 2.82)}}, [4, 40, 400])
    assert growth[0] == "| command | 4 s log | 40 s log | 400 s log | per extra minute of log |"
    assert growth[2].endswith("| 3.48 s, 60 MB (2.82 s, 50 MB) | 0.49 s (0.39 s) |")


def test_figures_have_three_significant_digits_and_no_exponent() -> None:
    assert [report.figure(v) for v in (1736.2, 30.295, 0.65, 0.000123, 0.0)] == [
        "1736", "30.3", "0.650", "0.000123", "0"]
