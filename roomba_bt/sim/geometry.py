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

INFINITY = math.inf


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


def ray_hit(ox: float, oy: float, dx: float, dy: float, seg: Segment) -> float:
    """Distance along the unit ray ``(ox, oy) + t (dx, dy)`` to ``seg``; infinity if none."""
    ax, ay, bx, by = seg
    ex = bx - ax
    ey = by - ay
    denom = dx * ey - dy * ex
    if denom == 0.0:
        return INFINITY
    wx = ax - ox
    wy = ay - oy
    t = (wx * ey - wy * ex) / denom
    if t < 0.0:
        return INFINITY
    u = (wx * dy - wy * dx) / denom
    if u < 0.0 or u > 1.0:
        return INFINITY
    return t


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


def bounding_box(polygon: Polygon) -> tuple[float, float, float, float]:
    xs = [p[0] for p in polygon]
    ys = [p[1] for p in polygon]
    return min(xs), min(ys), max(xs), max(ys)


def segments_intersect(a: Segment, b: Segment) -> bool:
    """True if the two segments cross or touch."""

    def orient(px: float, py: float, qx: float, qy: float, rx: float, ry: float) -> float:
        return (qx - px) * (ry - py) - (qy - py) * (rx - px)

    ax, ay, bx, by = a
    cx, cy, dx, dy = b
    d1 = orient(cx, cy, dx, dy, ax, ay)
    d2 = orient(cx, cy, dx, dy, bx, by)
    d3 = orient(ax, ay, bx, by, cx, cy)
    d4 = orient(ax, ay, bx, by, dx, dy)
    return (d1 * d2 <= 0.0) and (d3 * d4 <= 0.0)


def wrap_angle(angle: float) -> float:
    """``angle`` in radians, wrapped into -pi..pi."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi
