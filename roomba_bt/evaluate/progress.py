"""An evaluation's progress on stderr: a bar per variant, drawn together.

On a terminal the variants' bars are a block of lines, one a variant, redrawn in place (the
cursor moved up to the block's first line, each line written over and erased to its end)::

    dock turn_speed=90mm/s  [#########.....................] 312/1000 ok 301 elapsed 41s ETA 90s
    dock turn_speed=200mm/s [#########.....................] 311/1000 ok 305 elapsed 41s ETA 91s

Into a file or a pipe (a CI log), or a ``TERM=dumb`` terminal, no terminal code: a line after
the first episode, at each tenth of the whole evaluation, after the last and after
:data:`LOG_EVERY_S` without one, every variant's count on it (as a terminal shows them when
it has fewer lines than there are variants). Before, each variant had a bar of its own, each
redrawn with a carriage return on the one line, so an A/B's two bars took turns there (a
flicker no one could read), and a log got a line per variant and tenth. An evaluation
resumed (``--resume``) counts the episodes read back: ``700/1000`` going on to
``1000/1000``, not ``0/300``.

What is said on stderr while the bars are drawn (a worker's death) goes through
:func:`say`: the block is erased first and drawn again below it, as ``tqdm.write`` does.
"""

from __future__ import annotations

import itertools
import os
import shutil
import sys
import time
from collections.abc import Sequence
from typing import Any, TextIO

from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.evaluate.interleave import Progress

#: The terminal's "erase to the end of the line" (ANSI EL, as ``sensors`` clears its screen
#: with ANSI codes): a redraw shorter than the text it writes over leaves none of it.
ERASE_TO_END = "\x1b[K"
#: ... "erase to the end of the screen" (ANSI ED 0): a block of bars taken away
ERASE_BELOW = "\x1b[J"


def cursor_up(lines: int) -> str:
    """ANSI CPL: the cursor to the start of the line ``lines`` above (none for 0)."""
    return f"\x1b[{lines}F" if lines else "\r"


#: How often a terminal's bars are redrawn at most (s; at the first episode and the last
#: always): a sweep of short episodes finishes hundreds a second
REDRAW_S = 0.1

#: The longest a log goes without a line of the bars (s): a tenth of a 100 000-episode
#: sweep is half an hour, and a CI service that ends a job silent for 10 minutes (CircleCI's
#: no_output_timeout) ended it; a reader of the log saw nothing move
LOG_EVERY_S = 300.0

#: The order of the progress bars' draws, across bars: :attr:`ProgressBar.drawn`.
_DRAWS = itertools.count()


def bar_line(label: str, done: int, total: int, ok: int, elapsed: float, eta: float | None,
             width: int) -> str:  # fmt: skip
    """One bar: ``dock [#########.........] 12/50 ok 11 elapsed 3s ETA 8s`` (``ETA ?``
    before an episode of it ran: a resumed variant's episodes read back tell no pace)."""
    filled = round(width * done / max(total, 1))
    bar = "#" * filled + "." * (width - filled)
    left = "?" if eta is None else f"{eta:.0f}s"
    return f"{label}[{bar}] {done}/{total} ok {ok} elapsed {elapsed:.0f}s ETA {left}"


def _on_a_terminal(stream: TextIO) -> bool:
    """Whether ``stream`` is a terminal that takes the bars' codes: not one whose ``TERM`` is
    ``dumb`` (an editor's shell buffer, some CI runners' pseudo-terminals), which showed
    each ``ESC[K`` as text; it gets a log's lines."""
    isatty = getattr(stream, "isatty", None)
    return bool(isatty()) and os.environ.get("TERM") != "dumb" if isatty is not None else False


def _size(stream: TextIO) -> tuple[int, int]:
    """How many characters a line of ``stream``'s terminal holds (a longer one wraps, and a
    redraw in place then writes over the wrong lines), and how many lines it shows."""
    try:
        columns, lines = os.get_terminal_size(stream.fileno())
    except (AttributeError, OSError, ValueError):  # no file behind it (a test's terminal)
        columns = lines = 0
    fallback = shutil.get_terminal_size()  # 0: a pty never sized, COLUMNS and LINES or 80x24
    return columns or fallback.columns, lines or fallback.lines


class ProgressBar:
    """``[#########.........] 12/50 ok 11 ETA 8s`` on stderr, redrawn in place on a terminal;
    into a file or a pipe (a CI log), a line of its own after the first episode, each tenth
    and the last (a redraw per episode filled logs with carriage returns). A redraw erases
    what is left of the line after it: one shorter than the line before (an ETA from 100 s
    to 99 s) left the last characters of the longer one, ``ETA 99ss``, ``ETA 57s17s``. One
    batch's bar; the variants of an evaluation are drawn together by :class:`ProgressBars`."""

    def __init__(self, stream: TextIO | None = None, width: int = 30, label: str = "") -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.label = label
        self.started = time.perf_counter()
        self.ok = 0
        self.redraw = _on_a_terminal(self.stream)
        #: when this bar last drew (the order of every bar's draws) and whether that left
        #: its line open (a terminal's redraw before the last episode): :func:`end_bars`
        self.drawn = (-1, False)

    def __call__(self, done: int, total: int, result: EpisodeResult) -> None:
        self.ok += result.succeeded
        if (
            not self.redraw
            and done not in (1, total)
            and done * 10 // total == (done - 1) * 10 // total
        ):
            return
        elapsed = time.perf_counter() - self.started
        eta = elapsed / done * (total - done) if done else 0.0
        start, end = ("\r", "\n" if done == total else "") if self.redraw else ("", "\n")
        self.drawn = (next(_DRAWS), not end)
        line = bar_line(self.label, done, total, self.ok, elapsed, eta, self.width)
        self.stream.write(f"{start}{line}{ERASE_TO_END if self.redraw else ''}{end}")
        self.stream.flush()


def _label_cut(label: str, cut: int) -> str:
    """``label`` (padded, ending in a space) ``cut`` characters shorter, its start left out
    (``...`` in its place): a variant's label names the mission as given, often a long path,
    and its parameters last, which tell one variant's bar from the next; cut at its end,
    the line lost its count and ETA on a narrow terminal. At least its last ten kept."""
    if cut <= 0:
        return label
    keep = max(10, len(label) - cut - 3)
    return label if keep + 3 >= len(label) else "..." + label[-keep:]


class ProgressBars:
    """Every variant's bar of one evaluation (``labels``, one a variant, and ``totals``,
    each one's episodes), drawn together: on a terminal a block of lines, one a variant,
    redrawn in place at most every ``interval_s`` (:data:`REDRAW_S`; at the first episode
    and the last always); into a log, a line at the first episode, at each tenth of the
    whole evaluation, at the last, and after :data:`LOG_EVERY_S` without one, every
    variant's count on it. ``already``: per variant, the episodes of its
    total finished before this run and how many of them succeeded (``--resume``'s, read
    back), counted from the start. :meth:`bar` is variant ``b``'s progress callback."""

    def __init__(
        self,
        labels: Sequence[str],
        totals: Sequence[int],
        stream: TextIO | None = None,
        width: int = 30,
        already: Sequence[tuple[int, int]] = (),
        interval_s: float | None = None,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.names = list(labels)
        widest = max((len(label) for label in labels), default=0)
        self.labels = [f"{label:<{widest}} " if label else "" for label in labels]
        self.totals = list(totals)
        already = list(already) or [(0, 0)] * len(labels)
        #: per variant: finished (those read back included), succeeded, finished in this run
        self.done = [done for done, _ in already]
        self.ok = [ok for _, ok in already]
        self.ran = [0] * len(labels)
        self.redraw = _on_a_terminal(self.stream)
        self.interval_s = REDRAW_S if interval_s is None else interval_s
        self.started = time.perf_counter()
        self.last_drawn = -float("inf")
        self.tenth = -1  # the tenth of the whole a log's last line was written at
        self.logged = 0.0  # and when (s since the start)
        self.open = 0  # the lines of the block on the terminal, the cursor on its last
        #: when the bars last drew (the order of every bar's draws) and whether that left
        #: the block open (:func:`end_bars`)
        self.drawn = (-1, False)

    def bar(self, b: int) -> Progress:
        """Variant ``b``'s progress callback, ``progress(done, total, result)`` (its count
        of this run, which :attr:`totals` and ``already`` hold)."""

        def progress(_: int, __: int, result: EpisodeResult) -> None:
            self.ran[b] += 1
            self.done[b] += 1
            self.ok[b] += result.succeeded
            self._draw()

        return progress

    def _eta(self, elapsed: float, ran: int, left: int) -> float | None:
        if not left:
            return 0.0
        return elapsed / ran * left if ran else None

    def _lines(self, elapsed: float, width: int, cut: int = 0) -> list[str]:
        """Each variant's bar line, ``width`` wide, each label ``cut`` characters shorter
        (:func:`_label_cut`)."""
        return [
            bar_line(_label_cut(label, cut), done, total, ok, elapsed,
                     self._eta(elapsed, ran, total - done), width)
            for label, done, total, ok, ran in zip(self.labels, self.done, self.totals, self.ok,
                                                   self.ran, strict=True)
        ]  # fmt: skip

    def _draw(self) -> None:
        finished = sum(self.done) >= sum(self.totals)
        now = time.perf_counter()
        if self.redraw:
            if not finished and self.open and now - self.last_drawn < self.interval_s:
                return
            self.last_drawn = now
            self._draw_block(now - self.started, finished)
        elif not self._write_line(now - self.started, finished):
            return
        self.drawn = (next(_DRAWS), self.open > 0)
        self.stream.flush()

    def _draw_block(self, elapsed: float, finished: bool) -> None:
        """The block of bars written over the one drawn before (the cursor on its last
        line), each line cut to the terminal's width (a line that wrapped would take two,
        and the next redraw would go up too few); ended with a newline at the last. More
        variants than the terminal has lines (a sweep of 30 values on 24): one line for all
        (the cursor cannot go up past the screen's top to redraw the block)."""
        columns, rows = _size(self.stream)
        columns -= 1  # the last one left free: no wrap at its end
        lines = self._lines(elapsed, self.width)
        if len(lines) >= rows:
            lines = [self._line_for_all(elapsed)]
        else:
            longest = max(len(line) for line in lines)
            width = max(5, self.width - max(0, longest - columns))  # a narrower bar first
            over = longest - (self.width - width) - columns  # then shorter labels
            lines = self._lines(elapsed, width, max(0, over))
        lines = [line[:columns] + ERASE_TO_END for line in lines]
        up = cursor_up(self.open - 1) if self.open else ""
        self.stream.write(up + "\n".join(lines) + ("\n" if finished else ""))
        self.open = 0 if finished else len(lines)
        if self.open:
            _OPEN.add(self)
        else:
            _OPEN.discard(self)

    def _line_for_all(self, elapsed: float) -> str:
        """One line, every variant's count on it: ``[###...] 200/2000 ok 190 elapsed 40s
        ETA 360s: dock a 100/1000 ok 94, dock b 100/1000 ok 96``."""
        done, total = sum(self.done), sum(self.totals)
        eta = self._eta(elapsed, sum(self.ran), total - done)
        line = bar_line("", done, total, sum(self.ok), elapsed, eta, self.width)
        counts = zip(self.names, self.done, self.totals, self.ok, strict=True)
        return f"{line}: " + ", ".join(f"{name} {d}/{t} ok {ok}" for name, d, t, ok in counts)

    def _write_line(self, elapsed: float, finished: bool) -> bool:
        """Into a log, a line at the first episode, at each tenth of the whole, at the last
        and after :data:`LOG_EVERY_S` without one: whether one was written."""
        done, total = sum(self.done), sum(self.totals)
        tenth = done * 10 // max(total, 1)
        quiet = elapsed - self.logged >= LOG_EVERY_S
        if self.tenth >= 0 and tenth == self.tenth and not finished and not quiet:
            return False
        self.tenth, self.logged = tenth, elapsed
        lines = self._lines(elapsed, self.width)
        line = lines[0] if len(lines) == 1 else self._line_for_all(elapsed)
        self.stream.write(line + "\n")
        return True

    def take_away(self) -> None:
        """The block erased from the terminal, the cursor where it began: what is said next
        takes its place, and the next draw draws it again below that."""
        if self.open:
            self.stream.write(cursor_up(self.open - 1) + ERASE_BELOW)
            self.stream.flush()
            self.open = 0
            self.drawn = (self.drawn[0], False)
        _OPEN.discard(self)

    def end(self) -> None:
        """The block left on the terminal as it is, its line ended (an evaluation that
        stopped before its last episode: Ctrl-C, a lost cluster), so what is said next
        starts a line of its own."""
        if self.open:
            self.stream.write("\n")
            self.stream.flush()
            self.open = 0
            self.drawn = (self.drawn[0], False)
        _OPEN.discard(self)


#: The blocks of bars open on a terminal now: :func:`say` takes them away first.
_OPEN: set[ProgressBars] = set()


def say(message: str) -> None:
    """``message`` on stderr, on a line of its own while bars are drawn: their block is
    erased first and drawn again under it at the next episode (a worker's death said while
    the bars were drawn began mid-line, glued to the last bar's text)."""
    for bars in list(_OPEN):
        bars.take_away()
    print(message, file=sys.stderr)


def end_bars(bars: Sequence[object]) -> None:
    """End the line the last drawn of ``bars`` left open on a terminal (an evaluation that
    stopped before its last episode: Ctrl-C, a lost cluster), so that what is said next
    starts a line of its own: it followed the bar, ``ETA 567s^Cresults written to ...``."""
    drawn = [bar for bar in bars if isinstance(getattr(bar, "drawn", None), tuple)]
    last: Any = max(drawn, key=lambda bar: getattr(bar, "drawn", (-1,))[0], default=None)
    if isinstance(last, ProgressBars):
        last.end()
    elif last is not None and last.drawn[1]:  # any progress callable without it draws no bar
        last.stream.write("\n")
        last.stream.flush()
        last.drawn = (last.drawn[0], False)
