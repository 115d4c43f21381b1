"""Checkpoints and --resume: an interrupted render continues without redoing its finished passes."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import child_env

from styletrace.errors import UsageError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.pipeline.passes import PassSplit
from styletrace.pipeline.ray_checkpoint import Checkpoint, Checkpoints
from styletrace.pipeline.ray_plan import Plan
from styletrace.pipeline.ray_run import Render, job_for

STYLE = {"style": "cel", "inner": 2, "max_depth": 3}


def test_break_then_resume_renders_only_the_rest_and_equals_the_undisturbed_render(
    ray_cluster, tmp_path
):
    w, h, spp, seed = 48, 32, 8, 4
    job = job_for("cornell-box", api.make_integrator(**STYLE), w, h)
    out = str(tmp_path / "img.exr")
    plan = Plan(w, h, spp, seed, PassSplit(pass_spp=1))
    whole = Render(job, plan, ray_cluster)
    list(whole)
    # units may arrive out of order, and those after a gap are summed when it closes: if the first
    # unit comes last the whole render lands at once and there is nothing left to resume, so that
    # render is started again (a few tries: this only happens when the workers are very uneven)
    for _ in range(5):
        first = Render(job, plan, ray_cluster, Checkpoints(out, every=3600))
        if any(3 <= prog.spp_done < spp for prog in first):
            break
    first.save()  # as the command line does after Ctrl-C: the finished units go to the checkpoint
    saved = json.load(open(out + ".checkpoint.json"))
    done = sum(saved["rounds_done"])
    assert 3 <= done < spp
    again = Render(job, plan, ray_cluster, Checkpoints(out, resume=True))
    assert again.resumed_units == done
    steps = list(again)
    assert len(steps) == 1 + spp - done  # the checkpoint's progress, then one per remaining unit
    assert np.array_equal(again.progress().image, whole.progress().image)
    again.finish()
    assert not [f for f in os.listdir(tmp_path) if "checkpoint" in f]


def test_checkpoint_keeps_the_exact_float32_sum(tmp_path):
    total = (np.random.default_rng(1).random((5, 7, 3)) * 1e4).astype(np.float32)
    total[0, 0] = [1e-30, 3.4e38, 0.1]
    ck = Checkpoint(str(tmp_path / "a.png"), {"spp": 4})
    ck.save(total, [2])
    ck.save(total + np.float32(1), [3])  # a new generation replaces the old one
    assert sorted(os.listdir(tmp_path)) == ["a.png.checkpoint-2.exr", "a.png.checkpoint.json"]
    got, rounds = Checkpoint(str(tmp_path / "a.png"), {"spp": 4}).load()
    assert rounds == [3] and np.array_equal(got, total + np.float32(1))


def test_resume_with_other_settings_is_refused_in_one_line(tmp_path):
    Checkpoint(str(tmp_path / "a.png"), {"spp": 4, "seed": 0}).save(
        np.zeros((2, 2, 3), np.float32), [1]
    )
    with pytest.raises(UsageError, match=r"other settings \(seed 0, now 1\); drop --resume"):
        Checkpoint(str(tmp_path / "a.png"), {"spp": 4, "seed": 1}).load()
    with pytest.raises(UsageError, match="no checkpoint"):
        Checkpoint(str(tmp_path / "b.png"), {"spp": 4}).load()


def rounds_checkpointed(proc, manifest, at_least, timeout=240):
    """Poll the checkpoint manifest every 50 ms until it counts `at_least` finished rounds, the
    process ends or `timeout` seconds pass; the rounds counted last."""
    done, deadline = 0, time.monotonic() + timeout
    while done < at_least and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
        try:
            done = sum(json.load(open(manifest))["rounds_done"])
        except (OSError, ValueError):
            pass
    return done


def cli(*args, **kw):
    # passes long enough (~0.1 s of paths each) that the tests' 50 ms polls see the render midway:
    # with millisecond passes a loaded machine finished the render between two polls, and the kill
    # missed it
    return [
        sys.executable,
        "-m",
        "styletrace",
        "render",
        "cornell-box",
        "--width",
        "96",
        "--height",
        "64",
        "--spp",
        "10",
        "--pass-spp",
        "1",
        "--style",
        "cel",
        "--inner",
        "32",
        "-q",
        *args,
    ]


def read(path):
    return np.array(mi.Bitmap(path), dtype=np.float32)


def test_killed_driver_then_resume_equals_the_undisturbed_render(ray_cluster, tmp_path):
    """SIGKILL the command line (and its process group) once a few passes are checkpointed;
    `--resume` finishes the render, equal to the single-process one; other settings are refused
    in one line."""
    ref, out = str(tmp_path / "ref.exr"), str(tmp_path / "out.exr")
    r = subprocess.run(cli("-o", ref), env=child_env(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    args = cli("-o", out, "--checkpoint-every", "0", "--ray", ray_cluster)
    proc = subprocess.Popen(
        args,
        env=child_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    manifest = out + ".checkpoint.json"
    try:
        done = rounds_checkpointed(proc, manifest, 3)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert 3 <= done < 10 and not os.path.exists(out)
    bad = subprocess.run(
        args + ["--resume", "--seed", "1"],
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "other settings (seed 0, now 1)" in bad.stderr
    r = subprocess.run(
        args + ["--resume"], env=child_env(), capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    assert np.array_equal(read(out), read(ref))
    assert not os.path.exists(manifest)


def test_ctrl_c_keeps_the_finished_passes_in_the_image_and_the_checkpoint(ray_cluster, tmp_path):
    out = str(tmp_path / "out.exr")
    args = cli("-o", out, "--checkpoint-every", "0", "--ray", ray_cluster)
    proc = subprocess.Popen(
        args, env=child_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    manifest = out + ".checkpoint.json"
    rounds_checkpointed(proc, manifest, 2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted; wrote" in err and os.path.exists(out)
    kept = sum(json.load(open(manifest))["rounds_done"])
    assert 2 <= kept < 10 and np.isfinite(read(out)).all()
    again = subprocess.run(args, env=child_env(), capture_output=True, text=True, timeout=300)
    assert again.returncode == 2 and "add --resume to continue it" in again.stderr
    assert again.stderr.count("\n") == 1
