from __future__ import annotations

import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.mission import CompiledMission, Diagnostic, compile_mission, load_mission


@pytest.fixture(autouse=True)
def _fresh_blackboard(clean_blackboard: None) -> None:
    """Every test here runs on an empty blackboard (``clean_blackboard``, tests/conftest.py)."""


@pytest.fixture
def mission_file(tmp_path: Path) -> Callable[..., Path]:
    """``mission_file(text, name="m.yaml")``: write a (dedented) mission, return its path."""

    def write(text: str, name: str = "m.yaml") -> Path:
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
        return path

    return write


@pytest.fixture
def compile_text(mission_file: Callable[..., Path]) -> Callable[..., CompiledMission]:
    def compile_(text: str, params: dict[str, str] | None = None) -> CompiledMission:
        return load_mission(mission_file(text), params)

    return compile_


@pytest.fixture
def errors_of(mission_file: Callable[..., Path]) -> Callable[..., list[str]]:
    """The diagnostics of a mission as ``line:col: message`` strings."""

    def errors(text: str, params: dict[str, str] | None = None, **kwargs: object) -> list[str]:
        mission, diagnostics = compile_mission(mission_file(text), params, **kwargs)  # type: ignore[arg-type]
        assert mission is None or not diagnostics
        return [short(d) for d in diagnostics]

    return errors


def short(d: Diagnostic) -> str:
    return f"{d.line}:{d.column}: {d.message}"
