"""`styletrace render --denoise expectation|image` on the command line: the pass split, and a stop
that keeps the work.

- `--pass-spp` splits the recorded passes as it does a plain render (it was ignored: one pass of all
  samples).
- Ctrl-C (SIGINT) after some passes ends the render after the pass under way; the finished passes
  are denoised and written, with the buffer, and the exit status is 130. With `expectation` the
  written image is the buffer's restyle; with `image` it is the denoised render of exactly that many
  passes.
"""
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
from conftest import child_env  # noqa: F401  (tests/conftest.py: the source tree first on PYTHONPATH)
from helpers.filtered_scene import GAUSSIAN_SCENE

import styletrace
from styletrace.lookdev.buffer import load_buffer

ENV = child_env()


def _exr(path):
    import mitsuba as mi
    return np.asarray(mi.Bitmap(str(path)), dtype=np.float32)[..., :3]


def test_pass_spp_splits_the_recorded_passes(tmp_path):
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            "--denoise",
            "expectation",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "4",
            "--inner",
            "2",
            "--pass-spp",
            "2",
            "--coverage",
            "4",
            "-q",
            "-o",
            str(tmp_path / "o.exr"),
            "--buffer",
            str(tmp_path / "b.npz"),
        ],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    source = load_buffer(str(tmp_path / "b.npz"))
    assert source.header["denoise"]["coverage"] == 4
    # the points' buffer is one pass of 4 points; the camera samples' passes are those of the render
    py = styletrace.render(
        "cornell-box",
        style="cel",
        spp=4,
        inner=2,
        width=16,
        height=16,
        pass_spp=2,
        denoise="expectation",
        coverage=4,
    )
    np.testing.assert_allclose(_exr(tmp_path / "o.exr"), py, atol=1e-5)
    whole = styletrace.render(
        "cornell-box",
        style="cel",
        spp=4,
        inner=2,
        width=16,
        height=16,
        pass_spp=4,
        denoise="expectation",
        coverage=4,
    )
    # with the built-in scenes' sampler (`owen_sobol`) passes continue one sequence: another
    # split draws the same samples (with independent samples it would draw others)
    np.testing.assert_allclose(whole, py, atol=1e-5)


def interrupted(method, out, *extra):
    """`render --denoise METHOD` of 4000 passes, Ctrl-C once 3 are done: (exit status, stderr
    after the signal, the spp the render says it wrote)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            "--denoise",
            method,
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "4000",
            "--inner",
            "4",
            "--pass-spp",
            "1",
            "-o",
            str(out),
            *extra,
        ],
        stderr=subprocess.PIPE,
        env=ENV,
    )
    seen, deadline = b"", time.time() + 120
    while b"3/4000" not in seen and time.time() < deadline:
        chunk = os.read(proc.stderr.fileno(), 4096)
        assert chunk, seen.decode()
        seen += chunk
    proc.send_signal(signal.SIGINT)
    rest = proc.communicate(timeout=120)[1]
    assert b"wrote the finished passes, denoised" in rest, (seen + rest).decode()
    return proc.returncode, rest, int(re.search(rb"after (\d+) of 4000 spp", rest).group(1))


def test_ctrl_c_denoises_and_writes_the_finished_passes(tmp_path):
    out, bufp = tmp_path / "partial.exr", tmp_path / "partial.npz"
    code, rest, done = interrupted("expectation", out, "--buffer", str(bufp))
    assert code == 130, rest.decode()
    image = _exr(out)
    assert image.shape == (32, 32, 3) and np.isfinite(image).all() and image.mean() > 0
    assert 3 <= done < 4000
    buf = load_buffer(str(bufp))
    np.testing.assert_allclose(styletrace.restyle(buf), image, atol=1e-4)


def test_ctrl_c_with_image_denoising_denoises_the_finished_passes(tmp_path):
    """The image written is OIDN's output on the finished passes: the same as denoising a render
    of that many passes with the same seed and split."""
    out = tmp_path / "partial.exr"
    code, rest, done = interrupted("image", out)
    assert code == 130 and 3 <= done < 4000, rest.decode()
    again = styletrace.render(
        "cornell-box",
        style="cel",
        spp=done,
        inner=4,
        width=32,
        height=32,
        pass_spp=1,
        denoise="image",
    )
    np.testing.assert_allclose(_exr(out), again, rtol=1e-4, atol=1e-5)


def test_a_gaussian_film_denoises_with_both_methods(tmp_path):
    """Both methods run on a film with Mitsuba's default filter (gaussian), and the denoised image
    is nearer to a 1024-spp render of the same film than the noisy render of the same spp is (the
    yardstick: the noise that denoising is there to remove; measured 2.1e-4 and 2.3e-4 against
    3.5e-4, as with a box filter 2.8e-4 and 3.7e-4 against 11e-4). With `expectation` the written
    image is the saved buffer's restyle."""
    scene = tmp_path / "g.xml"
    scene.write_text(GAUSSIAN_SCENE)
    import mitsuba as mi
    styletrace.init()
    assert mi.load_file(str(scene)).sensors()[0].film().rfilter().class_name() == "GaussianFilter"
    size = dict(width=48, height=48)
    ref = styletrace.render(str(scene), style="identity", spp=1024, inner=1, seed=5, **size)
    noisy = styletrace.render(str(scene), style="identity", spp=4, inner=4, seed=0, **size)
    err_noisy = float(np.mean((noisy - ref) ** 2))
    for method in ("expectation", "image"):
        out = tmp_path / f"{method}.exr"
        extra = ["--buffer", str(tmp_path / "b.npz")] if method == "expectation" else []
        res = subprocess.run([sys.executable, "-m", "styletrace", "render", str(scene),
                              "--denoise", method, "--style", "identity", "--spp", "4", "--inner",
                              "4", "--width", "48", "--height", "48", "-q", "-o", str(out), *extra],
                             capture_output=True, text=True, env=ENV, timeout=300)
        assert res.returncode == 0, res.stderr
        image = _exr(out)
        assert image.shape == ref.shape and np.isfinite(image).all()
        err = float(np.mean((image - ref) ** 2))
        assert err < err_noisy, (method, err, err_noisy)
    buf = load_buffer(str(tmp_path / "b.npz"))
    assert buf.header["filter"] == {"type": "gaussian", "stddev": 0.5}
    written = _exr(tmp_path / "expectation.exr")
    np.testing.assert_allclose(styletrace.restyle(buf), written, atol=1e-5)
