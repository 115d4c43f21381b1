"""Turntables and lists of scenes as numbered frames, each chunk of frames one Ray task; the orbit's
geometry."""
import os
import pickle
import subprocess
import sys

import numpy as np
from conftest import child_env

from styletrace.frontends import api
from styletrace.frontends.ray_command import frame_paths
from styletrace.gate import mi
from styletrace.pipeline.orbit import camera_target, orbit, rotation, sensor_to_world
from styletrace.pipeline.ray_describe import SceneSpec, _decode


def test_target_is_where_the_central_ray_hits_and_the_orbit_turns_about_it():
    """The furnace's camera at (0, 0, 4) looks at its unit sphere at the origin: the target is
    (0, 0, 1)."""
    scene = api.load_scene("furnace", 16, 16)
    m = sensor_to_world(scene)
    target = camera_target(scene)
    np.testing.assert_allclose(target, [0, 0, 1], atol=1e-5)
    mats = orbit(m, target, m[:3, 1], 4, 360.0)
    assert np.array_equal(mats[0], m)
    # half a turn about the y axis through it
    np.testing.assert_allclose(mats[2][:3, 3], [0, 0, -2], atol=1e-5)
    # a quarter turn (right-handed about +y)
    np.testing.assert_allclose(mats[1][:3, 3], [3, 0, 1], atol=1e-5)
    for k in range(4):  # the camera keeps its distance to the target and still looks at it
        fwd = mats[k][:3, 2] / np.linalg.norm(mats[k][:3, 2])
        np.testing.assert_allclose(np.cross(fwd, target - mats[k][:3, 3]), 0, atol=1e-6)


def test_target_falls_back_to_the_bbox_centre_when_the_central_ray_misses():
    scene = mi.load_dict(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0]
                ),
            },
            "s": {"type": "sphere", "center": [3, 0, 0], "radius": 1.0},
        }
    )
    np.testing.assert_allclose(camera_target(scene), [3, 0, 0], atol=1e-5)


def test_rotation_matches_mitsubas():
    axis = np.array([1.0, 2.0, 0.5])
    r = rotation(axis, 33.0)
    unit = (axis / np.linalg.norm(axis)).tolist()  # Mitsuba's rotate() takes a unit axis
    mit = np.array(mi.ScalarTransform4f().rotate(unit, 33.0).matrix, dtype=np.float64)
    np.testing.assert_allclose(r, mit[:3, :3], atol=1e-6)


def test_scene_dicts_with_transforms_travel_to_workers():
    d = api.scene_dict("cornell-box", 8, 8)
    spec = SceneSpec.of(d)
    back = _decode(pickle.loads(pickle.dumps(spec)).scene)
    a = np.array(d["sensor"]["to_world"].matrix)
    assert np.array_equal(np.array(back["sensor"]["to_world"].matrix), a)
    assert np.array_equal(api.load_scene(back).sensors()[0].world_transform().matrix,
                          api.load_scene(d).sensors()[0].world_transform().matrix)


def render_cli(*args):
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            "--width",
            "24",
            "--height",
            "16",
            "--spp",
            "2",
            "--style",
            "cel",
            "--inner",
            "2",
            "-q",
            *args,
        ],
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_turntable_frames_are_numbered_and_frame_zero_is_the_still(ray_cluster, tmp_path):
    out = str(tmp_path / "spin.exr")
    r = render_cli("cornell-box", "--frames", "3", "--orbit", "90", "-o", out, "--ray", ray_cluster)
    assert r.returncode == 0, r.stderr
    names = sorted(f for f in os.listdir(tmp_path) if f.endswith(".exr"))
    assert names == ["spin_0000.exr", "spin_0001.exr", "spin_0002.exr"]
    still = str(tmp_path / "still.exr")
    assert render_cli("cornell-box", "-o", still).returncode == 0
    frames = [np.array(mi.Bitmap(str(tmp_path / n))) for n in names]
    assert np.array_equal(frames[0], np.array(mi.Bitmap(still)))
    assert not np.array_equal(frames[1], frames[0])


def test_turntable_frames_on_ray_are_denoised_in_the_workers(ray_cluster, tmp_path):
    """With --denoise image each frame is denoised in its chunk's worker, with the guides of the
    frame's own camera: frame 0 is the denoised still (no history yet; to OIDN's rounding), and
    frame 1 is not frame 1 undenoised."""
    out, raw = str(tmp_path / "spin.exr"), str(tmp_path / "raw.exr")
    for path, how in ((out, "image"), (raw, "off")):
        r = render_cli("cornell-box", "--style", "identity", "--frames", "2", "--orbit", "40",
                       "--denoise", how, "-o", path, "--ray", ray_cluster)
        assert r.returncode == 0, r.stderr
    still = str(tmp_path / "still.exr")
    assert render_cli("cornell-box", "--style", "identity", "--denoise", "image",
                      "-o", still).returncode == 0
    frame = [np.array(mi.Bitmap(str(tmp_path / f"spin_{k:04d}.exr"))) for k in range(2)]
    noisy = np.array(mi.Bitmap(str(tmp_path / "raw_0001.exr")))
    np.testing.assert_allclose(frame[0], np.array(mi.Bitmap(still)), rtol=1e-5, atol=1e-6)
    assert not np.allclose(frame[1], noisy, rtol=1e-3, atol=1e-3)


def test_turntable_frames_carry_their_data_passes(ray_cluster, tmp_path):
    """`--passes depth,vector` on a turntable: each numbered EXR has the channels; frame 0's are a
    still's (its camera), and its vector is the turn's (the orbit's frame -1 and frame 1)."""
    out = str(tmp_path / "spin.exr")
    r = render_cli("cornell-box", "--frames", "2", "--orbit", "20", "--passes", "depth,vector",
                   "-o", out, "--ray", ray_cluster)
    assert r.returncode == 0, r.stderr
    still = str(tmp_path / "still.exr")
    assert render_cli("cornell-box", "--passes", "depth", "-o", still).returncode == 0

    def channels(path):
        bmp = mi.Bitmap(path)
        names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
        return dict(zip(names, np.moveaxis(np.array(bmp), -1, 0)))

    frames = [channels(str(tmp_path / f"spin_{k:04d}.exr")) for k in range(2)]
    alone = channels(still)
    for name in ("R", "G", "B", "Depth.Z"):
        assert np.array_equal(frames[0][name], alone[name]), name
    assert not np.array_equal(frames[1]["Depth.Z"], frames[0]["Depth.Z"])
    for ch in frames:
        seen = ch["Depth.Z"] < 1e9
        # a turn about the up axis through the target: sideways, more the farther from it
        for c in ("Vector.X", "Vector.Z"):
            assert seen.mean() > 0.5 and np.mean(np.abs(ch[c][seen]) > 0.1) > 0.5, c


def test_bad_frame_arguments_are_one_line(tmp_path):
    r = render_cli("cornell-box", "--orbit", "90", "-o", str(tmp_path / "a.png"))
    assert (
        r.returncode == 2 and "--orbit needs --frames N" in r.stderr and r.stderr.count("\n") == 1
    )
    r = render_cli("cornell-box", "--ray", "cornell-box", "-o", str(tmp_path / "a.png"))
    assert r.returncode == 2 and "bad --ray address 'cornell-box'" in r.stderr


SPHERE_XML = """<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="2"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/>
            <rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" \
value="{colour}"/></bsdf></shape>
</scene>
"""


def test_a_list_of_scene_files_renders_one_numbered_frame_each(ray_cluster, tmp_path):
    """Each file is one frame (their chunk a task on the cluster); frame k equals rendering file
    k on its own (the suite does not denoise by default: no reuse, the same seed)."""
    files = []
    for k, colour in enumerate(("0.8,0.2,0.2", "0.2,0.2,0.8")):
        path = tmp_path / f"s{k}.xml"
        path.write_text(SPHERE_XML.format(colour=colour))
        files.append(str(path))
    out = str(tmp_path / "seq.exr")
    r = render_cli(*files, "--style", "cel", "-o", out, "--ray", ray_cluster)
    assert r.returncode == 0, r.stderr
    for k, path in enumerate(files):
        alone = str(tmp_path / f"alone{k}.exr")
        assert render_cli(path, "--style", "cel", "-o", alone).returncode == 0
        assert np.array_equal(
            np.array(mi.Bitmap(str(tmp_path / f"seq_{k:04d}.exr"))), np.array(mi.Bitmap(alone))
        )
    first, second = (np.array(mi.Bitmap(str(tmp_path / f"seq_{k:04d}.exr"))) for k in range(2))
    assert not np.array_equal(first, second)


def test_frames_without_spp_print_the_auto_values_and_the_resolved_spp(ray_cluster, tmp_path):
    """The split of `--samples` is resolved per scene: the frames' run names it on the auto-values
    line and its summary gives the camera samples it rendered (it once said `spp None`)."""
    r = subprocess.run(
        [sys.executable, "-m", "styletrace", "render", "cornell-box", "--width", "16", "--height",
         "16", "--samples", "4", "--frames", "2", "-o", str(tmp_path / "t.png"), "--ray",
         ray_cluster],
        env=child_env(), capture_output=True, text=True, timeout=300,
    )
    assert r.returncode == 0, r.stderr
    auto = [line for line in r.stderr.splitlines() if line.startswith("styletrace: auto values:")]
    assert len(auto) == 1 and "samples=4: spp=1 x 4 children" in auto[0], r.stderr
    summary = r.stderr.strip().splitlines()[-1]
    assert summary.startswith("wrote 2 frames") and summary.endswith("spp 1, on Ray)"), summary


def turntable_chunks(seed, count, chunk):
    """A cel turntable through the expectation denoiser (16 x 16, Samples 4), with reuse."""
    from styletrace.animation.frame_chunks import FrameScene, chunks_of
    from styletrace.frontends.ray_command import turntable_frames
    from styletrace.pipeline.denoising import Denoising
    from styletrace.pipeline.job import python_job
    from styletrace.pipeline.resolve import resolve
    resolved = resolve(python_job("cornell-box", style="cel", samples=4, seed=seed, width=16,
                                  height=16, denoising=Denoising("auto")))
    assert resolved.method == "expectation"
    frames = turntable_frames(FrameScene.of(resolved, mi.variant()), resolved.scene, count, 30.0,
                              motion=True)
    return chunks_of(frames, chunk, reuse=True)


def test_frames_on_ray_are_the_local_frames_bit_for_bit_and_resume(ray_cluster, tmp_path):
    """Five frames in chunks of 2 (three chunks), denoised with reuse: each chunk one task in a
    worker (the pids it reports are not this process's), and every frame equals the frame
    rendered in this process, bit for bit; a resume on Ray writes a missing frame alone, the
    same again."""
    from styletrace.animation.frames import Manifest, render_frames
    from styletrace.animation.ray_frames import render_frames_on_ray
    chunks = turntable_chunks(3, 5, 2)
    here = [str(tmp_path / f"here_{k:04d}.exr") for k in range(5)]
    there = [str(tmp_path / f"ray_{k:04d}.exr") for k in range(5)]
    assert render_frames(chunks, here, Manifest(str(tmp_path / "here.exr"), {}))[1] == 0
    came = []
    written, status, pids = render_frames_on_ray(
        chunks, there, Manifest(str(tmp_path / "ray.exr"), {}), ray_cluster,
        on_frame=lambda i, path: came.append(i))
    assert status == 0 and sorted(written) == sorted(came) == list(range(5))
    assert pids and os.getpid() not in pids
    for a, b in zip(here, there):
        assert np.array_equal(np.array(mi.Bitmap(a)), np.array(mi.Bitmap(b))), b
    # resumed on Ray: the missing frame 3 alone is written (its chunk, frames 2 and 3, renders
    # again for its history; the chunks written whole are not sent), equal to the first run's
    manifest = Manifest(str(tmp_path / "ray.exr"), {})
    manifest.load()
    manifest.done.discard(3)
    manifest.add(0)
    os.remove(there[3])
    again = Manifest(str(tmp_path / "ray.exr"), {})
    written, status, _ = render_frames_on_ray(chunks, there, again, ray_cluster, resume=True)
    assert (written, status) == ([3], 0)
    assert np.array_equal(np.array(mi.Bitmap(here[3])), np.array(mi.Bitmap(there[3])))


def psnr(a, b):
    return float(10 * np.log10(1.0 / np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def test_a_24_frame_turntable_on_ray_is_as_clean_as_here(ray_cluster, tmp_path):
    """24 frames of a turntable (16 x 16, Samples 4, cel denoised, reuse on, chunks of 8: three
    tasks on the two workers), seeds 1 and 2, here and on Ray: the PSNR between the two seeds'
    frames on Ray is within 1 dB of that here (the frames are as clean); with the same pipeline
    in the workers, they are the same frames."""
    from styletrace.frontends.cli import main
    common = ["render", "cornell-box", "--style", "cel", "--width", "16", "--height", "16",
              "--samples", "4", "--denoise", "auto", "--frames", "24", "--orbit", "90", "-q"]
    seqs = {}
    for where in ("here", "ray"):
        for seed in (1, 2):
            out = str(tmp_path / f"{where}{seed}.exr")
            ray = ["--ray", ray_cluster] if where == "ray" else []
            assert main([*common, "--seed", str(seed), "-o", out, *ray]) == 0
            seqs[where, seed] = np.stack([np.array(mi.Bitmap(p))[..., :3]
                                          for p in frame_paths(out, 24)])
    here, there = psnr(seqs["here", 1], seqs["here", 2]), psnr(seqs["ray", 1], seqs["ray", 2])
    print(f"PSNR between seeds 1 and 2: here {here:.3f} dB, on Ray {there:.3f} dB")
    assert abs(here - there) < 1.0, (here, there)
    assert np.array_equal(seqs["here", 1], seqs["ray", 1])
