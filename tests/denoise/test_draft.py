"""The preview's draft pass is denoised (the expectation, before the style): the state says so,
the command line it shows reproduces it, and its cel image is closer to a converged render than
the undenoised draft's."""
import numpy as np
from preview.conftest import wait_until

import styletrace
from styletrace.denoise import expectation as X
from styletrace.preview import session as module


def test_the_draft_is_denoised(monkeypatch):
    monkeypatch.setattr(module, "DRAFT_GRACE_S", 120.0)
    size = 64
    s = module.Session("cornell-box", inner=4, spp=2, width=size, height=size).start()
    try:
        wait_until(lambda: s.draft is not None, 300, "the draft")
        assert s.draft_denoised and X.DENOISED in s.draft.arrays
        img, spp, inner = s.restyle("cel", None, {})
        assert s.state()["draft_denoised"] or s.buffer is not None
        assert "--denoise expectation" in s.command("cel", None, {}, spp, inner)
    finally:
        s.stop()
    kw = dict(style="cel", spp=1, seed=0, width=size, height=size)
    ref = styletrace.render("cornell-box", inner=256, **kw)
    noisy = styletrace.render("cornell-box", inner=module.DRAFT_INNER, **kw)
    # the undenoised n = 1 draft flips bands everywhere; the denoised one must at least halve its
    # MSE
    assert np.mean((img - ref) ** 2) < 0.5 * np.mean((noisy - ref) ** 2)
