"""The equal-time section's rules, without rendering: which fixed count is at equal time, the
verdict, the quick comparisons and the sheets' labels. (tests/test_gallery.py renders the
section.)"""
import pytest

from styletrace.frontends import equal_time as et
from styletrace.frontends.equal_time import Comparison


def test_pick_is_the_largest_count_not_slower_than_the_method():
    assert et.pick([0.10, 0.14, 0.22], 0.18) == 1
    assert et.pick([0.10, 0.14, 0.22], 0.14) == 1      # equal time counts as not slower
    # times measured out of order: still the largest n
    assert et.pick([0.10, 0.09, 0.30], 0.12) == 1
    assert et.pick([0.10, 0.14, 0.22], 5.0) == 2
    assert et.pick([0.30, 0.40], 0.12) == 0            # every count slower: the smallest


def test_only_a_strictly_lower_error_wins():
    assert et.verdict(1.5) == "win"
    assert et.verdict(1.0) == "loss"                   # the same error at the method's own cost
    assert et.verdict(0.4) == "loss"
    assert (
        et.ratio_of(0.2, 0.1) == 2.0
        and et.ratio_of(0.0, 0.0) == 1.0
        and et.ratio_of(0.1, 0.0) == float("inf")
    )


def test_quick_comparisons_keep_their_fixed_counts_below_a_small_reference():
    one = et.quick(Comparison("a", "a", "cel", {"inner": 4}, reference=4096))
    assert one.reference == et.QUICK_REFERENCE and one.counts == (4, 8, 16)[:et.QUICK_COUNTS]
    two = et.quick(Comparison("b", "b", "saturation", {"inner": "8:64,4"}, reference=(64, 64),
                              counts=(2, 4, 8, 16, 32), below=(4,)))
    # 8 would share the reference's 8 children
    assert two.reference == (8, 8) and two.counts == (2, 4)
    assert et.fixed_inner(two, 4) == (4, 4) and et.fixed_inner(one, 4) == 4
    tiny = et.quick(Comparison("c", "c", "cel", {"inner": 1}, reference=4, counts=(8, 16)))
    assert tiny.counts == (8,)  # never none at all


def entry(verdict, ratio):
    return {
        "key": "k",
        "title": "T",
        "scene": "cornell-box",
        "size": 32,
        "repeats": 1,
        "style": "cel",
        "params": {},
        "integrator": {},
        "reference": {"inner": [64, 64], "seconds": 1.0},
        "method": {"config": {"inner": "8:64,4"}, "seconds": 0.2, "mse": 0.1},
        "fixed": [{"n": 4, "inner": [4, 4], "seconds": 0.15, "mse": 0.1 * ratio}],
        "equal_time": 0,
        "fixed_slower": False,
        "ratio": ratio,
        "verdict": verdict,
        "file": "k.png",
    }


@pytest.mark.parametrize(
    "verdict,ratio,mark", [("win", 2.0, "T: win"), ("loss", 0.5, "T: **LOSS**")]
)
def test_the_sheets_say_the_verdict_and_the_numbers(verdict, ratio, mark):
    md = "\n".join(et.sheet_md([entry(verdict, ratio)]))
    assert f"### {mark}" in md and "| reference | 64,64 | 1.0 |  |" in md
    assert (
        "| fixed n=4 (equal time) | 4,4 | 0.150 |" in md
        and "| method | inner=8:64,4 | 0.200 | 1.000e-01 |" in md
    )
    assert (
        "2.00x lower MSE than fixed n=4"
        if verdict == "win"
        else "the method's MSE is 2.00x that of"
    ) in md
    h = "\n".join(et.sheet_html([entry(verdict, ratio)]))
    assert ("LOSS</strong>" in h) == (verdict == "loss") and "<img src='k.png'" in h
    assert et.sheet_md([]) == [] and et.sheet_html([]) == []
