"""The sample budget (`pipeline.budget`, issues 36 and 44): `samples`, paths per pixel, split once
by `pipeline.resolve` into camera samples x children for every style, after the denoising method is
chosen (the expectation denoiser, every front end's default, takes at most CHILDREN children):
explicit counts win exactly, three that disagree are refused in one line in the caller's terms, and
the expectation buffer's cap lowers an auto spp. The observable is the resolved job (its spp, its
integrator's `slot.n`), not a render."""
import pytest

from styletrace.config.settings import AdaptiveCount
from styletrace.errors import UsageError
from styletrace.frontends import api
from styletrace.pipeline import terms
from styletrace.pipeline.budget import CHILDREN, Request, averages_children, draft_request, split
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.job import Job, python_job
from styletrace.pipeline.resolve import resolve
from styletrace.styles import registry

W = H = 8
#: the split of the built-in scene's samples by the style's default n: {n: {samples: (spp, n)}}
EXPECTED = {
    16: {16: (4, 4), 64: (16, 4)},    # cel, color_map, gamma, hatching, ...: n = CHILDREN
    8: {16: (4, 4), 64: (16, 4)},     # saturation
    1: {16: (16, 1), 64: (64, 1)},    # identity, contrast, sepia
    0: {16: (16, 1), 64: (64, 1)},    # closed form (gooch, xtoon, coordinate): no children
}


@pytest.fixture(scope="module")
def box():
    """The built-in Cornell box at 8 x 8 (its sampler's sample_count is 16)."""
    return api.load_scene("cornell-box", W, H)


def resolved(scene, denoise="expectation", **kw):
    """The job a render of `denoise` runs (the expectation: every front end's default for a style
    of several children)."""
    return resolve(python_job("cornell-box", width=W, height=H, denoising=Denoising(denoise), **kw),
                   scene=scene)


def planned(job, denoise="expectation"):
    """`job` resolved with `denoise`."""
    return resolve(job.with_(denoising=Denoising(denoise)))


def counts(r):
    """(spp, n at the first stylized level) of a resolved job."""
    return r.spp, int(r.integrator.settings.slot.n(0))


@pytest.mark.parametrize("samples", [16, 64])
@pytest.mark.parametrize("style", registry.style_names())
def test_every_style_spends_the_samples_as_paths_per_pixel(box, style, samples):
    default = registry.style_class(style).default_inner
    assert default in EXPECTED, f"{style}: add the split of a default n of {default}"
    r = resolved(box, style=style, samples=samples)
    assert counts(r) == EXPECTED[default][samples]
    assert r.budget.paths == samples
    assert r.auto.startswith(f"samples={samples}: spp={r.spp}")


def test_the_scenes_sample_count_is_the_default_budget(box):
    r = resolved(box, style="cel")
    assert counts(r) == (4, CHILDREN) and r.budget.request.budget == 16
    assert r.auto.startswith("samples=16: spp=4 x 4 children; ")
    # fewer samples than CHILDREN: n shrinks to the samples, one camera sample
    assert counts(resolved(box, style="cel", samples=2)) == (1, 2)
    assert counts(resolved(box, style="cel", samples=24)) == (6, 4)  # round(24 / 4) = 6
    # a style of fewer children than CHILDREN keeps its own n
    assert counts(resolved(box, style="identity", samples=24)) == (24, 1)


def test_without_the_expectation_denoised_an_auto_n_is_the_styles():
    """g applied to each camera sample's mean of n children is biased by O(1/n): where the
    expectation is not denoised (denoise off or image) the budget keeps the style's own n."""
    box = api.load_scene("cornell-box", W, H)
    for denoise in ("off", "image"):
        r = resolved(box, denoise, style="cel")
        assert counts(r) == (1, 16) and r.auto.startswith("samples=16: spp=1 x 16 children")
        assert counts(resolved(box, denoise, style="cel", samples=64)) == (4, 16)
        assert counts(resolved(box, denoise, style="saturation")) == (2, 8)
        assert counts(resolved(box, denoise, style="identity")) == (16, 1)
        assert counts(resolved(box, denoise, style="cel", inner=2)) == (8, 2)  # given: as given


def test_a_given_inner_count_wins_and_spp_follows(box):
    assert counts(resolved(box, style="cel", inner=8)) == (2, 8)
    assert counts(resolved(box, style="cel", inner=8, samples=64)) == (8, 8)
    assert counts(resolved(box, style="cel", inner=3, samples=16)) == (5, 3)  # round(16 / 3)
    # an adaptive count n0:n_max spends n0 per camera sample
    r = resolved(box, style="cel", inner="4:64", samples=64)
    assert r.spp == 16 and r.integrator.settings.slot.n(0) == AdaptiveCount(4, 64)


def test_a_given_spp_wins_and_keeps_the_styles_n_without_samples(box):
    """spp alone is every call before samples existed: the style's own n, no split named."""
    r = resolved(box, style="cel", spp=4)
    assert counts(r) == (4, 16) and "samples=" not in r.auto
    assert counts(resolved(box, style="cel", spp=4, samples=64)) == (4, 16)
    assert counts(resolved(box, style="cel", spp=4, samples=16)) == (4, 4)
    assert counts(resolved(box, style="cel", spp=3, samples=16)) == (3, 5)  # round(16 / 3)
    assert counts(resolved(box, style="cel", spp=32, samples=16)) == (32, 1)


def test_spp_and_inner_given_are_used_exactly_and_samples_must_agree(box):
    r = resolved(box, style="cel", spp=4, inner=8)
    assert counts(r) == (4, 8) and "samples=" not in r.auto
    assert counts(resolved(box, style="cel", spp=4, inner=8, samples=32)) == (4, 8)
    with pytest.raises(UsageError) as info:
        resolved(box, style="cel", spp=4, inner=8, samples=64)
    assert str(info.value) == ("samples=64 with spp=4 and inner=8 (32 paths per pixel): give at "
                               "most two of the three")


@pytest.mark.parametrize("caller, words", [
    (terms.PYTHON, "samples=64 with spp=4 and inner=8"),
    (terms.COMMAND_LINE, "--samples 64 with --spp 4 and --inner 8"),
    (terms.BLENDER, "'Samples' 64 with 'Camera samples' 4 and 'Inner samples' 8"),
])
def test_a_refusal_names_the_settings_in_the_callers_terms(box, caller, words):
    """The same three counts that disagree, asked by Python, the command line and Blender: each
    hears its own names (the keyword, the flag, the field's label)."""
    job = python_job("cornell-box", width=W, height=H, style="cel", spp=4, inner=8, samples=64)
    with pytest.raises(UsageError) as info:
        resolve(job.with_(terms=caller), scene=box)
    assert str(info.value) == f"{words} (32 paths per pixel): give at most two of the three"


def test_several_levels_keep_their_counts(box):
    two = dict(style="cel", stylize="first_n_hits", stylize_depth=2)
    r = resolved(box, samples=64, **two)
    assert counts(r) == (1, 16) and r.integrator.settings.slot.n(1) == 16  # 256 paths: spp >= 1
    assert "samples=64: spp=1 x 16,16 children (256 paths per pixel)" in r.auto
    r = resolved(box, samples=64, inner="4,2", **two)
    assert counts(r) == (8, 4) and r.budget.paths == 64
    assert counts(resolved(box, samples=64, spp=2, **two)) == (2, 16)  # n is not split over levels


def test_the_scene_files_own_inner_count_is_given(tmp_path):
    scene = tmp_path / "own.xml"
    scene.write_text(
        '<scene version="3.0.0"><integrator type="stylized"><string name="style" value="cel"/>'
        '<integer name="inner_samples" value="4"/></integrator>'
        '<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
        '<integer name="height" value="8"/></film><sampler type="independent">'
        '<integer name="sample_count" value="32"/></sampler></sensor>'
        '<shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/></emitter>'
        "</shape></scene>"
    )
    assert counts(planned(Job(scene=str(scene)))) == (8, 4)
    assert counts(planned(Job(scene=str(scene), samples=64))) == (16, 4)
    with pytest.raises(UsageError, match=r"inner=4 \(16 paths per pixel\)"):
        resolve(Job(scene=str(scene), samples=64, spp=4))


def test_a_prebuilt_integrator_is_split_unless_it_names_its_count(box):
    cel = api.make_integrator(style="cel")
    assert counts(planned(Job(scene=box, integrator=cel, samples=64))) == (16, 4)
    assert counts(planned(Job(scene=box, integrator=cel, samples=8))) == (2, 4)
    assert counts(resolve(Job(scene=box, integrator=cel, samples=8))) == (1, 8)  # not denoised
    given = api.make_integrator(style="cel", inner=2)
    r = planned(Job(scene=box, integrator=given, samples=8))
    assert counts(r) == (4, 2) and r.integrator.values["inner_samples"] == 2
    from styletrace.gate import mi
    path = mi.load_dict({"type": "path"})  # no children: a camera sample is one path
    assert resolve(Job(scene=box, integrator=path, samples=64)).spp == 64


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "16"])
def test_bad_samples_are_refused_in_one_line(box, bad):
    with pytest.raises(UsageError) as info:
        resolved(box, style="cel", samples=bad)
    assert str(info.value).startswith(f"bad value {bad!r} for samples: expected an integer in [1, ")


def rq(samples, spp=None, inner=None, style_children=16, given=True, **kw):
    """A request: `samples` paths per pixel (named by the caller where `given`, else the scene's),
    `spp` camera samples and `inner` children given, a style of `style_children`."""
    return Request(scene_samples=samples, samples=samples if given else None, camera_samples=spp,
                   children=inner, style_children=style_children, **kw)


def test_the_rule_itself():
    """`split` alone: the module doc's cases, without a scene."""
    s = split(rq(16, given=False, denoised=True))
    assert (s.camera_samples, s.children) == (4, (4,))
    assert s.note == "samples=16: spp=4 x 4 children"
    assert (s := split(rq(16, given=False))).camera_samples == 1 and s.children == (16,)
    assert split(rq(64, style_children=8, given=False)).children == (8,)
    assert split(rq(16, style_children=0, given=False)).note == "samples=16: spp=16 (no children)"
    assert split(rq(16, style_children=1, given=False)).note == "samples=16: spp=16 x 1 child"
    assert split(rq(64, 4)).children == (16,)
    assert split(rq(64, 4, given=False)).children == (16,)
    assert split(rq(16, 4)).children == (4,)
    assert split(rq(16, 4, given=False)).children == (16,)
    assert split(rq(16, 4, given=False)).note == ""  # spp alone: nothing chosen
    # a closed-form style draws no children: spp alone sets its cost, nothing to refuse
    assert split(rq(64, 4, style_children=0)).paths == 4
    with pytest.raises(UsageError, match=r"inner=4:64 \(16 paths"):
        split(rq(64, 4, (AdaptiveCount(4, 64),)))


def test_the_method_is_chosen_from_the_request_before_the_split():
    """Whether a camera sample averages children, which decides auto's method, reads the request:
    it is so in the split the method then makes, denoised or not."""
    for request in (rq(16), rq(2), rq(1), rq(16, style_children=1), rq(16, style_children=0),
                    rq(16, 16), rq(16, 4), rq(3, least_camera_samples=2),
                    rq(2, least_camera_samples=2), rq(16, inner=(1,)), rq(16, inner=(3,))):
        for denoised in (False, True):
            s = split(Request(**{**request.__dict__, "denoised": denoised}))
            many = not request.closed and int(s.children[0]) > 1
            assert averages_children(request) == many, (request, denoised)


def test_a_draft_is_one_camera_sample_of_the_renders_children():
    for whole in (split(rq(16, denoised=True)), split(rq(64, inner=(8,))),
                  split(rq(16, style_children=0)), split(rq(64, levels=2, inner=(4, 2)))):
        d = split(draft_request(whole))
        assert d.camera_samples == 1 and d.children == whole.children
        assert d.per_camera_sample == whole.per_camera_sample


def test_the_expectation_buffers_cap_lowers_an_auto_spp_and_raises_an_auto_n():
    assert split(rq(64, given=False), cap=16) == split(rq(64, given=False))
    # 64 x 16 would be 64 camera samples
    capped = split(rq(1024, given=False, denoised=True), cap=16)
    assert (capped.camera_samples, capped.children) == (16, (64,))
    assert capped.note == "samples=1024: spp=16 x 64 children"
    assert split(rq(1000, given=False, denoised=True), cap=16).children == (63,)  # ceil
    # a given n stays; the spp is held to the cap
    s = split(rq(1024, inner=(8,), given=False), cap=16)
    assert (s.camera_samples, s.children) == (16, (8,))
    # a given spp is the caller's (auto then takes the image denoiser: denoising.choose_method)
    assert split(rq(1024, 32, given=False), cap=16).camera_samples == 32
    # several levels keep their counts
    two = split(rq(4096, inner=(4, 2), given=False, levels=2), cap=16)
    assert (two.camera_samples, two.children) == (16, (4, 2))
    assert split(rq(64, given=False), cap=0).camera_samples == 1  # a film over the cap: one


def test_error_aovs_take_at_least_two_camera_samples(box):
    """Their variance needs two camera samples (`runner.Runner.check` refuses one): an auto spp
    is raised to 2 and an auto n lowered to round(samples / 2); a given spp is the caller's."""
    r = resolved(box, style="cel", aovs=True)
    assert counts(r) == (4, 4) and r.budget.paths == 16
    assert counts(resolved(box, style="cel", aovs=True, samples=4)) == (2, 2)
    assert counts(resolved(box, style="cel", aovs=True, samples=64)) == (16, 4)
    assert counts(resolved(box, style="cel", aovs=True, inner=16)) == (2, 16)
    assert counts(resolved(box, style="cel", aovs=True, spp=1)) == (1, 16)
    assert split(rq(16, given=False, least_camera_samples=2), cap=1).camera_samples == 1
