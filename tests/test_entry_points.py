"""One scene, every entry point, one image (issue 19).

The scene: a `moment`-wrapped `path` with max_depth $depth (set to 3 through defines) and
hide_emitters, an area light and a constant sky (which hide_emitters hides from the camera),
rendered with cel at its `auto` thresholds. Every route builds the same `pipeline.Job`, so the
command line, `styletrace.render`, the Ray path, `render_buffer` and `mi.render` on the same file
written with a `stylized` integrator draw the same image to the bit for the same seed and pass
split. Where a route cannot be bit-identical the test says why and compares the image means within 4
standard errors, the SE from the per-pixel sample variance (the error AOV `variance` of the render:
each pixel's estimate's variance, (E[x^2] - mean^2) / (spp - 1)).
"""
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import child_env

import styletrace
from styletrace.gate import mi
from styletrace.pipeline.passes import pass_seed

styletrace.init()

SEED, SPP, INNER = 5, 4, 2
SCENE = """<scene version="3.0.0">
  <default name="depth" value="6"/>
  {integrator}
  <sensor type="perspective">
    <float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 1, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/>
      <rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
  </sensor>
  <shape type="sphere"><point name="center" x="-1.2" y="0" z="0"/><float name="radius" value="0.8"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="1.2" y="0" z="0"/><float name="radius" value="0.8"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.7"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="5"/><rotate x="1" angle="-90"/><translate \
y="-0.8"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="90"/><translate y="3"/></transform>
    <emitter type="area"><rgb name="radiance" value="6, 6, 6"/></emitter></shape>
  <emitter type="constant"><rgb name="radiance" value="0.3, 0.3, 0.35"/></emitter>
</scene>
"""
MOMENT = (
    '<integrator type="moment"><integrator type="path"><integer name="max_depth" value="$depth"/>'
    '<boolean name="hide_emitters" value="true"/></integrator></integrator>'
)
#: the same render written for Mitsuba alone: its `stylized` integrator with what the pipeline
#: carries over
STYLIZED = (
    '<integrator type="stylized"><string name="style" value="cel"/><integer name="inner_samples" '
    'value="2"/>'
    '<integer name="max_depth" value="$depth"/><boolean name="hide_emitters" '
    'value="true"/></integrator>'
)
ARGS = dict(style="cel", inner=INNER, spp=SPP, seed=SEED, defines={"depth": "3"})


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("entry")
    wrapped, own = folder / "moment.xml", folder / "stylized.xml"
    wrapped.write_text(SCENE.format(integrator=MOMENT))
    own.write_text(SCENE.format(integrator=STYLIZED))
    return str(wrapped), str(own)


@pytest.fixture(scope="module")
def reference(files):
    """`styletrace.render`'s image, and each pixel's estimate's variance from the same render
    with the error AOVs (a kernel with more outputs: its image may differ in the last bit, its
    statistics do not)."""
    image = styletrace.render(files[0], **ARGS)
    with_aovs, aovs = styletrace.render(files[0], aovs=True, **ARGS)
    within_4_se(with_aovs, image, aovs["variance"])
    return image, aovs["variance"]


def within_4_se(image, other, variance):
    """|mean(image) - mean(other)| < 4 SE per channel, both images of independent or equal
    estimates of the same expectation, each with per-pixel estimate variance `variance` (so the
    difference has twice it)."""
    n = variance.shape[0] * variance.shape[1]
    se = np.sqrt(2 * variance.reshape(-1, 3).sum(axis=0)) / n
    diff = np.abs(image.reshape(-1, 3).mean(axis=0) - other.reshape(-1, 3).mean(axis=0))
    assert np.all(se > 0), se
    assert np.all(diff < 4 * se), (diff, se)


def test_the_python_call_keeps_the_files_settings(files, reference):
    """The same call again is the same image; without the carried settings (the depth, the hidden
    sky) it is another, and api.render is the same function."""
    assert np.array_equal(styletrace.render(files[0], **ARGS), reference[0])
    from styletrace.frontends import api
    assert api.render is styletrace.render  # the one-line alias
    plain = styletrace.render(files[0], max_depth=6, hide_emitters=False, **ARGS)
    assert not np.array_equal(plain, reference[0])
    assert plain.reshape(-1, 3).mean() > reference[0].reshape(-1, 3).mean()  # the sky is seen again


def test_command_line(files, reference, tmp_path):
    out = tmp_path / "cli.exr"
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            files[0],
            "-D",
            "depth=3",
            "--style",
            "cel",
            "--inner",
            str(INNER),
            "--spp",
            str(SPP),
            "--seed",
            str(SEED),
            "-o",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    # resolved, not the 0.5 fallback
    assert re.search(r"auto values: cel thresholds=0\.\d+", r.stderr), r.stderr
    assert np.array_equal(np.array(mi.Bitmap(str(out)))[..., :3], reference[0])


def test_ray_on_a_local_cluster(files, reference):
    assert np.array_equal(styletrace.render(files[0], cluster="local", **ARGS), reference[0])


def test_render_buffer_then_restyle_to_the_same_style(files, reference):
    """The buffer's image is the render's bit for bit. The restyle applies g again, in numpy, to
    the stored float32 children's means (not in the kernel's order of operations): last-bit
    differences, so it is held to 4 SE of the mean and to float32 rounding per pixel."""
    buf = styletrace.render_buffer(files[0], **ARGS)
    assert np.array_equal(buf.image, reference[0])
    again = styletrace.restyle(buf, style="cel")
    within_4_se(again, reference[0], reference[1])
    np.testing.assert_allclose(again, reference[0], rtol=1e-5, atol=1e-6)


def test_mi_render_on_the_file_resolves_the_auto_thresholds(files, reference):
    """Mitsuba's own render of the file written with `stylized`: one pass of SPP samples with
    seed s is the pipeline's first (and here only) pass, whose seed is pass_seed(s, 0), so the
    image is the same to the bit."""
    scene = mi.load_file(files[1], depth="3")
    image = np.array(mi.render(scene, spp=SPP, seed=pass_seed(SEED, 0)))[..., :3]
    assert np.array_equal(image, reference[0])
    fallback = mi.load_dict(
        {
            "type": "stylized",
            "style": "cel",
            "inner_samples": INNER,
            "max_depth": 3,
            "hide_emitters": True,
            "thresholds": "0.5",
        }
    )
    assert not np.array_equal(
        np.array(mi.render(scene, integrator=fallback, spp=SPP, seed=pass_seed(SEED, 0))), image
    )  # the unresolved fallback is another image: the thresholds were resolved


def test_mi_render_against_another_pass_split(files, reference):
    """Two passes of 2 spp (pipeline) against Mitsuba's one pass of 4: other seeds, other
    samples, so only the expectation agrees: the image means within 4 SE."""
    split = styletrace.render(files[0], pass_spp=2, **ARGS)
    assert not np.array_equal(split, reference[0])
    scene = mi.load_file(files[1], depth="3")
    whole = np.array(mi.render(scene, spp=SPP, seed=SEED))[..., :3]
    within_4_se(split, whole, reference[1])


def test_every_front_end_denoises_by_default(files, tmp_path, monkeypatch):
    """The default of `denoise` is one (`pipeline.denoising.default_method`: auto, unless
    $STYLETRACE_DENOISE, which the suite sets to off and this test clears): `styletrace.render`,
    the command line, the preview and Blender's Denoise property (tests/blender/test_denoise.py)
    all take it, and the Python call and the command line draw the same denoised image."""
    monkeypatch.delenv("STYLETRACE_DENOISE", raising=False)
    from styletrace.pipeline.denoising import default_method
    assert default_method() == "auto"
    args = dict(style="cel", inner=INNER, seed=SEED, defines={"depth": "3"})
    image = styletrace.render(files[0], **args)
    assert np.array_equal(image, styletrace.render(files[0], denoise="auto", **args))
    assert not np.array_equal(image, styletrace.render(files[0], denoise="off", **args))
    env = {k: v for k, v in child_env().items() if k != "STYLETRACE_DENOISE"}
    out = tmp_path / "default.exr"
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            files[0],
            "-D",
            "depth=3",
            "--style",
            "cel",
            "--inner",
            str(INNER),
            "--seed",
            str(SEED),
            "-o",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "denoised: expectation" in r.stderr, r.stderr
    assert np.array_equal(np.array(mi.Bitmap(str(out)))[..., :3], image)
    from styletrace.preview.jobs import page_job, prepare
    assert prepare(page_job(files[0], inner=INNER, spp=2)).page.method == "expectation"


@pytest.fixture
def splits(monkeypatch):
    """Every answer of the one split (`pipeline.budget.split`, called by `pipeline.resolve`)."""
    from styletrace.pipeline import resolve as module
    answers, split = [], module.split
    monkeypatch.setattr(module, "split", lambda *a, **k: answers.append(split(*a, **k))
                        or answers[-1])
    return answers


def test_every_front_end_takes_the_one_splits_answer(files, tmp_path, splits):
    """`samples` (paths per pixel; default the scene's sample count, 4 in this file) is split once
    per render, by `pipeline.budget.split` in `pipeline.resolve.resolve`, after the denoising
    method is chosen; every front end renders that answer: the command line (its auto line and its
    buffer), `styletrace.render` (its passes), `render_buffer` and the preview's session. Denoise
    off: at 32 samples cel's camera samples take its own 16 children, 2 of them; the file's 4 one
    camera sample of 4 children. With the expectation denoised a camera sample takes at most 4
    children (`budget.CHILDREN`): 8 x 4. Ray takes the same answer, undenoised; a draft is the same
    function asked one camera sample of the render's children. Blender's F12 and viewport:
    tests/blender/test_samples.py."""
    from styletrace.frontends import cli
    from styletrace.preview.jobs import page_job, prepare

    def one(count=1):
        """The answer of the render just made (one split; a draft's two: the render's, then its
        own request's), emptied."""
        got = list(splits)
        splits.clear()
        assert len(got) == count, got
        return got[-1] if count == 1 else got

    words = [files[0], "-D", "depth=3", "--style", "cel", "--seed", str(SEED), "-q"]
    assert cli.main(["render", *words, "--denoise", "expectation", "--samples", "32", "-o",
                     str(tmp_path / "d.exr")]) == 0
    answer = one()
    assert (answer.camera_samples, answer.children) == (8, (4,))
    assert answer.note == "samples=32: spp=8 x 4 children"
    for samples, (spp, n) in ((32, (2, 16)), (None, (1, 4))):
        flag = [] if samples is None else ["--samples", str(samples)]
        npz = tmp_path / f"{samples}.npz"
        assert cli.main(["render", *words, "--denoise", "off", *flag, "--buffer", str(npz),
                         "-o", str(tmp_path / "o.exr")]) == 0
        answer = one()
        assert (answer.camera_samples, answer.children) == (spp, (n,))
        assert f"samples={samples or 4}: spp={spp} x {n} children" == answer.note
        recorded = styletrace.load_buffer(str(npz))
        assert (recorded.spp, recorded.header["slots"][0]["inner"]) == (spp, n)
        given = {} if samples is None else {"samples": samples}
        totals = []
        styletrace.render(files[0], style="cel", seed=SEED, defines={"depth": "3"},
                          denoise="off", callback=lambda p: totals.append(p.spp_total), **given)
        assert one().camera_samples == spp and set(totals) == {spp}
        buf = styletrace.render_buffer(files[0], style="cel", seed=SEED, defines={"depth": "3"},
                                       **given)
        answer = one()
        assert (buf.spp, buf.header["slots"][0]["inner"]) == (answer.camera_samples,
                                                               answer.children[0]) == (spp, n)
        page = prepare(page_job(files[0], denoise="off", **given)).page  # the page starts with cel
        assert (page.spp, page.budget.children) == (spp, (n,)) and one().children == (n,)
        # on Ray (nothing runs until its passes are asked for): the same answer, not denoised
        from styletrace.denoise.finishers import plan
        from styletrace.pipeline.execute import OnRay
        from styletrace.pipeline.job import python_job
        job = python_job(files[0], style="cel", seed=SEED, defines={"depth": "3"}, **given)
        ray = plan(job, executor=OnRay("local")).resolved
        assert ray.method == "off" and (ray.spp, ray.budget.children) == (spp, (n,))
        assert one().camera_samples == spp
    # a draft asks the same function for its own request: one camera sample of those children
    from styletrace.pipeline.denoising import Denoising
    job = python_job(files[0], style="cel", seed=SEED, defines={"depth": "3"},
                     denoising=Denoising("expectation"))
    draft = plan(job.with_(draft=True)).resolved
    whole, mine = one(count=2)  # the render's split, then the draft's request's
    assert (draft.spp, draft.budget.children) == (1, whole.children) == (1, mine.children)


