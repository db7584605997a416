"""Orientation: the ladder of marks is found among other rows of parallel lines."""

from __future__ import annotations

import math

import numpy as np

from streamread.orientation import Segment, angle_distance, faint_segments, find_ladders, linear_contours
from streamread.segment import threshold_response, thin_response, to_gray, valley_response
from streamread.synth import render_still


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


def test_a_faint_line_responds_in_its_own_direction_and_an_edge_not_at_all() -> None:
    image = np.full((60, 60), 180, np.uint8)
    image[29:31, 10:50] = 150  # a faint horizontal line, 2 px thick
    along = valley_response(image, 0.0)
    across = valley_response(image, 90.0)
    assert along[29:31, 20:40].min() >= 20  # nearly its 30 grey levels
    assert across[29:31, 20:40].max() <= 2
    edge = np.full((60, 60), 180, np.uint8)
    edge[30:] = 100  # a step: darker on one side only
    assert max(float(valley_response(edge, a).max()) for a in (0.0, 45.0, 90.0, 135.0)) <= 1.0


def test_faint_marks_the_threshold_loses_are_found_as_faint_lines() -> None:
    # dev seed 1296, a small 5 ml syringe: its marks, 6 px apart and faint, make no ladder along
    # its axis as plain linear contours, and the best one as faint lines
    image, truth = render_still(1296)
    (x0, y0), (x1, y1) = truth.axis_px
    axis_deg = math.degrees(math.atan2(y1 - y0, x1 - x0)) % 180.0
    gray = to_gray(image)

    def off_axis(angle: float) -> float:
        return angle_distance(angle, axis_deg)

    segments = []
    for k in (5, 11):
        response = thin_response(gray, k)
        for r in (response.dark, response.bright):
            segments += linear_contours(threshold_response(r), 2.5, 4.0)
    assert all(off_axis(lad.axis_angle_deg) > 5.0 for lad in find_ladders(segments))
    faint = find_ladders(faint_segments(gray, 2.5, 4.0))
    assert faint and off_axis(faint[0].axis_angle_deg) <= 3.0
    assert len(faint[0].segments) >= 15  # of its 26 marks
