"""``replay.atomic``: hidden unique temporary names, inputs refused, only own files deleted."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from replay import OutputError, Text, open_reader, open_writer
from replay.atomic import (
    AtomicFolder,
    AtomicOutput,
    check_not_input,
    is_temp_output,
    temp_output_of,
    temp_sibling,
    write_text_atomic,
)
from tests.outputs import temp_outputs


def test_temp_names_are_hidden_unique_siblings(tmp_path: Path) -> None:
    final = tmp_path / "run.mcap"
    names = {temp_sibling(final) for _ in range(200)}
    assert len(names) == 200
    for temp in names:
        assert temp.parent == tmp_path
        assert temp.name.startswith(".run.mcap.camlog-") and temp.name.endswith(".tmp")
        assert is_temp_output(temp) and temp_output_of(temp) == final
    for user_name in ("run.mcap", "run.mcap.partial", ".run.mcap", "run.mcap.tmp",
                      ".run.mcap.camlog-xyz.tmp"):
        assert not is_temp_output(tmp_path / user_name)
        assert temp_output_of(tmp_path / user_name) is None


def test_temp_name_skips_a_taken_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    tokens = iter(["0" * 16, "0" * 16, "1" * 16])
    monkeypatch.setattr("replay.temp_names.secrets.token_hex", lambda _n: next(tokens))
    (tmp_path / f".x.camlog-{'0' * 16}.tmp").write_text("someone's")
    assert temp_sibling(tmp_path / "x").name == f".x.camlog-{'1' * 16}.tmp"


def test_file_appears_only_on_commit(tmp_path: Path) -> None:
    final = tmp_path / "out.txt"
    with AtomicOutput(final, overwrite=False) as output:
        output.temp.write_text("new")
        assert not final.exists()
        assert temp_outputs(tmp_path) == [output.temp]
    assert final.read_text() == "new"
    assert temp_outputs(tmp_path) == []


def test_failure_removes_only_the_own_temp(tmp_path: Path) -> None:
    final = tmp_path / "out.txt"
    leftover = tmp_path / ".out.txt.camlog-00000000000000aa.tmp"  # an earlier crashed run
    leftover.write_text("recover me")
    user_file = tmp_path / "out.txt.partial"
    user_file.write_text("mine")
    with pytest.raises(RuntimeError), AtomicOutput(final, overwrite=False) as output:
        output.temp.write_text("half")
        raise RuntimeError
    assert not final.exists() and not output.temp.exists()
    assert leftover.read_text() == "recover me" and user_file.read_text() == "mine"


def test_existing_output_needs_overwrite(tmp_path: Path) -> None:
    final = tmp_path / "out.txt"
    final.write_text("old")
    with pytest.raises(OutputError, match=r"exists .*--overwrite"):
        AtomicOutput(final, overwrite=False)
    write_text_atomic(final, "new")
    assert final.read_text() == "new"


def test_directory_replaced_only_when_it_may_be(tmp_path: Path) -> None:
    folder = tmp_path / "home"
    folder.mkdir()
    (folder / "notes.txt").write_text("keep")
    with pytest.raises(OutputError, match="not a log"):
        AtomicOutput(folder, overwrite=True)
    with AtomicOutput(folder, overwrite=True, replaceable_dir=lambda _p: True) as output:
        output.temp.mkdir()
        (output.temp / "new.txt").write_text("new")
    assert sorted(p.name for p in folder.iterdir()) == ["new.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["home"]


@pytest.mark.parametrize("kind", ["same", "symlink", "hardlink", "inside", "holds"])
def test_output_that_is_or_touches_an_input_is_refused(tmp_path: Path, kind: str) -> None:
    log = tmp_path / "bag"
    log.mkdir()
    (log / "bag.mcap").write_bytes(b"input")
    output = {"same": log, "inside": log / "out.mcap", "holds": tmp_path}.get(kind)
    given = log
    if kind == "symlink":
        output = tmp_path / "alias"
        output.symlink_to(log)
    elif kind == "hardlink":
        given = log / "bag.mcap"
        output = tmp_path / "copy.mcap"
        os.link(given, output)
    assert output is not None
    with pytest.raises(OutputError, match="input"):
        AtomicOutput(output, overwrite=True, inputs=[given], replaceable_dir=lambda _p: True)
    assert (log / "bag.mcap").read_bytes() == b"input"
    check_not_input(tmp_path / "other.mcap", [given])  # a sibling is fine


def test_folder_moves_named_files_into_an_existing_folder(tmp_path: Path) -> None:
    folder = tmp_path / "cal"
    folder.mkdir()
    (folder / "notes.txt").write_text("keep")
    (folder / "ost.yaml").write_text("old")
    with pytest.raises(OutputError, match=r"already holds ost\.yaml"):
        AtomicFolder(folder, ["ost.yaml", "report.md"], overwrite=False)
    with AtomicFolder(folder, ["ost.yaml", "report.md"], overwrite=True) as staged:
        (staged.path / "ost.yaml").write_text("new")
        (staged.path / "report.md").write_text("report")
        assert (folder / "ost.yaml").read_text() == "old"
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt", "ost.yaml", "report.md"]
    assert (folder / "ost.yaml").read_text() == "new"
    assert temp_outputs(tmp_path) == []


def test_new_folder_appears_whole_or_not_at_all(tmp_path: Path) -> None:
    folder = tmp_path / "cal"
    with pytest.raises(RuntimeError), AtomicFolder(folder, ["a"], overwrite=False) as staged:
        (staged.path / "a").write_text("a")
        raise RuntimeError
    assert list(tmp_path.iterdir()) == []
    with AtomicFolder(folder, ["a"], overwrite=False) as staged:
        (staged.path / "a").write_text("a")
    assert [p.name for p in tmp_path.iterdir()] == ["cal"]


def test_folder_may_hold_inputs_but_not_be_or_replace_one(tmp_path: Path) -> None:
    folder = tmp_path / "cal"
    folder.mkdir()
    log = folder / "run.mcap"
    log.write_bytes(b"input")
    AtomicFolder(folder, ["ost.yaml"], overwrite=False, inputs=[log]).discard()
    with pytest.raises(OutputError, match="is the input"):
        AtomicFolder(folder, ["run.mcap"], overwrite=True, inputs=[log])
    with pytest.raises(OutputError, match="inside the input"):
        AtomicFolder(log / "x", ["a"], overwrite=True, inputs=[log])
    assert log.read_bytes() == b"input"


def test_writer_temp_is_hidden_and_a_leftover_opens_with_a_warning(tmp_path: Path) -> None:
    final = tmp_path / "run.mcap"
    writer = open_writer(final)
    writer.write("/t", Text("x"), log_time_ns=1)
    assert writer.temp_path.parent == tmp_path and is_temp_output(writer.temp_path)
    writer._finish()  # finished on disk but never renamed: what a kill before commit leaves
    with open_reader(writer.temp_path) as reader:
        assert [r.message for r in reader.messages()] == [Text("x")]
        assert "temporary output for run.mcap" in reader.warnings[0]
    assert not final.exists()
