"""An episode's trajectory as a results record keeps it and ``eval --plot`` draws it.

The simulator keeps a point every fourth step (and the evaluation every second of those): a
20-minute episode's 40 000 points, where a few hundred draw the same path. An episode run for
a plot keeps only those (:attr:`~roomba_bt.evaluate.episode.EpisodeSpec.simplify_path`), so
that a sweep's parent holds and its workers send the path as drawn, not every point.
"""

from __future__ import annotations

from collections.abc import Iterable

#: how far (m) a kept path may stray from the trajectory: under a pixel of ``eval --plot``'s
#: figure (8 inches at 110 dpi for a room of 4 m or more: about 5 mm a pixel)
PATH_TOLERANCE_M = 0.005


def kept_path(trajectory: Iterable[tuple[float, float]]) -> tuple[tuple[float, float], ...]:
    """``trajectory`` (m) as a results record keeps it and ``eval --plot`` draws it: each
    point to the mm, a point the same as the one before left out, then the points a straight
    line between those kept passes within :data:`PATH_TOLERANCE_M` of left out
    (Ramer-Douglas-Peucker, the farthest point kept first). A 20-minute episode's 40 000
    points (one every two ticks) keep a few hundred, drawn the same. The same path given
    again is given back as it is (the farthest point of a part is kept, and what it left out
    is not there to be found again), so a record read back and written again, or drawn,
    is the same path."""
    points: list[tuple[float, float]] = []
    for x, y in trajectory:
        point = (round(x, 3), round(y, 3))
        if not points or points[-1] != point:
            points.append(point)
    if len(points) < 3:
        return tuple(points)
    keep = [False] * len(points)
    keep[0] = keep[-1] = True
    parts = [(0, len(points) - 1)]
    tolerance = PATH_TOLERANCE_M * PATH_TOLERANCE_M
    while parts:
        first, last = parts.pop()
        (ax, ay), (bx, by) = points[first], points[last]
        dx, dy = bx - ax, by - ay
        chord = dx * dx + dy * dy
        farthest, at = -1.0, -1
        for i in range(first + 1, last):
            px, py = points[i]
            if chord == 0.0:  # a loop back to where the part began: from that point
                far = (px - ax) ** 2 + (py - ay) ** 2
            else:
                cross = dx * (py - ay) - dy * (px - ax)
                far = cross * cross / chord
            if far > farthest:
                farthest, at = far, i
        if farthest > tolerance:
            keep[at] = True
            parts += [(first, at), (at, last)]
    return tuple(point for point, kept in zip(points, keep, strict=True) if kept)
