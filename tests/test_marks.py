"""Major/minor grouping by relative length (the paper's 15 % jump) and stray bars, on hand-made ladders."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from streamread.fit import fit_scale
from streamread.marks import (
    _spacing_near,
    _walk,
    Bar,
    anchored_runs,
    bars_from_mask,
    best_marks,
    clearest_plane,
    fit_grid,
    group_by_length,
    in_column,
    kernel_for,
    ladder_quality,
    major_step,
    majors_at_labels,
    print_plane,
    segment_bars,
)
from streamread.profile import GroupingConfig, default_profile
from streamread.types import Mark, Marks, OcrRead


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


def test_a_long_mark_not_seen_does_not_double_the_major_step() -> None:
    # seed 1129: a 50 ml cylinder whose "40" long mark lies behind a post; the long marks seen
    # are 20 steps apart and the medium marks at 5 and 15 halve a 10-step lattice. Taken as 20
    # steps, the labels' height was looked for over twice their spacing (a liquid's edge was
    # taken for the text) and the long marks' values 50 and 30 were not round
    grouped = group_by_length(_ladder({0: 57.0, 20: 59.0, 5: 42.0, 15: 42.0}, 22, minor_px=26.0), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == [0, 20]
    assert major_step(grouped) == 10


def test_medium_marks_off_the_half_way_phase_keep_the_major_step() -> None:
    # held-out 2103: a burette whose grid miscounted; mediums at 57 and 62 beside long marks at
    # 14 and 54 are no lattice of 10, and the step stays 40 (the fit then refuses the scale)
    tiers = {14: "major", 54: "major", 57: "medium", 62: "medium"}
    marks = Marks(marks=tuple(Mark(y_up=100 + 8.3 * k, x0_up=170.0, x1_up=200.0, thickness_up=1.5,
                                   tier=tiers.get(k, "minor"), grid_index=k) for k in range(70)),  # type: ignore[arg-type]
                  spacing_up=8.3)
    assert major_step(marks) == 40


def test_without_a_regular_series_the_longest_group_is_kept() -> None:
    # two long bars only: nothing regular to find, the paper's rule stands
    grouped = group_by_length(_ladder({3: 40.0, 17: 41.0}, 30), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == [3, 17]


def test_two_long_marks_stay_the_majors_over_a_medium_between_them() -> None:
    # seed 1282 of the still benchmark: a 50 ml cylinder cropped to two labelled marks and the
    # medium mark between them; adding the medium would halve the label spacing
    grouped = group_by_length(_ladder({0: 60.0, 10: 62.0, 5: 46.0}, 16, minor_px=30.0), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == [0, 10]


def test_lengths_that_creep_leave_the_majors_to_the_longer_lattice() -> None:
    # img_029 of the real set seen whole: the labelled ring marks measure 25-35 px where the
    # light darkens them, the ticks 22 px; three ring marks at 41-42 px fall every 15 steps by
    # chance. No jump of 15 % parts 28 from 22 (25 sits between), and 15 steps is no scale's
    # major step: the majors are the lattice of longer marks every 5
    lengths = {1: 35.0, 6: 28.0, 11: 28.0, 16: 42.0, 21: 27.0, 26: 27.0, 31: 41.0, 36: 26.0, 41: 25.0, 0: 42.0}
    grouped = group_by_length(_ladder(lengths, 45), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == list(range(1, 45, 5))


def test_the_lattice_is_counted_over_the_scale_not_a_stray_far_off_it() -> None:
    # img_029 again, as the still reader cuts it: a label's rule under the foot lies on the grid
    # 14 steps past the last mark (749 px), and a speck beside it. Counted to them, the lattice
    # of every 5th mark filled under 80 % of its positions and no majors were found
    lengths = {1: 35.0, 6: 28.0, 11: 28.0, 16: 42.0, 21: 27.0, 26: 27.0, 31: 41.0, 36: 26.0, 41: 25.0, 0: 42.0}
    scale = _ladder(lengths, 45)
    strays = tuple(Mark(y_up=100 + 8.3 * k, x0_up=170.0, x1_up=170.0 + length, thickness_up=1.5, grid_index=k)
                   for k, length in ((58, 749.0), (59, 3.0)))
    grouped = group_by_length(Marks(marks=scale.marks + strays, spacing_up=8.3), GroupingConfig())
    assert sorted(m.grid_index for m in grouped.majors) == list(range(1, 45, 5))


def test_bars_on_two_grid_lines_only_are_no_ladder() -> None:
    # a long line broken into pieces on two rows (a label's rules): twelve bars, two grid steps.
    # A quadratic through two positions is no grid (numpy warned "poorly conditioned")
    bars = [Bar(y=100.0 + 10.0 * (k % 2), x0=30.0 * k, x1=30.0 * k + 20.0, thickness=1.5, strength=50.0)
            for k in range(12)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert fit_grid(bars, default_profile("measuring_cylinder").marks) is None


def _ticks_and_a_curved_ring() -> np.ndarray:
    """Ticks 8 px apart over columns 10-30, and at the 10th a ring across the bore (columns
    10-90) seen curved: on the ticks' row over their columns, bending 6 px down towards the far
    wall, so that its centroid lies 2 px (a quarter of a division) off the grid."""
    mask = np.zeros((200, 120), np.uint8)
    for k in range(21):
        if k != 10:
            mask[20 + 8 * k: 22 + 8 * k, 10:31] = 255
    for x in range(10, 91):
        y = int(round(100 + 6 * ((x - 10) / 80) ** 2))
        mask[y: y + 2, x] = 255
    return mask


@pytest.mark.parametrize("rings", [False, True])
def test_a_curved_ring_is_placed_by_its_row_over_the_ticks_where_rings_are_expected(rings: bool) -> None:
    # clean 9189, 9587 (50 ml burettes): the rings dropped, the numbers beside them went to the
    # half-ml ticks five divisions off. Where the profile says the long marks are rings
    # (burettes), the ring is a mark on its grid line, at its row over the ticks' columns
    mask = _ticks_and_a_curved_ring()
    config = replace(default_profile("burette").marks, rings=rings)
    marks = fit_grid(bars_from_mask(mask, mask, config), config)
    assert marks is not None
    ring = [m for m in marks.marks if m.x1_up > 80]
    if not rings:
        assert not ring  # off the grid: dropped, as on cylinders and syringes
        return
    assert len(ring) == 1
    ticks = {m.grid_index: m.y_up for m in marks.marks if m.x1_up <= 31}
    assert ring[0].grid_index - 1 in ticks and ring[0].grid_index + 1 in ticks
    # on the grid: half way between its neighbours, within a tenth of a division
    assert abs(ring[0].y_up - (ticks[ring[0].grid_index - 1] + ticks[ring[0].grid_index + 1]) / 2) < 0.8


def test_only_burette_profiles_expect_rings() -> None:
    assert default_profile("burette").marks.rings
    assert not default_profile("measuring_cylinder").marks.rings and not default_profile("syringe").marks.rings


def test_a_long_series_with_most_of_its_rows_empty_scores_below_a_full_one() -> None:
    # dev 1201: the light gaps between a 10 ml cylinder's marks made a ladder of 44, two of them
    # a little longer ten steps apart; the dark marks, one more, had a long mark every five
    # steps. Scored by count alone the gaps won (numbers read beside them: no reading); a series
    # holding under half of its lattice's rows counts for that share, doubled
    # (there, three of the dark marks were missed: 45 on 48 rows)
    gaps = group_by_length(_ladder({12: 30.0, 22: 30.0}, 44), GroupingConfig())
    full = _ladder({k: 30.0 for k in range(0, 48, 5)}, 48)
    dark = group_by_length(replace(full, marks=tuple(m for m in full.marks if m.grid_index not in (7, 18, 33))),
                           GroupingConfig())
    assert len(gaps.majors) == 2 and len(dark.majors) == 10
    assert ladder_quality(dark) > ladder_quality(gaps)
    assert ladder_quality(gaps) == pytest.approx(44 * 0.8)  # two long rows held of five: 0.4, doubled
    # a full series keeps its whole score, and so does one with half its long marks or more seen
    # (seed 1459: 5 of 7, the others unseen; counted at 5/7 it lost to a ladder of fewer marks)
    assert ladder_quality(dark) == pytest.approx(45 * 45 / 48)
    partly = group_by_length(_ladder({k: 30.0 for k in (0, 10, 20, 40, 60)}, 61), GroupingConfig())
    assert major_step(partly) == 10 and len(partly.majors) == 5
    assert ladder_quality(partly) == pytest.approx(61.0)


def test_the_walk_starts_from_the_spacing_about_the_middle() -> None:
    # dev 1264: a 50 ml burette seen at a slant, its marks 5.7 px apart at the far end and 7.5 px
    # at the near one; the comb's one spacing was 7.2 px, 13 % over the spacing where the walk
    # began (with the bars' own jitter besides). Started from a comb's spacing off by more
    # (here 30 %), the walk took six divisions for five where they are short; from the
    # spacing about the middle it takes every bar in turn
    spacing = np.linspace(5.7, 7.5, 100)
    ys = 100.0 + np.concatenate([[0.0], np.cumsum(spacing[:-1])])
    bars = [Bar(y=float(y), x0=100.0, x1=115.0, thickness=1.5, strength=60.0) for y in ys]
    assert _spacing_near(bars, 50, 8.5) == pytest.approx(spacing[50], abs=0.1)
    assert _spacing_near(bars, 50, 20.0) == 20.0  # no gap near the ladder's: its own spacing
    walked = dict(_walk(bars, 8.5))
    assert [walked[k].y for k in sorted(walked)] == pytest.approx(list(ys))


def _slanted_bars(count: int, hidden: range = range(0)) -> tuple[list[Bar], np.ndarray]:
    """Bars of a scale seen at a slant (7.6 px apart at one end, 6.6 at the other, as clean
    11908's 1 ml syringe) with the grid steps ``hidden`` left out (a stopper over them); and
    every step's row."""
    spacing = np.linspace(7.6, 6.6, count)
    ys = 100.0 + np.concatenate([[0.0], np.cumsum(spacing[:-1])])
    bars = [Bar(y=float(y), x0=100.0, x1=115.0, thickness=1.5, strength=60.0)
            for k, y in enumerate(ys) if k not in hidden]
    return bars, ys


def test_the_walk_crosses_a_stopper_eight_divisions_long() -> None:
    # clean 11908: a 1 ml syringe's stopper hid 8 of its 0.01 ml divisions; the walk took no
    # stride over six steps, stopped there and lost the 36 marks past it
    hidden = range(44, 52)
    bars, ys = _slanted_bars(90, hidden)
    walked = dict(_walk(bars, 7.1))
    assert len(walked) == len(bars)
    k0 = min(walked)
    assert all(walked[k].y == pytest.approx(ys[k - k0]) for k in walked)  # each bar on its own step


def test_the_walk_does_not_stride_onto_a_run_spaced_otherwise() -> None:
    # clean 11807: past a 1 ml syringe's stopper, nine divisions on, a run of bars 6.3 px apart
    # beside marks 5.8 px apart: the stride's count of steps is not to be trusted over it
    marks = [Bar(y=300.0 + 5.8 * k, x0=100.0, x1=115.0, thickness=1.5, strength=60.0) for k in range(40)]
    other = [Bar(y=300.0 - 9 * 5.8 - 6.3 * k, x0=100.0, x1=115.0, thickness=1.5, strength=60.0) for k in range(16)]
    walked = dict(_walk(sorted(marks + other, key=lambda b: b.y), 5.8))
    assert sorted(b.y for b in walked.values()) == pytest.approx(sorted(b.y for b in marks))


def test_the_walk_does_not_start_from_a_stray_in_the_middle() -> None:
    # clean 11908: the middle bar was a stroke of the "0.5" beside the marks, 1.5 px off its
    # step; from it every mark lay off the walk's steps and the walk placed that bar alone
    bars, ys = _slanted_bars(81)
    stray = Bar(y=float(ys[40]) + 2.0, x0=90.0, x1=98.0, thickness=1.5, strength=60.0)
    bars = sorted([*bars, stray], key=lambda b: b.y)
    assert bars[len(bars) // 2] is stray
    walked = dict(_walk(bars, 7.1))
    assert stray not in walked.values()
    assert len(walked) == len(ys)
    assert fit_grid(bars, default_profile("syringe").marks) is not None
    assert len(fit_grid(bars, default_profile("syringe").marks)) == len(ys)


def _cylinder_marks(extra: list[int]) -> Marks:
    """Forty marks 8 px apart, every fifth long and numbered (value = top - 0.2 per step down),
    and ``extra`` bars on grid lines further down."""
    ks = list(range(40)) + extra
    marks = Marks(marks=tuple(Mark(y_up=50 + 8.0 * k, x0_up=100.0, x1_up=130.0 if k % 5 == 0 else 118.0,
                                   thickness_up=1.5, tier="major" if k % 5 == 0 else "minor", grid_index=k)
                              for k in ks), spacing_up=8.0)
    return marks


def _reads(top: float) -> list[OcrRead]:
    return [OcrRead(y_up=50 + 8.0 * k, text=f"{top - 0.2 * k:g}", value=round(top - 0.2 * k, 6), confidence=90.0)
            for k in range(0, 40, 5)]


def test_a_lone_bar_past_the_zero_is_not_a_mark() -> None:
    # img_029 and seed 1047: a cylinder's foot (or rim) on a grid line a dozen steps past the
    # last mark valued the scale below zero, and the whole calibration was refused
    marks = _cylinder_marks([52, 53])
    fit, why = fit_scale(marks, _reads(9.0), min_reads=2)
    assert fit is not None, why
    assert len(fit.mark_y_up) == 40 and min(fit.mark_values) == pytest.approx(1.2)


def test_lone_marks_within_the_scale_are_kept() -> None:
    # marks seen past a syringe's stopper come in ones and twos too: on the scale, they stay
    marks = _cylinder_marks([52, 53])
    fit, why = fit_scale(marks, _reads(12.0), min_reads=2)
    assert fit is not None, why
    assert len(fit.mark_y_up) == 42 and min(fit.mark_values) == pytest.approx(1.4)



def _gapped(spacing_px: list[float], hidden: set[int], misnumbered_by: int) -> tuple[Marks, list[int]]:
    """A ladder whose spacing grows (perspective), long marks every 5, the marks in ``hidden``
    unseen (a stopper, a label), and every mark past the first hidden one misnumbered by
    ``misnumbered_by``, as the grid's curve does when it is extrapolated over the gap. Returns
    it and the true grid indices of the marks seen."""
    ys = np.concatenate([[100.0], 100.0 + np.cumsum(spacing_px[:-1])])
    first_hidden = min(hidden)
    marks, truth = [], []
    for k, y in enumerate(ys):
        if k in hidden:
            continue
        major = k % 5 == 0
        marks.append(Mark(y_up=float(y), x0_up=170.0, x1_up=210.0 if major else 190.0, thickness_up=1.5,
                          tier="major" if major else "minor",
                          grid_index=k + (misnumbered_by if k > first_hidden else 0)))
        truth.append(k)
    return Marks(marks=tuple(marks), spacing_up=spacing_px[0]), truth


# a 3 ml syringe seen at an angle (seed 1038): 15 marks, a stopper hiding 7, three marks with
# no long one among them, a gap, then two marks with a long one, on a growing spacing
GAPS = set(range(15, 22)) | set(range(25, 29))


@pytest.mark.parametrize("off", [-2, -1, 1, 2])
def test_marks_past_a_gap_are_counted_by_the_long_marks(off: int) -> None:
    # the runs past the gaps, numbered off by a step or two, are put back on the long marks'
    # lattice, and the run with no long mark is placed by the curve through the others
    marks, truth = _gapped(list(np.linspace(11.7, 13.4, 33)), GAPS, off)
    assert [m.grid_index for m in marks.marks] != truth
    assert [m.grid_index for m in anchored_runs(marks).marks] == truth


def _past_the_gap_tiered_short(marks: Marks) -> Marks:
    """``marks`` as grouping by length leaves them when the grid misnumbered the runs past the
    gap: their long marks fell off the lattice and were tiered with the short ones."""
    first_hidden = min(GAPS)
    return Marks(marks=tuple(replace(m, tier="minor") if m.y_up > marks.marks[first_hidden - 1].y_up else m
                             for m in marks.marks), spacing_up=marks.spacing_up)


@pytest.mark.parametrize("off", [-1, 1])
def test_long_marks_past_a_gap_tiered_short_still_count_by_their_length(off: int) -> None:
    # dev 1004: a 1 ml syringe's "0.1" and "0" marks past its stopper, twice as long as the
    # ticks beside them, tiered "minor", left the run a division off
    marks, truth = _gapped(list(np.linspace(11.7, 13.4, 33)), GAPS, off)
    marks = _past_the_gap_tiered_short(marks)
    assert [m.grid_index for m in anchored_runs(marks).marks] == truth


def test_a_bar_beside_the_scale_past_a_gap_is_not_a_long_mark() -> None:
    # dev 1285: a bar as long as a mark but a scale's width to the side shifted the run past
    # the stopper, numbered right by the curve, a step off
    marks, _ = _gapped(list(np.linspace(11.7, 13.4, 33)), GAPS, 0)
    marks = _past_the_gap_tiered_short(marks)
    # the last run's own long mark (k = 30) unseen, a bar beside the scale a step past its end
    seen = tuple(m for m in marks.marks if m.grid_index != 30)
    last = max(seen, key=lambda m: m.grid_index)
    stray = replace(last, y_up=last.y_up + 13.4, x0_up=300.0, x1_up=340.0, grid_index=last.grid_index + 1)
    with_stray = Marks(marks=seen + (stray,), spacing_up=marks.spacing_up)
    assert anchored_runs(with_stray) is with_stray


def test_a_ladder_on_its_lattice_is_left_as_it_is() -> None:
    marks, _ = _gapped(list(np.linspace(11.7, 13.4, 33)), GAPS, 0)
    assert anchored_runs(marks) is marks


def _one_ml(seen: range, run: range, misnumbered_by: int, mediums: bool) -> tuple[Marks, list[int]]:
    """A 1 ml syringe's ladder as clean 10212 and 10473 had it: long marks every 10 (and, with
    ``mediums``, a medium one half-way), a spacing growing from 5.1 to 5.6 px, the marks in
    ``seen`` and then the ``run`` past a stopper, that run numbered ``misnumbered_by`` off.
    Returns it and the true grid indices of its marks."""
    ys = 100.0 + np.concatenate([[0.0], np.cumsum(np.linspace(5.1, 5.6, 80))])
    marks, truth = [], []
    for k in [*seen, *run]:
        tier = "major" if k % 10 == 0 else ("medium" if mediums and k % 10 == 5 else "minor")
        marks.append(Mark(y_up=float(ys[k]), x0_up=170.0, x1_up={"major": 200.0, "medium": 190.0}.get(tier, 182.0),
                          thickness_up=1.2, tier=tier, grid_index=k + (misnumbered_by if k in run else 0)))
        truth.append(k)
    return Marks(marks=tuple(marks), spacing_up=5.1), truth


@pytest.mark.parametrize("off", [-1, 1])
def test_a_run_past_a_gap_is_counted_by_its_half_way_mark(off: int) -> None:
    # clean 10473: eight marks past a 1 ml syringe's stopper, the 0.25 mark the only one not
    # short among them, numbered a step off by the grid's curve; too few to count the gap by
    marks, truth = _one_ml(range(0, 36), range(52, 57), off, mediums=True)
    assert [m.grid_index for m in anchored_runs(marks).marks] == truth


@pytest.mark.parametrize(("run", "off"), [(range(51, 60), -1), (range(51, 60), 1), (range(51, 54), 2),
                                        (range(62, 66), -2)])
def test_a_run_with_no_long_mark_is_numbered_by_the_projective_curve(run: range, off: int) -> None:
    # clean 10212: nine short marks past the stopper, 19 steps past the last mark seen, which
    # the grid's quadratic made 20; 9676 and 9860: runs of three marks one and two steps off
    marks, truth = _one_ml(range(0, 36), run, off, mediums=False)
    assert [m.grid_index for m in anchored_runs(marks).marks] == truth
    right, _ = _one_ml(range(0, 36), run, 0, mediums=False)
    assert anchored_runs(right) is right


def test_a_run_between_the_steps_is_not_shifted_onto_them() -> None:
    # clean 9667: a stopper's ribs past the gap, half a step off the marks' lattice, numbered
    # as marks by the grid: no shift puts them on the curve, and none is made
    marks, _ = _one_ml(range(0, 36), range(51, 56), 1, mediums=False)
    spacing = marks.marks[-1].y_up - marks.marks[-2].y_up
    ribs = Marks(marks=tuple(replace(m, y_up=m.y_up + 0.5 * spacing) if m.grid_index > 40 else m for m in marks.marks),
                 spacing_up=marks.spacing_up)
    assert anchored_runs(ribs) is ribs


def _scale_on(background_bgr: tuple[int, int, int], print_bgr: tuple[int, int, int]) -> np.ndarray:
    """An upright strip, 300 x 120, of ``background_bgr`` with 21 marks of ``print_bgr`` 12 px
    apart from row 30 (2 px thick, 24 px long, every fifth 44 px long) from column 40."""
    strip = np.full((300, 120, 3), background_bgr, np.uint8)
    for k in range(21):
        y = 30 + 12 * k
        strip[y:y + 2, 40:(84 if k % 5 == 0 else 64)] = print_bgr
    rng = np.random.default_rng(0)
    return np.clip(strip + rng.normal(0, 3, strip.shape), 0, 255).astype(np.uint8)


def test_print_as_light_as_a_coloured_liquid_is_found_in_one_colour_plane() -> None:
    # blue print over orange liquid: both about 140 grey (seeds 1007, 1207: no scale of marks in
    # the luminance), but the print is 150 darker in the red plane
    strip = _scale_on(background_bgr=(40, 120, 220), print_bgr=(250, 150, 70))
    profile = default_profile("syringe")
    assert fit_grid(segment_bars(strip, profile.marks, kernel_for(12.0))["dark"], profile.marks) is None
    marks, path = best_marks(strip, profile.marks, profile.grouping, kernel_for(12.0))
    assert marks is not None and path == "dark-red"
    assert len(marks.marks) == 21 and marks.spacing_up == pytest.approx(12.0, abs=0.1)
    assert sorted(m.y_up for m in marks.majors) == pytest.approx([30.5, 90.5, 150.5, 210.5, 270.5], abs=0.5)
    assert print_plane(strip, path) is not None and print_plane(strip, path).mean() > 150  # the red plane


def test_the_kernel_is_shorter_than_a_division_down_to_its_least_height() -> None:
    assert kernel_for(12.0) == 11 and kernel_for(40.0) == 33
    assert kernel_for(2.5) == 5  # the usual least: a retry may go lower
    assert kernel_for(2.5, 3) == 3 and kernel_for(1.0, 3) == 3


def test_print_seen_in_the_luminance_is_not_looked_for_in_the_planes() -> None:
    marks, path = best_marks(_scale_on((200, 200, 200), (40, 40, 40)), default_profile("syringe").marks,
                             default_profile("syringe").grouping, kernel_for(12.0))
    assert marks is not None and path == "dark"


def test_the_plane_where_faint_marks_over_a_liquid_stand_out_is_chosen() -> None:
    # the lower half of the scale behind orange liquid, where blue print is as light as the
    # liquid in grey: the red plane shows those marks (the faintest quarter decides)
    strip = _scale_on(background_bgr=(200, 200, 200), print_bgr=(250, 150, 70))
    strip[150:] = _scale_on(background_bgr=(40, 120, 220), print_bgr=(250, 150, 70))[150:]
    profile = default_profile("syringe")
    marks, path = best_marks(strip, profile.marks, profile.grouping, kernel_for(12.0))
    assert marks is not None and not path.startswith("dark-")  # the marks over the glass suffice
    plane = clearest_plane(strip, marks)
    assert plane is not None and np.array_equal(plane, strip[:, :, 2])
    # black print on grey glass: no plane beats the luminance
    plain = _scale_on((200, 200, 200), (40, 40, 40))
    plain_marks, _ = best_marks(plain, profile.marks, profile.grouping, kernel_for(12.0))
    assert plain_marks is not None and clearest_plane(plain, plain_marks) is None


def test_faint_lines_on_the_grid_but_beside_the_scale_are_not_kept_as_marks() -> None:
    # img_020: the faint-line path keeps short lines on the grid's rows well beside the ticks (an
    # edge of the glass, a scratch); a long mark reaching past the ticks' columns stays
    scale = [Mark(y_up=100 + 15.0 * k, x0_up=212.0, x1_up=272.0 if k % 10 == 0 else 228.0, thickness_up=2.0,
                  tier="major" if k % 10 == 0 else "minor", grid_index=k) for k in range(30)]
    strays = [Mark(y_up=550.0, x0_up=166.0, x1_up=173.0, thickness_up=2.0, tier="minor", grid_index=30),
              Mark(y_up=565.0, x0_up=351.0, x1_up=358.0, thickness_up=2.0, tier="minor", grid_index=31)]
    kept = in_column(Marks(marks=tuple(scale + strays), spacing_up=15.0))
    assert kept.marks == tuple(scale)


def _labels_every_10(count: int = 5, offset_px: float = 0.0,
                     height_px: float = 16.0) -> list[tuple[float, float, float | None]]:
    """Labels (centre row, height, no line) every 10 marks of ``_ladder``, from mark 5, each
    centred ``offset_px`` from its mark (0: beside it)."""
    return [(100 + 8.3 * (5 + 10 * i) + offset_px, height_px, None) for i in range(count)]


def test_labels_set_the_long_marks_every_ten_where_length_does_not() -> None:
    # the labelled marks no longer than the rest (faint lines seen short): length says nothing
    marks = _ladder({}, 50)
    relabelled = majors_at_labels(marks, _labels_every_10(), 10)
    assert relabelled is not None
    assert sorted(m.grid_index for m in relabelled.majors) == [5, 15, 25, 35, 45]
    assert majors_at_labels(relabelled, _labels_every_10(), 10) is None  # those are the long marks already
    assert majors_at_labels(marks, _labels_every_10(count=2), 10) is None  # two labels are too few


def test_a_plainly_longer_mark_beside_a_label_off_the_phase_leaves_it_out() -> None:
    # the grid lost a step under the last label: its own mark (twice as long) is off the phase
    marks = _ladder({5: 40, 15: 40, 25: 40, 35: 40, 44: 44}, 50)
    labels = _labels_every_10()
    labels[-1] = (100 + 8.3 * 44, 16.0, None)
    relabelled = majors_at_labels(marks, labels, 10)
    assert relabelled is not None
    assert sorted(m.grid_index for m in relabelled.majors) == [5, 15, 25, 35]


def test_a_label_whose_mark_lies_elsewhere_than_the_others_is_left_out() -> None:
    # the labels drift along the marks (a miscounted grid): the last stands 12 px off where the others do
    # (from its mark on the phase, the nearest to it)
    marks = _ladder({}, 50)
    labels = _labels_every_10()
    labels[-1] = (labels[-1][0] - 12.0, 16.0, None)
    relabelled = majors_at_labels(marks, labels, 10)
    assert relabelled is not None
    assert sorted(m.grid_index for m in relabelled.majors) == [5, 15, 25, 35]


def test_lines_across_labels_vote_only_where_three_lie_alike() -> None:
    marks = _ladder({}, 50)
    row = {k: 100 + 8.3 * k for k in range(50)}
    # three labels whose lines lie one mark below the centre's nearest mark: they set the phase
    alike = [(row[5] - 2.0, 16.0, row[6]), (row[15] - 2.0, 16.0, row[16]), (row[25] - 2.0, 16.0, row[26]),
             (row[35] - 2.0, 16.0, None)]
    relabelled = majors_at_labels(marks, alike, 10)
    assert relabelled is not None and sorted(m.grid_index for m in relabelled.majors) == [6, 16, 26, 36]
    # lines at rows unlike one another are ticks under a digit, not the labels' lines: ignored
    unlike = [(row[5] - 2.0, 16.0, row[6]), (row[15] - 2.0, 16.0, row[14]), (row[25] - 2.0, 16.0, row[27]),
              (row[35] - 2.0, 16.0, None)]
    by_length = majors_at_labels(marks, unlike, 10)
    assert by_length is not None and sorted(m.grid_index for m in by_length.majors) == [5, 15, 25, 35]
