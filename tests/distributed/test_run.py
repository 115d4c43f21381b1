"""Passes as Ray tasks on a real local cluster: the merged image equals the single-process one,
bit for bit."""
import os
import signal

import numpy as np

import styletrace
from styletrace.frontends import api
from styletrace.pipeline.passes import PassSplit
from styletrace.pipeline.ray_plan import Plan
from styletrace.pipeline.ray_run import Render, job_for

STYLE = {"style": "cel", "inner": 2, "max_depth": 3}


def local(scene, width, height, spp, seed, pass_spp, style=STYLE, sampler=None):
    sc = api.load_scene(scene, width, height, sampler=sampler)
    integ = api.make_integrator(**style)
    image = None
    for prog in api.passes(sc, integ, spp, seed, pass_spp=pass_spp):
        image = prog.image
    return image


def test_cluster_render_is_bit_identical_to_the_local_one(ray_cluster):
    ref = local("cornell-box", 40, 24, 8, 7, 2)
    got = styletrace.render(
        "cornell-box", spp=8, seed=7, width=40, height=24, pass_spp=2, cluster=ray_cluster, **STYLE
    )
    assert got.dtype == np.float32 and got.shape == (24, 40, 3)
    assert np.array_equal(got, ref)
    # another seed draws other samples: the comparison can tell images apart
    assert not np.array_equal(local("cornell-box", 40, 24, 8, 8, 2), ref)


def test_a_builtin_scenes_sampler_travels_to_the_workers(ray_cluster):
    ref = local("cornell-box", 40, 24, 4, 7, 2, sampler="independent")
    got = styletrace.render("cornell-box", spp=4, seed=7, width=40, height=24, pass_spp=2,
                            cluster=ray_cluster, sampler="independent", **STYLE)
    assert np.array_equal(got, ref)
    assert not np.array_equal(local("cornell-box", 40, 24, 4, 7, 2), ref)


def test_tiled_image_on_the_cluster_equals_api_passes(ray_cluster):
    """1030 x 1024 pixels is two tiles of 1024 x 1024 (the second shifted inwards); two passes
    each."""
    w, h = 1030, 1024
    cheap = {"style": "identity", "inner": 1, "max_depth": 2}
    ref = local("cornell-box", w, h, 2, 3, 1, cheap)
    job = job_for("cornell-box", api.make_integrator(**cheap), w, h)
    run = Render(job, Plan(w, h, 2, 3, PassSplit(pass_spp=1)), ray_cluster)
    assert len(run.layout) == 2 and run.total_units == 4
    spp_seen = [p.spp_done for p in run]
    assert spp_seen[-1] == 2 and len(spp_seen) == 4
    assert np.array_equal(run.progress().image, ref)


def test_a_killed_worker_is_retried_and_the_image_is_unchanged(ray_cluster):
    """SIGKILL the worker that delivered the first unit while it renders its next one: Ray runs
    that unit again (max_retries) and the merged image equals the undisturbed render."""
    w, h, spp = 96, 96, 12
    ref = local("cornell-box", w, h, spp, 11, 1)
    job = job_for("cornell-box", api.make_integrator(**STYLE), w, h)
    run = Render(job, Plan(w, h, spp, 11, PassSplit(pass_spp=1)), ray_cluster)
    killed = []

    def kill_first(pid):
        if not killed:
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    run.on_result = kill_first
    for _ in run:
        pass
    assert killed and run.progress().spp_done == spp
    assert np.array_equal(run.progress().image, ref)


def test_a_ray_render_is_denoised_by_its_driver_as_here(ray_cluster):
    """The driver of a Ray render has the merged image of the passes, the same as a render here
    (bit for bit: the test above), and denoises it with the image denoiser as a render here does:
    the same image, to OIDN's float rounding from one call to the next. Auto picks that denoiser
    on Ray (the expectation denoiser needs every camera sample in one process)."""
    args = dict(style="identity", spp=8, seed=7, width=40, height=24, pass_spp=2)
    here = styletrace.render("cornell-box", denoise="image", **args)
    there = styletrace.render("cornell-box", denoise="image", cluster=ray_cluster, **args)
    np.testing.assert_allclose(there, here, rtol=1e-5, atol=1e-6)
    noisy = styletrace.render("cornell-box", denoise="off", cluster=ray_cluster, **args)
    assert not np.allclose(there, noisy, rtol=1e-3, atol=1e-3)  # it was denoised
    auto = styletrace.render("cornell-box", denoise="auto", cluster=ray_cluster, **args)
    np.testing.assert_allclose(auto, here, rtol=1e-5, atol=1e-6)
