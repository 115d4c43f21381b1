"""`styletrace gallery --quick`: every setup renders, references and the contact sheet are
written; the equal-time section's numbers agree with renders redone here and its verdicts follow
its ratios."""
import json
import os
import re

import numpy as np
import pytest

from styletrace.frontends import gallery
from styletrace.frontends.cli import main
from styletrace.frontends.equal_time import Comparison


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """One quick gallery for the tests of this module: its folder and gallery.json."""
    out = tmp_path_factory.mktemp("quick") / "g"
    assert main(["gallery", "--quick", "-o", str(out)]) == 0
    return out, json.loads((out / "gallery.json").read_text())


def test_quick_gallery(quick):
    out, res = quick
    assert [e["key"] for e in res["setups"]] == [s.key for s in gallery.SETUPS]
    for e in res["setups"]:
        for r in e["renders"]:
            assert (out / r["file"]).stat().st_size > 0
    for name in ("index.html", "index.md", "mse.png"):
        assert (out / name).stat().st_size > 0
    html = (out / "index.html").read_text()
    assert all(f"src='{r['file']}'" in html for e in res["setups"] for r in e["renders"])
    with_ref = [e for e in res["setups"] if "reference" in e]
    assert {e["key"] for e in with_ref} == {"color_map", "cel"}
    for e in with_ref:
        mse = [r["mse"] for r in e["renders"]]
        # direct application: both the bias and the variance of g(<I>_n) shrink with n; over
        # thousands of pixel channels the drop from n=1 to n=4 is far larger than the MSE's own
        # sampling error
        assert mse[-1] < mse[0], (e["key"], mse)
    # the equal-time section: one side-by-side PNG per comparison, shown on both sheets
    assert [e["key"] for e in res["equal_time"]] == [c.key for c in gallery.EQUAL_TIME]
    md = (out / "index.md").read_text()
    for e in res["equal_time"]:
        assert (out / e["file"]).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"src='{e['file']}'" in html and f"]({e['file']})" in md


def render_again(e, inner=None, config=None):
    """A render of an equal-time entry redone from the settings gallery.json records, by the
    public API."""
    import styletrace
    kw = {**e["integrator"], **e["params"], **(config if config is not None else {"inner": inner})}
    kw["inner"] = tuple(kw["inner"]) if isinstance(kw["inner"], list) else kw["inner"]
    return styletrace.render(
        e["scene"],
        style=e["style"],
        spp=e["spp"],
        seed=e["seed"],
        width=e["size"],
        height=e["size"],
        **kw,
    )


def test_equal_time_numbers_are_consistent(quick):
    """The JSON's MSEs are those numpy computes from the renders redone from its settings; the
    count at equal time is the largest rendered n not slower than the method (the smallest when
    all are slower), the fixed counts stop at the first one slower than the method, and the
    verdict follows the ratio."""
    _, res = quick
    for e in res["equal_time"]:
        ref = render_again(e, e["reference"]["inner"]).astype(np.float64)
        m, fixed, i = e["method"], e["fixed"], e["equal_time"]
        f = fixed[i]
        for img, recorded in ((render_again(e, config=m["config"]), m["mse"]),
                              (render_again(e, f["inner"]), f["mse"])):
            assert recorded == pytest.approx(
                np.mean((img.astype(np.float64) - ref) ** 2), rel=1e-12, abs=0
            )
        for r in (m, *fixed):
            assert r["seconds"] == np.median(r["times"]) and len(r["times"]) == e["repeats"]
        secs = [r["seconds"] for r in fixed]
        # only the last rendered count may be slower
        assert all(t <= m["seconds"] for t in secs[:-1])
        within = [j for j, t in enumerate(secs) if t <= m["seconds"]]
        assert i == (max(within) if within else 0), (e["key"], secs, m["seconds"])
        assert e["fixed_slower"] == (f["seconds"] > m["seconds"])
        assert e["ratio"] == f["mse"] / m["mse"]
        assert e["verdict"] == ("win" if e["ratio"] > 1 else "loss")


def test_a_method_worse_than_every_fixed_count_is_a_loss(tmp_path, monkeypatch):
    """A deliberately bad method: an adaptive count 4:4 (the image of n=4, plus the adaptive
    bookkeeping) against fixed counts from 8 up. Every fixed count averages more children than
    it, so whichever of them is at equal time has the lower error, and the section must call the
    method a LOSS: on its entry, in its picture's sheets. (Timing decides only which fixed count
    it meets, so the test asserts no speed.)"""
    bad = Comparison(
        "equal_time_bad",
        "Cel, an adaptive count that never adapts",
        "cel",
        method={"inner": "4:4"},
        reference=4096,
        counts=(8, 16, 32),
    )
    monkeypatch.setattr(gallery, "EQUAL_TIME", [bad])
    out = tmp_path / "g"
    assert main(["gallery", "--quick", "--only", "equal_time", "-o", str(out)]) == 0
    (e,) = json.loads((out / "gallery.json").read_text())["equal_time"]
    f = e["fixed"][e["equal_time"]]
    assert e["method"]["mse"] > f["mse"] and e["ratio"] < 1 and e["verdict"] == "loss", e
    assert (
        "### Cel, an adaptive count that never adapts: **LOSS**" in (out / "index.md").read_text()
    )
    assert ">LOSS</strong></h3>" in (out / "index.html").read_text()
    assert (out / e["file"]).stat().st_size > 0


def test_ctrl_c_in_a_comparison_keeps_the_finished_ones(tmp_path, monkeypatch):
    """The section saves gallery.json and the sheets after each comparison: Ctrl-C during the
    second loses nothing of the first."""
    from styletrace.frontends import equal_time

    first, second = (
        Comparison(
            f"equal_time_{k}", k, "color_map", method={"inner": 4}, reference=64, counts=(4,)
        )
        for k in ("first", "second")
    )
    monkeypatch.setattr(gallery, "EQUAL_TIME", [first, second])
    compare = equal_time.compare

    def interrupted(c, *args, **kw):
        if c.key == second.key:
            raise KeyboardInterrupt
        return compare(c, *args, **kw)
    monkeypatch.setattr(equal_time, "compare", interrupted)
    out = tmp_path / "g"
    assert main(["gallery", "--quick", "--only", "equal_time", "-o", str(out)]) == 130
    entries = json.loads((out / "gallery.json").read_text())["equal_time"]
    assert [e["key"] for e in entries] == [first.key] and (
        out / entries[0]["file"]
    ).stat().st_size > 0
    assert f"]({entries[0]['file']})" in (out / "index.md").read_text()


def test_refused_settings_in_the_table_stop_the_gallery_before_it_renders(
    tmp_path, monkeypatch, capsys
):
    """reuse_deep=world is refused at the first hit (it pools second-level vertices): the gallery
    says so in one line and renders nothing, not even the dragon setups that come before the
    section."""
    refused = Comparison("equal_time_refused", "refused", "cel", reference=64,
                         method={"inner": 4, "reuse": "pixels", "reuse_deep": "world"})
    monkeypatch.setattr(gallery, "EQUAL_TIME", [refused])
    out = tmp_path / "g"
    assert main(["gallery", "--quick", "--only", "gooch,equal_time", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("styletrace: error: ") and err.count("\n") == 1 and "reuse" in err, err
    assert list(out.iterdir()) == []


def test_only_and_skip_select_setups_and_the_equal_time_section():
    setups, comps = gallery.select_setups(["equal_time"])
    assert setups == [] and comps == gallery.EQUAL_TIME
    setups, comps = gallery.select_setups(None, ["equal_time"])
    assert setups == gallery.SETUPS and comps == []
    setups, comps = gallery.select_setups(["cel", gallery.EQUAL_TIME[0].key])
    assert [s.key for s in setups] == ["cel"] and comps == gallery.EQUAL_TIME[:1]
    setups, comps = gallery.select_setups(["equal_time", "cel"], [gallery.EQUAL_TIME[0].key, "cel"])
    assert setups == [] and comps == gallery.EQUAL_TIME[1:]
    with pytest.raises(
        ValueError, match="unknown gallery setup.s. nope: available are .*equal_time"
    ):
        gallery.select_setups(None, ["nope"])


def test_unknown_setup_is_one_line(tmp_path, capsys):
    assert main(["gallery", "--quick", "--only", "nope", "-o", str(tmp_path / "g")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("styletrace: error: unknown gallery setup(s) nope") and "\n" not in err
    assert (
        main(["gallery", "--quick", "--skip", "equal_time,nope2", "-o", str(tmp_path / "g")]) == 2
    )
    err = capsys.readouterr().err.strip()
    assert err.startswith("styletrace: error: unknown gallery setup(s) nope2") and "\n" not in err
    assert not (tmp_path / "g").exists()


def test_mse_of_non_finite_renders_is_honest_and_quiet():
    """A render with an inf pixel has an infinite MSE, and computing it sends no numpy warning to
    stderr."""
    import warnings

    import numpy as np

    from styletrace.frontends.gallery import mse
    img = np.zeros((2, 2, 3), np.float32)
    img[0, 0, 0] = np.inf
    ref = np.zeros((2, 2, 3), np.float64)
    ref[0, 0, 0] = np.inf
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isinf(mse(img, np.zeros_like(ref))) and np.isnan(mse(img, ref))
        assert mse(np.ones((2, 2, 3), np.float32), np.zeros_like(ref)) == 1.0


def test_the_guide_gives_the_time_of_the_committed_gallery_run():
    """docs/guide.md once gave two totals for one run (157 s and 525 s): the one it gives is the
    `seconds` of docs/gallery/gallery.json, which docs/gallery/index.md shows."""
    docs = os.path.join(os.path.dirname(__file__), "..", "..", "docs")
    with open(os.path.join(docs, "gallery", "gallery.json"), encoding="utf-8") as f:
        seconds = round(json.load(f)["seconds"])
    with open(os.path.join(docs, "guide.md"), encoding="utf-8") as f:
        guide = f.read()
    with open(os.path.join(docs, "gallery", "index.md"), encoding="utf-8") as f:
        assert f"total {seconds} s" in f.read()
    stated = {int(t) for t in
              re.findall(r"default gallery[^.]*?(?:took|takes about) (\d+) s", guide)}
    assert stated == {seconds}, stated
