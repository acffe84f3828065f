"""The order the suite runs in: modules with known-long tests first, each module whole and in its own order."""

from types import SimpleNamespace

from conftest import pytest_collection_modifyitems


def _item(nodeid: str, *marks: str):
    return SimpleNamespace(nodeid=nodeid, get_closest_marker=lambda name: name if name in marks else None)


def test_modules_with_long_tests_come_first_whole_and_in_their_order():
    items = [
        _item("a.py::fast"),
        _item("b.py::peer", "peer"),
        _item("c.py::fast_1"),
        _item("c.py::slow", "slow", "subprocess"),
        _item("c.py::fast_2"),
        _item("d.py::fast"),
        _item("e.py::slow", "slow"),
    ]
    pytest_collection_modifyitems(None, None, items)
    assert [item.nodeid for item in items] == [
        "c.py::fast_1",
        "c.py::slow",
        "c.py::fast_2",
        "e.py::slow",
        "b.py::peer",
        "a.py::fast",
        "d.py::fast",
    ]
