"""``roomba_bt.robot``'s names, imported from their modules when first asked for."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

import roomba_bt.robot as robot


@pytest.mark.parametrize("name", robot.__all__)
def test_every_name_is_the_object_its_module_defines(name: str) -> None:
    value = getattr(robot, name)
    module = importlib.import_module(value.__module__)
    assert getattr(module, name) is value
    assert name in dir(robot)


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError) as raised:
        robot.nope  # noqa: B018
    assert str(raised.value) == "module 'roomba_bt.robot' has no attribute 'nope'"


def test_from_import_in_a_fresh_interpreter() -> None:
    """``from roomba_bt.robot import Connection`` (as docs/robot.md writes it) loads the
    connection's module then, not before."""
    script = (
        "import sys\n"
        "import roomba_bt.robot.interface\n"
        "assert 'roomba_bt.robot.connection' not in sys.modules\n"
        "from roomba_bt.robot import Connection, sigterm_raises\n"
        "print(Connection.__module__, sigterm_raises.__module__)\n"
    )
    output = subprocess.check_output([sys.executable, "-c", script], text=True, timeout=HANG_S)
    assert output.split() == ["roomba_bt.robot.connection", "roomba_bt.robot.safety"]
