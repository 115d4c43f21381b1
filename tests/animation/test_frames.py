"""Command-line frames in chunks (animation/frame_chunks.py, animation/frames.py): temporal reuse
within a chunk, a fresh history at the next, and resume per frame."""
import numpy as np
import pytest

from styletrace.animation.frame_chunks import Frame, FrameScene, chunks_of, frame_seed, render_chunk
from styletrace.animation.frames import Manifest, render_frames
from styletrace.denoise.finishers import plan
from styletrace.gate import mi
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.job import python_job
from styletrace.pipeline.resolve import resolve
from styletrace.pipeline.runner import Runner


def job(seed, samples, size):
    return python_job("cornell-box", style="cel", samples=samples, seed=seed, width=size,
                      height=size, denoising=Denoising("auto"))


def still(seed, samples, size):
    out = plan(job(seed, samples, size)).result()
    return np.asarray(out[0] if isinstance(out, tuple) else out)[..., :3]


def read(path):
    return np.array(mi.Bitmap(str(path)))[..., :3]


def frames_of(seed, samples, size, count):
    """`count` frames of one still shot (the same scene, camera and settings: a list of the same
    file), with the render's seed."""
    resolved = resolve(job(seed, samples, size))
    assert resolved.method == "expectation"
    return [Frame(FrameScene.of(resolved, mi.variant()))] * count


def test_frame_seeds_wrap_at_32_bits():
    assert frame_seed(7, 0) == 7 and frame_seed(7, 3) == 10
    assert frame_seed(2**32 - 1, 2) == 1


def test_a_still_shots_frames_converge_within_a_chunk_and_the_next_chunk_starts_afresh(tmp_path):
    """Cel through the expectation denoiser, 32 x 32, Samples 16, seed 1, chunks of 8: the error
    of frame k against the converged image (two renders at Samples 1024, mean((d - r1)(d - r2)),
    their noise cancels) falls with k; frame 7 meets about 8 frames' samples, so its error is
    under 0.75 of the mean error of the same frames without reuse (each frame its seed, alone;
    measured 0.63, and 0.56 from seed 21: the denoiser's bias and the hold's lag, which reuse
    does not remove, are in both; tests/denoise/test_temporal_frames.py measures 0.68 on 48 x
    48). Frame 8, the second chunk's first, has no history: it is the first frame of a fresh run
    from its seed, bit for bit."""
    size, samples, seed = 32, 16, 1
    r1, r2 = still(1001, 1024, size), still(1002, 1024, size)
    chunks = chunks_of(frames_of(seed, samples, size, 9), 8, reuse=True)
    assert [list(c.indices) for c in chunks] == [list(range(8)), [8]]
    paths = {i: str(tmp_path / f"f_{i:04d}.exr") for i in range(9)}
    for chunk in chunks:
        assert [i for i, _ in render_chunk(chunk, paths)] == list(chunk.indices)
    frames = [read(paths[i]) for i in range(9)]

    def error(image):
        return float(np.mean((image - r1) * (image - r2)))

    reused = [error(f) for f in frames[:8]]
    alone = [error(still(frame_seed(seed, i), samples, size)) for i in range(8)]
    assert np.array_equal(frames[0], still(seed, samples, size))  # no history yet: the still
    assert reused[-1] < reused[0] and reused[-1] < 0.75 * np.mean(alone), (reused, alone)
    fresh = str(tmp_path / "fresh.exr")
    first = chunks_of(frames_of(frame_seed(seed, 8), samples, size, 1), 8, reuse=True)[0]
    list(render_chunk(first, {0: fresh}))
    assert np.array_equal(frames[8], read(fresh))


@pytest.mark.parametrize("reuse", [True, False])
def test_resume_writes_the_missing_frame_as_the_first_run_did(tmp_path, monkeypatch, reuse):
    """Frame 4 of 6 (chunks of 3) deleted with its manifest entry: a resume writes it alone and
    equal to the first run's. With reuse its chunk renders again from its first frame (frame 3,
    for its history, not written) and stops after it; without reuse only frame 4 renders."""
    frames = frames_of(5, 4, 16, 6)
    chunks = chunks_of(frames, 3, reuse)
    paths = [str(tmp_path / f"f_{i:04d}.exr") for i in range(6)]
    settings = {"test": "frames"}
    assert render_frames(chunks, paths, Manifest(str(tmp_path / "f.exr"), settings)) == (
        list(range(6)), 0)
    first = [read(p) for p in paths]
    # with reuse each frame its seed; without, a still shot's frames are one image
    assert np.array_equal(first[3], first[4]) != reuse
    runs = {"write": 0, "result": 0}
    for name in runs:
        original = getattr(Runner, name)

        def counted(self, *a, _original=original, _name=name, **k):
            runs[_name] += 1
            return _original(self, *a, **k)
        monkeypatch.setattr(Runner, name, counted)
    manifest = Manifest(str(tmp_path / "f.exr"), settings)
    manifest.load()
    manifest.done.discard(4)
    manifest.add(0)  # rewritten without frame 4
    (tmp_path / "f_0004.exr").unlink()
    written, status = render_frames(chunks, paths, Manifest(str(tmp_path / "f.exr"), settings),
                                    resume=True)
    assert (written, status) == ([4], 0)
    assert runs == {"write": 1, "result": 1 if reuse else 0}
    assert np.array_equal(read(paths[4]), first[4])
    assert Manifest(str(tmp_path / "f.exr"), settings).load() == set(range(6))
