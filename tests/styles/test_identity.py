import numpy as np
import pytest

from styletrace.styles import StyleError, create

from .support import run


def test_returns_input():
    I = np.random.default_rng(0).uniform(-1, 5, size=(20, 3)).astype(np.float32)
    np.testing.assert_array_equal(run(create("identity"), I), I)


def test_has_no_parameters():
    with pytest.raises(StyleError, match="allowed are none"):
        create("identity", gamma=2)
    assert create("identity").describe() == "identity()"
