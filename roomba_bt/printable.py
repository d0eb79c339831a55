"""What of a text may reach a terminal or a log line as it is: the control characters a
stranger's file can carry, and :func:`escaped` to show them as ``\\x1b``.

Standard library only and importing nothing of ours, so that every layer may use it, the
protocol's included, and the command line's parser can say a name without loading YAML
(:mod:`roomba_bt.yamlsource` refuses these characters in a file; this module only shows
them)."""

from __future__ import annotations

import re

__all__ = ["ANY_CONTROL", "CONTROL", "escaped"]

#: Characters no text of a data file may hold (C0 but tab and newline, DEL, C1): a file
#: travels between strangers, and its texts reach the terminal (``show``, the live tree, the
#: log, error lines), where ``"\e[2J"`` clears the screen and ``"\e]0;...\a"`` retitles it
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")
#: every control character, tab and newline too: what must stay on one line (a node's name in
#: the live tree, the log and a run's summary, where "\n[ok] robot stopped" would fake a line)
ANY_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")


def escaped(text: str, which: re.Pattern[str] = CONTROL) -> str:
    """``text`` with each character ``which`` matches written as ``\\x1b``: an error line,
    a node's name or a mission's text is printed to a terminal, where a raw ``ESC [2J``
    would clear the screen (:data:`ANY_CONTROL`: a newline too, for what is one line)."""
    if which.search(text) is None:
        return text
    return which.sub(lambda found: f"\\x{ord(found.group()):02x}", text)
