"""The non-associative limit analysis against the pushover: its start from the joints'
elastic state (``selection.elastic_state``, ``least_energy_frozen``) and what its reason
proves (the associative multiplier above it)."""

from __future__ import annotations

import pytest

import masonry_dem as md
from masonry_dem.solvers.limit_analysis import limit_analysis
from masonry_dem.studies.corpus import random_wall

#: generated walls of the agreement corpus (``benchmarks/agreement.py``) of at most 29 blocks
#: with a reference collapse, every class the generator draws but openings in plane (none
#: that small): in and out of plane, held on one or both edges, openings with lintels, L
#: walls. The fast subset: the whole test takes about a minute on one idle core.
SMALL_WALLS = (
    5, 8, 10, 12, 17, 22, 30, 34, 36, 37, 44, 49, 50, 51, 60, 65, 70, 85, 100, 113, 114,
    118, 126, 136, 141, 142, 143, 150, 151, 154, 161,
)  # fmt: skip
#: of the 31, within 10 % of the pushover: 23 measured (docs/limit_analysis.md), 13 from the
#: associative start; the floor leaves two walls to a solver's other optimum elsewhere
WITHIN_TEN_PERCENT_AT_LEAST = 21


def test_a_course_tips_block_by_block_with_no_friction_in_its_head_joints():
    """A single course of 13 blocks on a base, its left block held in u1 and u3, tilted out
    of plane (generated wall w005): with joints that do not dilate, nothing presses the head
    joints, so every free block tips on its own at s / a (the pushover's 0.41474). From the
    associative collapse, whose head joints are clamped by a self-stress that dilatancy
    holds, the iteration keeps part of that friction (0.767 measured)."""
    model = random_wall(5).build()
    a, s = model.blocks.sizes[0, 1], model.blocks.sizes[0, 2]
    r = limit_analysis(model, associative=False)
    assert r.status == "collapse", r.reason
    assert r.load_factor == pytest.approx(s / a, rel=2e-3)  # the 8-face pyramid, grid 8
    assert r.info["start"] == "elastic"
    assert "heuristic estimate" in r.reason and "Radenkovic" in r.reason
    old = limit_analysis(model, associative=False, start="associative")
    assert old.status != "collapse" or old.load_factor > 1.5 * s / a


def test_the_start_is_checked():
    with pytest.raises(ValueError, match="start"):
        limit_analysis(random_wall(8).build(), associative=False, start="dead load")


@pytest.mark.slow
def test_against_the_pushover_on_thirty_one_generated_walls():
    """Each wall's non-associative multiplier, where it finds one, lies at or below the
    associative multiplier its reason quotes (Radenkovic: the proven side) and calls itself
    an estimate; at least ``WITHIN_TEN_PERCENT_AT_LEAST`` of the 31 lie within 10 % of the
    pushover's. The rest, measured: five walls held on both edges get "no collapse" (rigid
    blocks arch between the held columns), two slender in-plane walls lie 15-17 % above (the
    associative multiplier too: no friction is involved) and one held wall of friction 9.6
    settles 3.9 times above."""
    within = []
    for seed in SMALL_WALLS:
        model = random_wall(seed).build()
        pushover = md.pushover(model).collapse_multiplier
        r = limit_analysis(model, associative=False)
        assert r.status in ("collapse", "no collapse", "failed"), r.reason
        if r.status != "collapse":
            continue
        assert "heuristic estimate" in r.reason, r.reason
        assert r.load_factor <= r.info["associative"] * (1 + 1e-9), r.reason
        if pushover is not None and abs(r.load_factor / pushover - 1) <= 0.10:
            within.append(seed)
    assert len(within) >= WITHIN_TEN_PERCENT_AT_LEAST, within
