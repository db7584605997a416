"""Orientation: the ladder of marks is found among other rows of parallel lines."""

from __future__ import annotations

import math

from streamread.orientation import Segment, find_ladders


def _row(n: int, axis_deg: float, bar_deg: float, start: tuple[float, float], step: float, length: float,
         thickness: float = 1.5) -> list[Segment]:
    a = math.radians(axis_deg)
    return [Segment(start[0] + k * step * math.cos(a), start[1] + k * step * math.sin(a), length, thickness, bar_deg)
            for k in range(n)]


def test_marks_are_not_crowded_out_by_rows_of_long_lines() -> None:
    # a syringe at 135 degrees: its walls, ribs and a cable make three rows of long lines along the
    # axis (bars at 135 degrees, stacked across it), ahead of the marks (bars at 45 degrees) in the
    # angle histogram; the 30 marks must still come out as the best ladder, with the right axis
    clutter = []
    for i, (x, y) in enumerate(((100.0, 100.0), (300.0, 100.0), (100.0, 300.0))):
        clutter += _row(14, 45.0, 135.0, (x, y), 4.0, 60.0 + 10 * i)
    marks = _row(30, 135.0, 45.0, (400.0, 100.0), 12.0, 10.0)
    ladders = find_ladders(clutter + marks)
    assert ladders, "no ladder found"
    best = ladders[0]
    assert len(best.segments) == 30
    assert min(abs(best.axis_angle_deg - 135.0), abs(best.axis_angle_deg - 315.0)) < 2.0


def test_sealing_edge_is_the_steepest_rise_from_rubber_to_barrel() -> None:
    import numpy as np

    from streamread.indicator import _sealing_edge

    # rows 0-19 rubber (a lighter stretch between ribs at 8-10), sharp edge at 20 to the barrel,
    # then the background behind the barrel darkens at 28 (a table edge): the edge is at 20
    profile = np.full(40, 200.0)
    profile[:20] = 30.0
    profile[8:11] = 90.0
    profile[20] = 115.0  # half-way at the edge
    profile[28:] = 120.0
    edge = _sealing_edge(profile[2:39].tolist(), level=115.0, outward=1)  # rows 2-38
    assert edge is not None and abs(2 + edge - 20.0) < 0.5
    # the same stopper facing the other way
    edge = _sealing_edge(profile[::-1][1:38].tolist(), level=115.0, outward=-1)  # rows 1-37
    assert edge is not None and abs(1 + edge - 19.0) < 0.5


def test_the_rows_in_frame_end_where_the_bore_leaves_the_image() -> None:
    import numpy as np

    from streamread.orientation import rows_in_frame
    from streamread.types import Upright

    # a strip running down the image from row -100 (above the frame) to row 499 (past its foot
    # at 399), columns 200-259: rows 100-499 of the strip are the image's rows 0-399
    upright = Upright(angle_deg=90.0, to_upright=np.array([[1.0, 0.0, -200.0], [0.0, 1.0, 100.0]]),
                      strip_wh=(60, 600))
    assert rows_in_frame(upright, (20.0, 40.0), (400, 640)) == (100, 499)
    # a bore past the frame's right edge (column 700) is seen on no row
    assert rows_in_frame(upright, (20.0, 500.0), (400, 640)) == (0, -1)
