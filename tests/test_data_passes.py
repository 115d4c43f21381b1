"""The data passes at the front ends: `--passes` into the EXR's channels, `passes=` in Python, a
turntable's frames with their motion; the image unchanged by asking for them; refusals."""
import numpy as np
import pytest

import styletrace
from styletrace.frontends import api
from styletrace.frontends.cli import main
from styletrace.frontends.ray_command import turntable_frames
from styletrace.gate import mi
from styletrace.images import DATA_CHANNELS
from styletrace.kernel.data_passes import (
    BACKGROUND_DEPTH,
    DATA_PASSES,
    Motion,
    render_data_passes,
)
from styletrace.pipeline.execute import OnRay
from styletrace.pipeline.job import Job
from styletrace.pipeline.orbit import turntable
from styletrace.pipeline.resolve import resolve
from styletrace.pipeline.runner import Runner

styletrace.init()
SMALL = ["--width", "16", "--height", "12", "--spp", "2", "--inner", "2", "-q"]
#: every data pass: the image must not change with any of them
ALL = ",".join(DATA_PASSES)


def channels(path):
    bmp = mi.Bitmap(str(path))
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    return dict(zip(names, np.moveaxis(np.array(bmp), -1, 0)))


@pytest.mark.parametrize("extra", [[], ["--aovs"], ["--denoise", "expectation"],
                                   ["--denoise", "image"], ["--buffer", "BUF"]],
                         ids=["plain", "aovs", "expectation", "image", "buffer"])
def test_the_exr_carries_the_passes_and_the_image_is_unchanged(tmp_path, extra):
    """Every finisher writes the passes (plain, with the error AOVs, denoised either way, with a
    recorded buffer), and the image's channels are those of the same render without them."""
    out, plain = tmp_path / "a.exr", tmp_path / "b.exr"
    runs = []
    for path, passes in ((out, ["--passes", ALL]), (plain, [])):
        args = [str(tmp_path / f"{path.stem}.npz") if a == "BUF" else a for a in extra]
        runs.append(main(["render", "cornell-box", *SMALL, *args, *passes, "-o", str(path)]))
    assert runs == [0, 0]
    ch, before = channels(out), channels(plain)
    names = {c for _, cs in DATA_CHANNELS for c in cs}
    assert set(ch) == set(before) | names
    for name in before:  # bit for bit: the passes trace rays of their own
        assert np.array_equal(ch[name], before[name]), name
    depth = ch["Depth.Z"]
    # the camera (mi.cornell_box's) sits 2.9 in front of the box's opening, 4.9 of its back wall;
    # the film is wider than the box: its first samples there meet nothing
    seen = depth < BACKGROUND_DEPTH
    assert 0.5 < seen.mean() < 1 and (depth[~seen] == BACKGROUND_DEPTH).all()
    assert 2.89 < depth[seen].min() and depth[seen].max() < 4.91
    normal = np.stack([ch[f"Normal.{c}"] for c in "XYZ"], -1)
    norms = np.linalg.norm(normal, axis=-1)
    # unit inside a wall; shorter where a pixel's samples meet two walls or nothing
    assert (norms <= 1 + 1e-5).all() and np.mean(np.abs(norms[seen] - 1) < 1e-5) > 0.6
    assert all(np.abs(ch[f"Vector.{c}"]).max() == 0 for c in "XYZW")  # a still


@pytest.mark.parametrize(
    "extra,why",
    [
        (["--passes", "depth", "-o", "x.png"], "--passes writes its channels into an .exr"),
        (["--passes", "depth,zdepth", "-o", "x.exr"], "bad value 'zdepth' for --passes"),
        (["--passes", "mist", "--mist", "5,0,linear", "-o", "x.exr"],
         "bad value '5,0,linear' for --mist"),
    ],
)
def test_refusals_are_one_line(tmp_path, capsys, extra, why):
    args = ["render", "cornell-box", "--width", "8", "--height", "8", *extra]
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and why in err, err
    assert not list(tmp_path.iterdir())


def test_frames_refuse_a_png_before_any_frame(tmp_path, capsys):
    out = tmp_path / "spin.png"
    args = ["render", "cornell-box", "--width", "8", "--height", "8", "--frames", "2",
            "--passes", "vector", "-q", "-o", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert "--passes writes its channels into an .exr" in err and err.count("\n") == 0
    assert not list(tmp_path.iterdir())


def test_python_returns_the_passes_beside_the_image_and_the_aovs():
    kwargs = dict(style="cel", spp=2, inner=2, width=12, height=8, seed=4)
    alone = styletrace.render("cornell-box", **kwargs)
    image, extra = styletrace.render("cornell-box", passes=["vector", "depth"], **kwargs)
    assert np.array_equal(image, alone)
    assert set(extra) == {"depth", "vector"}
    assert extra["depth"].shape == (8, 12) and extra["vector"].shape == (8, 12, 4)
    image, extra = styletrace.render("cornell-box", passes="normal", aovs=True, **kwargs)
    assert set(extra) == {"variance", "bias", "children", "normal"}
    with pytest.raises(styletrace.UsageError, match="bad value 'z' for passes"):
        api.render("cornell-box", passes="z", width=8, height=8)


def test_python_motion_moves_the_camera():
    """A still's vector is 0; a Motion naming the camera one frame before and after gives the
    pixels' motion (the kernel's tests check its values)."""
    scene = api.load_scene("cornell-box", 12, 8)
    here = np.array(scene.sensors()[0].world_transform().matrix).reshape(4, 4)
    step = np.eye(4)
    step[0, 3] = 0.05
    _, extra = styletrace.render(scene, spp=2, passes="depth,vector",
                                 motion=Motion(step @ here, np.linalg.inv(step) @ here))
    v, seen = extra["vector"], extra["depth"] < BACKGROUND_DEPTH
    # sideways: every point seen moves along x alike towards both frames, by its parallax
    assert seen.mean() > 0.5 and (np.abs(v[seen][:, 0]) > 0.05).all()
    np.testing.assert_allclose(v[..., 0], v[..., 2], atol=1e-4)
    assert np.abs(v[..., [1, 3]]).max() < 1e-3


def test_a_turntables_frames_carry_their_neighbours_cameras():
    """Frame k of `--frames 4 --orbit 40` renders on frame k's camera, its Vector towards the
    cameras of frames k - 1 and k + 1 (the turn continued past both ends)."""
    from dataclasses import replace

    from styletrace.animation.frame_chunks import FrameScene
    resolved = resolve(Job(scene="cornell-box", width=12, height=8, spp=2,
                           data_passes="depth,vector"))
    frames = turntable_frames(FrameScene.of(resolved, "llvm_ad_rgb"), resolved.scene, 4, 40.0,
                              motion=True)
    cams = turntable(resolved.scene, 4, 40.0, -1, 5)
    depths = []
    for k, frame in enumerate(frames):
        cam = np.array(frame.camera)
        assert np.array_equal(cam, cams[k + 1])
        assert np.array_equal(np.array(frame.motion[0]), cams[k])
        assert np.array_equal(np.array(frame.motion[1]), cams[k + 2])
        job = replace(resolved, job=resolved.job.with_(motion=Motion(*map(np.array,
                                                                          frame.motion))))
        out = Runner(job, OnRay("local", cam)).data_passes()  # traced here: no cluster needed
        want = render_data_passes(job.scene, ("depth", "vector"), 2, 0,
                                  Motion(cams[k], cams[k + 2]), camera=cam)
        for key in want:
            assert np.array_equal(out[key], want[key]), key
        assert np.abs(out["vector"]).max() > 0.5
        depths.append(out["depth"])
    assert not np.array_equal(depths[0], depths[2])  # each frame on its own camera
    # frame 0 is on the still's camera
    still = Runner(resolve(Job(scene="cornell-box", width=12, height=8, spp=2,
                               data_passes="depth")), OnRay("local")).data_passes()
    assert np.array_equal(still["depth"], depths[0])
    # without motion asked for, the same cameras and none around them
    plain = turntable_frames(frames[0].scene, resolved.scene, 4, 40.0, motion=False)
    assert [f.camera for f in plain] == [f.camera for f in frames]
    assert all(f.motion is None for f in plain)


def test_a_stopped_run_writes_the_passes_too(tmp_path):
    """Ctrl-C writes the finished passes without Mitsuba (`write_plain`, a kernel may be running):
    the data passes, traced before the first pass, are in that file as well."""
    from types import SimpleNamespace

    from styletrace.denoise.finishers import Image
    from styletrace.pipeline.denoising import Denoising
    from styletrace.pipeline.runner import Plain
    rng = np.random.default_rng(1)
    prog = SimpleNamespace(image=rng.random((4, 6, 3)).astype(np.float32), aovs=None)
    depth = rng.random((4, 6)).astype(np.float32)
    for finisher in (Plain(), Image(Denoising("image"))):
        finisher.data = {"depth": depth}
        path = finisher.write_plain(prog, str(tmp_path / "stopped.exr"), "rgb")
        ch = channels(path)
        assert set(ch) == {"R", "G", "B", "Depth.Z"}
        assert np.array_equal(ch["Depth.Z"], depth)


def test_a_frames_manifest_names_the_passes_only_where_given():
    """`--resume` must not mix frames with and without the passes' channels; a manifest of a run
    without passes stays as it was (older manifests resume)."""
    from styletrace.animation.frames import frame_settings
    asked = Job(scene="cornell-box", data_passes="vector, depth")
    settings = frame_settings("orbit", ["cornell-box"], [{}], 4, 90.0, asked, "llvm_ad_rgb")
    assert settings["passes"] == ["depth", "vector"]
    plain = frame_settings("orbit", ["cornell-box"], [{}], 4, 90.0, asked.with_(data_passes=()),
                           "llvm_ad_rgb")
    assert "passes" not in plain


def header(path) -> dict:
    meta = mi.Bitmap(str(path)).metadata()
    return {k: meta[k] for k in meta.keys() if k.startswith("cryptomatte/")}


def test_cryptomatte_channels_and_manifests_at_the_front_ends(tmp_path):
    """`--passes crypto_object,crypto_material` writes Cycles' channels and the standard's
    header; Python returns the same manifests; a stopped run's plain writer keeps them."""
    import json

    from styletrace.cryptomatte import type_key
    from styletrace.kernel.data_passes import MANIFEST
    out = tmp_path / "c.exr"
    asked = ["--passes", "crypto_object,crypto_material"]
    assert main(["render", "cornell-box", *SMALL, *asked, "-o", str(out)]) == 0
    ch, meta = channels(out), header(out)
    kinds = ("CryptoObject", "CryptoMaterial")
    assert {f"{t}{k:02d}.{c}" for t in kinds for k in range(3) for c in "rgba"} <= set(ch)
    _, extra = styletrace.render("cornell-box", style="cel", spp=2, inner=2, width=16,
                                 height=12, passes=asked[1])
    for kind in kinds:
        key = f"cryptomatte/{type_key(kind)}/"
        assert meta[key + "name"] == kind and meta[key + "hash"] == "MurmurHash3_32"
        assert meta[key + "conversion"] == "uint32_to_float32"
        names = json.loads(meta[key + "manifest"])
        assert names == extra[MANIFEST][kind]
        ids = {f"{v:08x}" for v in np.unique(ch[f"{kind}00.r"].view(np.uint32))} - {"00000000"}
        assert ids and ids <= set(names.values())
    assert set(extra[MANIFEST]["CryptoMaterial"]) == {"white", "red", "green"}
    from types import SimpleNamespace

    from styletrace.pipeline.runner import Plain
    finisher = Plain()
    finisher.data = dict(extra)
    prog = SimpleNamespace(image=np.zeros((12, 16, 3), np.float32), aovs=None)
    assert header(finisher.write_plain(prog, str(tmp_path / "stopped.exr"), "rgb")) == meta
