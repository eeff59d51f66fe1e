"""Files rotor writes get the mode a plain ``open(path, "w")`` gives them, go only onto a
new name or a regular file (never a link, a device or a named pipe), several that belong
together all or none, and errors name the user's path, never the temporary file beside it."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from rotor.fileio import atomic_path, save_json, write_text_atomic


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    try:
        yield
    finally:
        os.umask(old)


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_new_file_gets_the_users_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        write_text_atomic(tmp_path / "a.txt", "x")
        with open(tmp_path / "plain.txt", "w") as f:
            f.write("x")
    finally:
        os.umask(old)
    assert _mode(tmp_path / "a.txt") == 0o666 & ~umask
    assert _mode(tmp_path / "a.txt") == _mode(tmp_path / "plain.txt")


def test_replaced_file_keeps_its_mode(tmp_path, umask_022):
    p = tmp_path / "a.json"
    p.write_text("{}")
    os.chmod(p, 0o640)
    save_json(p, {"a": 1}, what="a test")
    assert _mode(p) == 0o640
    assert p.read_text().strip().startswith("{")


def test_error_names_the_users_path_not_the_temporary(tmp_path):
    target = tmp_path / "x"
    target.mkdir()  # a folder where a file should go
    with pytest.raises(OSError) as e:
        write_text_atomic(target, "x")
    assert e.value.filename == str(target)
    assert ".rotor-" not in str(e.value)
    assert not [n for n in os.listdir(tmp_path) if n.startswith(".rotor-")]


def test_error_in_the_block_names_the_users_path(tmp_path):
    target = tmp_path / "out.png"
    with pytest.raises(OSError) as e:
        with atomic_path(target) as tmp:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), tmp)  # e.g. a full disk
    assert ".rotor-" not in str(e.value)
    assert e.value.filename == str(target)
    assert not target.exists()


def test_cli_error_names_the_users_path(tmp_path, capsys):
    from rotor.cli.app import main

    target = tmp_path / "x"
    target.mkdir()
    rc = main(["table", "4chn15", "-o", str(target)])
    err = capsys.readouterr().err
    assert rc != 0
    assert ".rotor-" not in err and str(target) in err


# ----------------------------------------------------------------------------- a log's header line
def _log(tmp_path, text, name="log.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_a_first_line_mixing_numbers_and_text_is_refused(tmp_path):
    """Data in another format (a decimal comma) used to be taken for a header and dropped."""
    from rotor.errors import LogError
    from rotor.logs.reader import read_log

    p = _log(tmp_path, "0;1000,5\n0.1;1001\n0.2;1002\n0.3;1003\n")
    with pytest.raises(
        LogError, match=r"line 1 writes '1000,5' with a decimal comma and line 2 '0.1' with a decimal point"
    ):
        read_log(p, "time,rpm")
    p = _log(tmp_path, "# bench 3\n0.0 1000 x\n0.1 1001 2\n0.2 1002 2\n")
    with pytest.raises(LogError, match=r"line 2 .*'#'"):
        read_log(p, "time,rpm")


def test_a_header_that_contradicts_the_spec_is_refused(tmp_path):
    from rotor.errors import LogError
    from rotor.logs.reader import read_log

    p = _log(tmp_path, "time,encoder_v,pressure_v\n0,1,2\n0.1,1,2\n0.2,1,2\n")
    with pytest.raises(
        LogError, match=r"line 1: the header names column 2 'encoder_v' but the column spec names it 'pressure_v'"
    ):
        read_log(p, "time,pressure_v,encoder_v")
    assert read_log(p, "time,encoder_v,-").kind == "encoder"  # '-' skips a named column


def test_a_header_of_other_names_is_recorded(tmp_path):
    from rotor.errors import LogError
    from rotor.logs.reader import read_log

    p = _log(tmp_path, "# bench\nTime [s],Speed\n0,1000\n0.1,1001\n0.2,1002\n")
    log = read_log(p, "time,rpm")
    np.testing.assert_array_equal(log["rpm"], [1000, 1001, 1002])
    assert len(log.notes) == 1 and "header line 2 ('Time [s],Speed') skipped" in log.notes[0]
    assert read_log(_log(tmp_path, "time,rpm\n0,1\n0.1,2\n0.2,3\n", "named.csv")).notes == ()
    # without a spec, the header's names read as they come: a time and a speed
    recognised = read_log(p)
    assert set(recognised.columns) == {"time", "rpm"}
    assert any("'Speed' → rpm" in n for n in recognised.notes)
    with pytest.raises(LogError, match="'Time \\[s\\]' is named a time but does not increase"):
        read_log(_log(tmp_path, "Time [s],Speed\n1,1000\n0,1001\n2,1002\n", "unordered.csv"))


@pytest.mark.parametrize(
    "make,words",
    [
        (lambda d: d / "plots", "is a folder"),  # a JSON or CSV output path that is a folder
        (lambda d: d / "file" / "t.csv", "is a file, not a folder"),  # a "folder" that is a file
        (lambda d: d / "missing" / "t.csv", "no folder"),  # a folder that does not exist
    ],
)
def test_a_path_that_cannot_be_written_is_refused_by_name_before_writing(tmp_path, make, words):
    (tmp_path / "plots").mkdir()
    (tmp_path / "file").write_text("x")
    path = make(tmp_path)
    with pytest.raises(OSError) as info:
        write_text_atomic(path, "text")
    assert info.value.filename == str(path) and words in info.value.strerror
    assert sorted(os.listdir(tmp_path)) == ["file", "plots"] and os.listdir(tmp_path / "plots") == []


# ----------------------------------------------------------------------------- what a file is written onto
def _through_atomic_path(path):
    with atomic_path(path) as tmp:
        Path(tmp).write_text("x\n")


def _fifo(tmp_path, name="pipe"):
    path = tmp_path / name
    os.mkfifo(path)  # stands in for a device such as /dev/null: not a regular file
    return path


@pytest.mark.parametrize(
    "write",
    [
        lambda p: write_text_atomic(p, "x\n"),
        lambda p: save_json(p, {"a": 1}, what="a test"),
        _through_atomic_path,
    ],
    ids=["write_text_atomic", "save_json", "atomic_path"],
)
def test_a_named_pipe_is_refused_and_stays_a_named_pipe(tmp_path, write):
    pipe = _fifo(tmp_path)
    with pytest.raises(OSError, match="named pipe") as info:
        write(pipe)
    assert str(pipe) in str(info.value) and "give a file name" in str(info.value)
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode)
    assert sorted(os.listdir(tmp_path)) == ["pipe"]


def test_a_link_is_neither_replaced_nor_written_through(tmp_path):
    target = tmp_path / "target.txt"
    target.write_text("the user's\n")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    with pytest.raises(OSError) as info:
        write_text_atomic(link, "x\n")
    assert info.value.filename == str(link) and f"is a link to {target}" in info.value.strerror
    assert link.is_symlink() and target.read_text() == "the user's\n"
    standard_output = tmp_path / "stdout"  # stands in for /dev/stdout: a link to a stream
    standard_output.symlink_to(_fifo(tmp_path))
    with pytest.raises(OSError, match=f"is a link to {tmp_path / 'pipe'}"):
        write_text_atomic(standard_output, "x\n")
    assert standard_output.is_symlink() and stat.S_ISFIFO(os.lstat(tmp_path / "pipe").st_mode)
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "nowhere")
    with pytest.raises(OSError, match="is a link to"):
        save_json(dangling, {}, what="a test")
    assert dangling.is_symlink() and not (tmp_path / "nowhere").exists()
    assert not [n for n in os.listdir(tmp_path) if n.startswith(".rotor-")]


def test_what_replaces_a_file_while_it_is_written_is_not_replaced(tmp_path):
    path = tmp_path / "out.csv"
    with pytest.raises(OSError, match="named pipe"):
        with atomic_path(path) as tmp:
            Path(tmp).write_text("x\n")
            os.mkfifo(path)  # made by someone else meanwhile
    assert stat.S_ISFIFO(os.lstat(path).st_mode) and sorted(os.listdir(tmp_path)) == ["out.csv"]


def test_several_files_are_written_all_or_none(tmp_path, monkeypatch):
    from rotor.fileio import write_texts_atomic

    log, truth = tmp_path / "rec.csv", tmp_path / "rec.truth.json"
    log.write_text("old log\n")
    truth.write_text("old truth\n")
    pipe = _fifo(tmp_path)
    with pytest.raises(OSError, match="named pipe"):  # every target checked before anything is written
        write_texts_atomic([(log, "new log\n"), (pipe, "x")])
    assert log.read_text() == "old log\n"

    real_replace = os.replace
    calls = []

    def second_fails(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), dst)  # a full disk
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", second_fails)
    with pytest.raises(OSError) as info:
        write_texts_atomic([(log, "new log\n"), (truth, "new truth\n")])
    assert info.value.filename == str(truth) and ".rotor-" not in str(info.value)
    assert log.read_text() == "old log\n" and truth.read_text() == "old truth\n"
    new = tmp_path / "new.csv"
    calls.clear()
    with pytest.raises(OSError):
        write_texts_atomic([(new, "new\n"), (tmp_path / "new.truth.json", "truth\n")])
    assert not new.exists()  # a file made by the first rename is removed again
    monkeypatch.undo()
    assert sorted(os.listdir(tmp_path)) == ["pipe", "rec.csv", "rec.truth.json"]
    write_texts_atomic([(log, "new log\n"), (truth, "new truth\n")])
    assert log.read_text() == "new log\n" and truth.read_text() == "new truth\n"
    with pytest.raises(ValueError, match="one file given twice"):
        write_texts_atomic([(log, "a"), (tmp_path / "." / "rec.csv", "b")])
