"""Names given where a file may be meant that the system will not look up at all (longer than a file name may be,
or holding a NUL character): one line naming what was given, never the OSError or ValueError of the lookup."""

import errno
import os

import pytest

from cli_runner import run_in_process
from spectrace.displays import load_display
from spectrace.errors import SpectraceError
from spectrace.io.input_files import is_regular_file, regular_file

TOO_LONG = "a" * 300  # beyond the 255 bytes a file name may have on common file systems
TOO_DEEP = "a/" * 3000  # beyond the 4096 bytes a path may have


@pytest.mark.parametrize("name", [TOO_LONG, TOO_DEEP, "a\0b.csv"])
def test_the_input_file_checks_answer_for_any_name(name):
    assert not is_regular_file(name)
    with pytest.raises(SpectraceError) as error:
        regular_file(name, what="display file")
    assert str(error.value).count("\n") == 0


@pytest.mark.parametrize("name", [TOO_LONG, TOO_DEEP])
def test_a_display_whose_name_is_too_long_is_one_error(name):
    with pytest.raises(SpectraceError, match="display"):
        load_display(name, where="display")


def test_a_scene_argument_too_long_is_one_line(tmp_path, monkeypatch, capsys):
    status, err = run_in_process(monkeypatch, capsys, ["render", TOO_LONG, "-o", str(tmp_path / "out.exr")])
    reason = os.strerror(errno.ENAMETOOLONG)
    assert status == 2 and err == f"error: {TOO_LONG}: cannot read scene file ({reason})\n", err
    assert not (tmp_path / "out.exr").exists()
