"""Plane geometry for the simulator, in millimetres and radians, on plain tuples of floats.

Kept to tuples and floats (no classes, no numpy) because the hot loop calls these a few times
per 15 ms step and the simulator must run three orders of magnitude faster than real time.

A segment is ``(ax, ay, bx, by)``; a polygon is a tuple of ``(x, y)`` vertices, closed
implicitly (the last vertex joins the first).
"""

from __future__ import annotations

import math

Point = tuple[float, float]
Segment = tuple[float, float, float, float]
Polygon = tuple[Point, ...]


def polygon_edges(polygon: Polygon) -> tuple[Segment, ...]:
    """The edges of a closed polygon."""
    n = len(polygon)
    return tuple(
        (polygon[i][0], polygon[i][1], polygon[(i + 1) % n][0], polygon[(i + 1) % n][1])
        for i in range(n)
    )


def closest_point(px: float, py: float, seg: Segment) -> tuple[float, float, float]:
    """The point of ``seg`` closest to ``(px, py)`` and the squared distance to it."""
    ax, ay, bx, by = seg
    dx = bx - ax
    dy = by - ay
    length_sq = dx * dx + dy * dy
    if length_sq == 0.0:
        cx, cy = ax, ay
    else:
        t = ((px - ax) * dx + (py - ay) * dy) / length_sq
        if t <= 0.0:
            cx, cy = ax, ay
        elif t >= 1.0:
            cx, cy = bx, by
        else:
            cx, cy = ax + t * dx, ay + t * dy
    ex = px - cx
    ey = py - cy
    return cx, cy, ex * ex + ey * ey


def distance_sq_to_segment(px: float, py: float, seg: Segment) -> float:
    return closest_point(px, py, seg)[2]


def point_in_polygon(px: float, py: float, polygon: Polygon) -> bool:
    """Even-odd rule; points on an edge may fall either way."""
    inside = False
    n = len(polygon)
    jx, jy = polygon[n - 1]
    for ix, iy in polygon:
        if (iy > py) != (jy > py) and px < (jx - ix) * (py - iy) / (jy - iy) + ix:
            inside = not inside
        jx, jy = ix, iy
    return inside


def wrap_angle(angle: float) -> float:
    """``angle`` in radians, wrapped into -pi..pi."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def segments_meet(p: Point, q: Point, r: Point, s: Point) -> bool:
    """Whether the closed segments pq and rs have a point in common."""

    def turn(a: Point, b: Point, c: Point) -> float:
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    def within(a: Point, b: Point, c: Point) -> bool:  # c on the line ab: between a and b?
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and (
            min(a[1], b[1]) <= c[1] <= max(a[1], b[1])
        )

    d1, d2, d3, d4 = turn(r, s, p), turn(r, s, q), turn(p, q, r), turn(p, q, s)
    if ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4)):
        return True
    return (
        (d1 == 0 and within(r, s, p))
        or (d2 == 0 and within(r, s, q))
        or (d3 == 0 and within(p, q, r))
        or (d4 == 0 and within(p, q, s))
    )
