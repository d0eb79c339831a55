"""What a stranger's mission files and names did that a clear error now meets (session 27,
mission files, findings 2-6)."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.mission import compile_mission


def _problems(path: Path, params: dict[str, str] | None = None) -> list[str]:
    _, problems = compile_mission(path, params)
    return [f"{p.line}:{p.column}: {p.message}" for p in problems]


def test_an_include_through_a_symlink_loop_is_refused_at_the_include(tmp_path: Path) -> None:
    """It was "internal error while compiling (RuntimeError: Symlink loop ...)" at 1:1."""
    (tmp_path / "loop_a.yaml").symlink_to("loop_b.yaml")
    (tmp_path / "loop_b.yaml").symlink_to("loop_a.yaml")
    path = tmp_path / "m.yaml"
    path.write_text("mission: m\ninclude: [loop_a.yaml]\ntree: {log: x}\n")
    assert _problems(path) == [
        "2:11: an include 'loop_a.yaml' is a symbolic link loop (it leads back to itself), "
        "not a file: name the file itself"
    ]
