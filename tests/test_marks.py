"""Major/minor grouping by relative length (the paper's 15 % jump), on hand-made ladders."""

from __future__ import annotations

from streamread.marks import group_by_length
from streamread.profile import GroupingConfig
from streamread.types import Mark, Marks


def _ladder(lengths: dict[int, float], count: int, minor_px: float = 22.0) -> Marks:
    marks = tuple(Mark(y_up=100 + 8.3 * k, x0_up=170.0, x1_up=170.0 + lengths.get(k, minor_px), thickness_up=1.5,
                       grid_index=k) for k in range(count))
    return Marks(marks=marks, spacing_up=8.3)


def test_labelled_marks_joined_by_their_digits_are_still_the_majors() -> None:
    # a 10 ml cylinder seen on real glass (img_029 of the real set): every 5th mark is a
    # labelled one, 28 px; where the digit touches the mark's end it measures 43 px; one stray
    # 44 px bar off the series (a line of the printed "ml")
    lengths = {k: 28.0 for k in range(5, 45, 5)}
    lengths.update({15: 43.0, 30: 42.0, 4: 44.0})
    grouped = group_by_length(_ladder(lengths, 46), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == list(range(5, 45, 5))


def test_a_regular_long_series_stays_major_without_its_mediums() -> None:
    lengths = {k: 30.0 for k in range(5, 60, 10)}
    lengths.update({k: 40.0 for k in range(0, 60, 10)})
    grouped = group_by_length(_ladder(lengths, 60), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == list(range(0, 60, 10))
    assert sorted(m.grid_index for m in grouped.marks if m.tier == "medium") == list(range(5, 60, 10))


def test_without_a_regular_series_the_longest_group_is_kept() -> None:
    # two long bars only: nothing regular to find, the paper's rule stands
    grouped = group_by_length(_ladder({3: 40.0, 17: 41.0}, 30), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == [3, 17]


def test_two_long_marks_stay_the_majors_over_a_medium_between_them() -> None:
    # seed 1282 of the still benchmark: a 50 ml cylinder cropped to two labelled marks and the
    # medium mark between them; adding the medium would halve the label spacing
    grouped = group_by_length(_ladder({0: 60.0, 10: 62.0, 5: 46.0}, 16, minor_px=30.0), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == [0, 10]
