"""A denoised render's buffer keeps the denoised expectation: restyling it equals a fresh
denoised render of the new style with the same seed (and survives save/load). The denoised
expectation does not depend on the style (it is formed before g), and OIDN is deterministic on
the CPU for the same input, so the comparison is up to float rounding: 1e-5 absolute on values of
order 1 (float32 sums of a few samples)."""
import numpy as np
import pytest

import styletrace
from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.pipeline.passes import Shot

KW = dict(spp=2, inner=2, seed=11)


@pytest.fixture(scope="module")
def recorded():
    scene = api.load_scene("cornell-box", 32, 32)
    image, buf = X.render_denoised_expectation(
        Shot(scene, api.make_integrator(style="cel", inner=KW["inner"]), KW["spp"], KW["seed"])
    )
    return scene, image, buf


def test_restyle_equals_fresh_denoised_render(recorded, tmp_path):
    scene, image, buf = recorded
    assert np.abs(styletrace.restyle(buf) - image).max() <= 1e-5
    path = buf.save(str(tmp_path / "d.npz"))
    loaded = styletrace.load_buffer(path)
    for style, params in (
        ("hatching", {}),
        ("color_map", {"gradient": "heat"}),
        ("cel", {"levels": "0.2,0.8"}),
        ("cel", {"levels": "0.1,0.3,0.6,0.9"}),
    ):
        # firefly=0: the buffer above was recorded by the denoiser itself, without the default
        # firefly control
        fresh = styletrace.render(
            scene, style=style, denoise="expectation", firefly=0, **KW, **params
        )
        for b in (buf, loaded):
            assert np.abs(styletrace.restyle(b, style=style, **params) - fresh).max() <= 1e-5, style


def test_first_object_hit_restyles_to_its_render(tmp_path):
    """`mixed` (styled objects, surfaces without a style behind and around them): the points' light
    before their styled vertex is denoised per pixel (`expectation.denoise_before`), and the buffer
    restyles to the render, after save/load too."""
    scene = api.load_scene("mixed", 32, 32)
    integrator = api.make_integrator(style="identity", stylize="first_object_hit")
    image, buf = X.render_denoised_expectation(Shot(scene, integrator, 2, 5))
    loaded = styletrace.load_buffer(buf.save(str(tmp_path / "m.npz")))
    for b in (buf, loaded):
        assert np.abs(styletrace.restyle(b) - image).max() <= 1e-5


def test_denoising_changed_the_image(recorded):
    """The buffer's image is the noisy render; the denoised one differs (else nothing above was
    tested)."""
    _, image, buf = recorded
    assert np.abs(image - buf.image[..., :3]).mean() > 1e-3


def test_aovs_say_denoised(tmp_path):
    """With denoising on the AOVs name themselves noisy_* and carry what the denoiser changed; no
    channel is called `variance` (it would read as the error of the denoised pixel)."""
    import mitsuba as mi
    for method in ("expectation", "image"):
        img, aovs = styletrace.render(
            "cornell-box",
            style="cel",
            spp=2,
            inner=2,
            width=16,
            height=16,
            aovs=True,
            denoise=method,
        )
        assert "variance" not in aovs and "noisy_variance" in aovs
        assert np.allclose(aovs["denoise_change"], img - styletrace.render(
            "cornell-box", style="cel", spp=2, inner=2, width=16, height=16), atol=1e-5)
        out = tmp_path / f"{method}.exr"
        styletrace.frontends.api.write_image(img, str(out), "rgb", aovs)
        names = [
            mi.Bitmap(str(out)).struct_()[i].name
            for i in range(mi.Bitmap(str(out)).channel_count())
        ]
        assert (
            "noisy_variance.R" in names
            and "denoise_change.G" in names
            and "variance.R" not in names
        )


def test_command_line_buffer_restyles_denoised(tmp_path):
    """`render --denoise expectation --buffer` then `restyle` = `render --denoise expectation` of
    the new style."""
    import subprocess
    import sys

    import mitsuba as mi
    from conftest import child_env
    small = ["--width", "24", "--height", "24", "--spp", "2", "--inner", "2", "--seed", "4", "-q"]

    def cli(*args):
        res = subprocess.run(
            [sys.executable, "-m", "styletrace", *args],
            capture_output=True,
            text=True,
            env=child_env(),
            timeout=300,
        )
        assert res.returncode == 0, res.stderr

    cli(
        "render",
        "--style",
        "cel",
        "--denoise",
        "expectation",
        *small,
        "--buffer",
        str(tmp_path / "b.npz"),
        "-o",
        str(tmp_path / "cel.exr"),
    )
    cli("restyle", str(tmp_path / "b.npz"), "--style", "hatching", "-o", str(tmp_path / "re.exr"))
    cli(
        "render",
        "--style",
        "hatching",
        "--denoise",
        "expectation",
        *small,
        "-o",
        str(tmp_path / "fresh.exr"),
    )
    re, fresh = (np.array(mi.Bitmap(str(tmp_path / f))) for f in ("re.exr", "fresh.exr"))
    assert np.abs(re - fresh).max() <= 1e-5
