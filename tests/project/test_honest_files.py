"""Files rotor writes get the mode a plain ``open(path, "w")`` gives them, and errors name
the user's path, never the temporary file beside it."""

from __future__ import annotations

import errno
import os
import stat

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
    with pytest.raises(LogError, match=r"line 2 is a header whose names 'Time \[s\]', 'Speed' are not column names"):
        read_log(p)


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
