"""The firefly control of direct application (`estimators.affine.MeanOfN(cap=(k, floor))`): exact
values on fixed children, on numpy and on Dr.Jit, and the switch that turns it off."""
import numpy as np
import pytest

from styletrace.estimators import Direct

from .estimator_stats import drjit_backend

#: per lane, the children in draw order (RGB); lane 0 holds a firefly, lane 1 none, lane 2 a firefly
#: in a shadow (the others are 0: the floor decides), lane 3 two equal bright children
CHILDREN = np.array([
    [(1.0, 1.0, 1.0), (1.2, 0.9, 0.9), (0.8, 1.0, 1.2), (90.0, 30.0, 60.0)],
    [(1.0, 1.0, 1.0), (2.0, 2.0, 2.0), (3.0, 3.0, 3.0), (2.5, 2.0, 1.5)],
    [(0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (6.0, 3.0, 3.0)],
    [(0.1, 0.1, 0.1), (5.0, 5.0, 5.0), (5.0, 5.0, 5.0), (0.1, 0.1, 0.1)],
])


def expected(children, k, floor):
    """The cap by hand: the brightest child scaled to k * max(mean brightness of the others,
    floor)."""
    out = []
    for lane in children:
        b = lane.mean(axis=1)
        top = int(np.argmax(b))  # the first of equal brightnesses, as the estimator keeps the first
        others = np.delete(lane, top, axis=0).mean(axis=1).mean()
        limit = k * max(others, floor)
        scale = min(1.0, limit / b[top]) if b[top] > 0 else 1.0
        kept = lane.copy()
        kept[top] *= scale
        out.append(kept.mean(axis=0))
    return np.array(out)


def run_numpy(est, children):
    lanes, n, _ = children.shape

    def draw(carry):
        (i,) = carry
        x = children[np.arange(lanes), np.minimum(i[:, 0], n - 1)]
        return x, (i + 1,)

    value, _ = est.run(
        draw,
        (np.zeros((lanes, 1), dtype=np.int64),),
        lambda c: (np.zeros((lanes, 1)), c),
        like=None,
    )
    return np.asarray(value)


@pytest.mark.parametrize("k,floor", [(4.0, 0.0), (4.0, 1.0), (2.0, 0.5)])
def test_the_brightest_child_is_capped_at_k_times_the_others(k, floor):
    got = run_numpy(Direct(lambda x: x, 4, cap=(k, floor)), CHILDREN)
    np.testing.assert_allclose(got, expected(CHILDREN, k, floor), rtol=1e-12)
    # lane 1 has no outlier at k = 4: untouched; lane 0's firefly is cut to k times the others' mean
    # brightness
    plain = CHILDREN.mean(axis=1)
    if k == 4.0:
        np.testing.assert_allclose(got[1], plain[1], rtol=1e-12)
    assert got[0].mean() < plain[0].mean() / 4


def test_off_is_the_plain_mean_and_the_shadow_keeps_its_child_below_the_floor():
    plain = run_numpy(Direct(lambda x: x, 4), CHILDREN)
    np.testing.assert_allclose(plain, CHILDREN.mean(axis=1), rtol=1e-12)
    # a lit child in a shadow (the others black) is kept up to k * floor: floor 1.5 keeps all of
    # brightness 4
    kept = run_numpy(Direct(lambda x: x, 4, cap=(4.0, 1.5)), CHILDREN)
    np.testing.assert_allclose(kept[2], CHILDREN[2].mean(axis=0), rtol=1e-12)


def test_a_lone_child_is_capped_at_the_cycles_clamp():
    one = CHILDREN[:, -1:, :]
    floor = 0.5
    got = run_numpy(Direct(lambda x: x, 1, cap=(4.0, floor)), one)
    limit = 10.0 / 0.18 * floor
    b = one[:, 0].mean(axis=1)
    np.testing.assert_allclose(got, one[:, 0] * np.minimum(1.0, limit / b)[:, None], rtol=1e-12)
    # with no floor a lone child has nothing to be compared with: no cap
    assert Direct(lambda x: x, 1, cap=(4.0, 0.0)).cap is None


def test_the_cap_on_drjit_matches_numpy():
    import drjit as dr
    mod = drjit_backend()
    lanes, n, _ = CHILDREN.shape
    flat = [
        mod.Array3f(
            *(
                mod.Float(np.ascontiguousarray(CHILDREN[:, j, c], dtype=np.float32))
                for c in range(3)
            )
        )
        for j in range(n)
    ]

    def draw(carry):
        (i,) = carry
        x = mod.Array3f(0.0)
        for j in range(n):
            x = dr.select(i == j, flat[j], x)
        return x, (i + 1,)

    est = Direct(lambda x: x, n, cap=(4.0, 0.25))
    value, _ = est.run(
        draw, (dr.zeros(mod.UInt32, lanes),), lambda c: (mod.Float(0.0), c), like=mod.Array3f
    )
    got = np.stack([np.asarray(value[c]) for c in range(3)], -1)
    np.testing.assert_allclose(got, expected(CHILDREN, 4.0, 0.25), rtol=1e-5)


def test_bad_caps_are_refused():
    with pytest.raises(ValueError):
        Direct(lambda x: x, 4, cap=(0.5, 0.0))
    with pytest.raises(ValueError):
        Direct(lambda x: x, 4, cap=(4.0, -1.0))
