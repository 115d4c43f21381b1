"""Writing images: EXR linear, PNG sRGB and clamped, atomic and checked, and a render is never
lost."""
import errno
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from conftest import child_env

import styletrace
from styletrace import images
from styletrace.gate import mi
from styletrace.images import save_safely, write_image

styletrace.init()


def read(path):
    bmp = mi.Bitmap(str(path))
    scale = 255.0 if bmp.component_format() == mi.Struct.Type.UInt8 else 1.0
    return np.array(bmp, dtype=np.float64) / scale


def srgb(x):
    """The sRGB transfer function (IEC 61966-2-1) on [0, 1]."""
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def test_a_failed_write_keeps_the_render(tmp_path, capsys):
    """If writing fails after rendering (e.g. the folder vanished), the image goes to a temporary
    EXR."""
    img = np.full((4, 6, 3), 0.25, dtype=np.float32)
    out = save_safely(img, str(tmp_path / "gone" / "x.png"))
    assert out != str(tmp_path / "gone" / "x.png") and out.endswith(".exr")
    np.testing.assert_array_equal(read(out), img)
    assert "saved the render to" in capsys.readouterr().err
    os.remove(out)


def test_png_clamps_instead_of_wrapping(tmp_path):
    """Above 1 is white however bright (Mitsuba's own 8-bit conversion wraps past ~2410 to
    black), below 0 and NaN are black, +inf white; in-range values are the sRGB code within
    rounding."""
    values = np.array(
        [1e4, 3000, 2410.5, -1, np.nan, np.inf, -np.inf, 0.5, 0.002, 1.0], dtype=np.float32
    )
    expect = np.array([1, 1, 1, 0, 0, 1, 0, srgb(0.5), srgb(0.002), 1.0])
    img = np.repeat(values[None, :, None], 3, axis=2)
    write_image(img, str(tmp_path / "c.png"))
    got = read(tmp_path / "c.png")[0, :, 0]
    assert np.abs(got - expect).max() <= 0.5 / 255 + 1e-9, got * 255


def test_exr_keeps_what_it_is_given(tmp_path):
    img = np.array([[[1e4, -1, np.nan], [np.inf, 0.5, 3000]]], dtype=np.float32)
    write_image(img, str(tmp_path / "c.exr"))
    np.testing.assert_array_equal(read(tmp_path / "c.exr"), img)
    assert images.nonfinite_pixels(img) == 2


def redirect_temp_files(monkeypatch, folder, device):
    """Temporary files made in `folder` get their data written to `device` (e.g. /dev/full)."""
    real = images.tempfile.mkstemp

    def mkstemp(**kw):
        fd, path = real(**kw)
        if os.path.samefile(kw.get("dir") or "/", folder):
            os.close(fd)
            fd = os.open(device, os.O_WRONLY)
        return fd, path

    monkeypatch.setattr(images.tempfile, "mkstemp", mkstemp)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_full_disk_raises_and_keeps_the_old_file(tmp_path, monkeypatch):
    """Writes to /dev/full fail with ENOSPC: the write raises, the old file and folder are
    untouched."""
    dest = tmp_path / "x.exr"
    old = np.full((2, 3, 3), 0.75, dtype=np.float32)
    write_image(old, str(dest))
    redirect_temp_files(monkeypatch, tmp_path, "/dev/full")
    with pytest.raises(OSError) as exc:
        write_image(np.zeros((64, 64, 3), np.float32), str(dest))
    assert exc.value.errno == errno.ENOSPC
    np.testing.assert_array_equal(read(dest), old)
    assert sorted(os.listdir(tmp_path)) == ["x.exr"]  # no temporary file left behind


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_full_disk_falls_back_to_a_temporary_exr(tmp_path, monkeypatch, capsys):
    redirect_temp_files(monkeypatch, tmp_path, "/dev/full")
    img = np.full((4, 4, 3), 0.5, dtype=np.float32)
    out = save_safely(img, str(tmp_path / "x.png"))
    assert out != str(tmp_path / "x.png") and not (tmp_path / "x.png").exists()
    np.testing.assert_array_equal(read(out), img)
    assert "No space left on device" in capsys.readouterr().err
    os.remove(out)


def test_a_short_write_is_detected(tmp_path, monkeypatch):
    """A writer that drops bytes but reports success (as Mitsuba's Bitmap.write does on a full
    disk)."""
    real = os.fdopen

    class Lossy:
        def __init__(self, f):
            self.f = f

        def write(self, data):
            self.f.write(data[: len(data) // 2])
            return len(data)

        def __getattr__(self, name):
            return getattr(self.f, name)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

    monkeypatch.setattr(images.os, "fdopen", lambda fd, mode: Lossy(real(fd, mode)))
    with pytest.raises(OSError, match="short write"):
        write_image(np.ones((8, 8, 3), np.float32), str(tmp_path / "x.exr"))
    assert os.listdir(tmp_path) == []


def test_a_failed_rename_keeps_the_old_file(tmp_path, monkeypatch):
    dest = tmp_path / "x.png"
    write_image(np.zeros((4, 4, 3), np.float32), str(dest))
    before = dest.read_bytes()

    def fail(src, dst):
        raise OSError(errno.EIO, "simulated failure")

    monkeypatch.setattr(images.os, "replace", fail)
    with pytest.raises(OSError):
        write_image(np.ones((4, 4, 3), np.float32), str(dest))
    assert dest.read_bytes() == before and os.listdir(tmp_path) == ["x.png"]


def test_the_destination_is_replaced_not_rewritten(tmp_path):
    """A reader that opened the old file keeps reading the old file: the new one is a new inode."""
    dest = tmp_path / "x.exr"
    write_image(np.zeros((4, 4, 3), np.float32), str(dest))
    with open(dest, "rb") as old:
        inode = os.fstat(old.fileno()).st_ino
        content = dest.read_bytes()
        write_image(np.ones((4, 4, 3), np.float32), str(dest))
        assert os.stat(dest).st_ino != inode
        assert old.read() == content
    np.testing.assert_array_equal(read(dest), 1.0)


def test_two_writers_of_one_path_leave_a_readable_file(tmp_path):
    dest = str(tmp_path / "x.exr")
    imgs = [np.full((256, 256, 3), v, dtype=np.float32) for v in (0.25, 0.5)]

    def writer(img):
        for _ in range(5):
            write_image(img, dest)

    threads = [threading.Thread(target=writer, args=(img,)) for img in imgs]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    got = read(dest)
    assert any(np.array_equal(got, img) for img in imgs)
    assert os.listdir(tmp_path) == ["x.exr"]


KILLED_WRITER = """
import sys, numpy as np, styletrace
styletrace.init()
from styletrace.images import write_image
img = np.random.default_rng(0).random((1024, 1024, 3), dtype=np.float32)
print("ready", flush=True)
while True:
    write_image(img, sys.argv[1])
"""


def test_kill_9_during_writes_never_leaves_a_broken_file(tmp_path):
    """A process rewriting a 12 MB EXR in a loop is killed at several moments; the file always
    reads."""
    dest = tmp_path / "x.exr"
    write_image(np.zeros((1024, 1024, 3), np.float32), str(dest))
    for delay in (0.05, 0.13, 0.31, 0.52):
        proc = subprocess.Popen(
            [sys.executable, "-c", KILLED_WRITER, str(dest)],
            stdout=subprocess.PIPE,
            env=child_env(),
        )
        assert proc.stdout.readline().strip() == b"ready"
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
        assert read(dest).shape == (1024, 1024, 3)


def test_a_written_file_gets_ordinary_permissions(tmp_path):
    """The temporary file is private (0o600); the image must not stay so: a new file gets 0o666
    less the umask, a replaced one keeps its own bits."""
    from styletrace.images import write_image
    img = np.full((4, 6, 3), 0.25, dtype=np.float32)
    umask = os.umask(0o022)
    try:
        fresh = tmp_path / "fresh.png"
        write_image(img, str(fresh))
        assert fresh.stat().st_mode & 0o777 == 0o644
        kept = tmp_path / "kept.exr"
        kept.write_bytes(b"")
        kept.chmod(0o640)
        write_image(img, str(kept))
        assert kept.stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(umask)


@pytest.mark.parametrize(
    "pixel_format,channels,ext",
    [
        ("rgb", 3, ".exr"),
        ("rgb", 3, ".png"),
        ("rgba", 4, ".exr"),
        ("rgba", 4, ".png"),
        ("luminance", 1, ".exr"),
        ("luminance", 1, ".png"),
        ("luminance_alpha", 2, ".exr"),
        ("luminance_alpha", 2, ".png"),
        ("xyz", 3, ".exr"),
    ],
)
def test_the_plain_encoder_writes_what_mitsuba_writes(tmp_path, pixel_format, channels, ext):
    """`encode_plain` (the interrupted render's writer, which must not wait for a running kernel)
    gives the file Mitsuba reads back as the same pixels, in the same pixel format, as Mitsuba's
    own encoding."""
    img = (np.random.default_rng(3).random((5, 7, channels)) * 3).astype(np.float32)
    img[0, 0, 0], img[1, 1, -1] = np.nan, np.inf
    write_image(img, str(tmp_path / f"plain{ext}"), pixel_format, plain=True)
    write_image(img, str(tmp_path / f"mitsuba{ext}"), pixel_format)
    a, b = mi.Bitmap(str(tmp_path / f"plain{ext}")), mi.Bitmap(str(tmp_path / f"mitsuba{ext}"))
    assert a.pixel_format() == b.pixel_format() and a.component_format() == b.component_format()
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_the_plain_encoder_keeps_the_aov_channels(tmp_path):
    rng = np.random.default_rng(4)
    img = rng.random((4, 6, 3)).astype(np.float32)
    aovs = {
        "variance": rng.random((4, 6, 3)),
        "bias": rng.random((4, 6)),
        "children": rng.random((4, 6)),
    }
    write_image(img, str(tmp_path / "plain.exr"), "rgb", aovs, plain=True)
    write_image(img, str(tmp_path / "mitsuba.exr"), "rgb", aovs)
    a, b = mi.Bitmap(str(tmp_path / "plain.exr")), mi.Bitmap(str(tmp_path / "mitsuba.exr"))
    assert [name for name, _ in a.split()] == [name for name, _ in b.split()]
    for (_, x), (_, y) in zip(a.split(), b.split()):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


@pytest.mark.parametrize("plain", [False, True])
def test_the_data_passes_follow_the_aovs_under_blenders_names(tmp_path, plain):
    """Depth, Normal and Vector are written after the image and the AOVs present, each channel
    named pass.channel as Blender names them; a PNG has no room for them."""
    rng = np.random.default_rng(5)
    img = rng.random((4, 6, 3)).astype(np.float32)
    extra = {"vector": rng.random((4, 6, 4)), "depth": rng.random((4, 6)),
             "children": rng.random((4, 6))}
    write_image(img, str(tmp_path / "a.exr"), "rgb", extra, plain=plain)
    bmp = mi.Bitmap(str(tmp_path / "a.exr"))
    arr = np.array(bmp)
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    assert set(names) == {"R", "G", "B", "children", "Depth.Z", "Vector.X", "Vector.Y",
                          "Vector.Z", "Vector.W"}, names
    for i, c in enumerate("XYZW"):
        np.testing.assert_array_equal(arr[..., names.index(f"Vector.{c}")],
                                      extra["vector"][..., i].astype(np.float32))
    np.testing.assert_array_equal(arr[..., names.index("Depth.Z")],
                                  extra["depth"].astype(np.float32))
    with pytest.raises(ValueError, match="data passes are written to .exr files only"):
        write_image(img, str(tmp_path / "a.png"), "rgb", {"depth": extra["depth"]}, plain=plain)


@pytest.mark.skipif(not os.path.isdir("/sys"), reason="needs Linux's /sys")
def test_a_folder_that_refuses_new_files_is_refused_before_the_render():
    """/sys passes `os.access(W_OK)` for root but refuses file creation: the check makes a file
    to know (one line, naming the output and the folder)."""
    with pytest.raises(styletrace.UsageError) as info:
        images.check_target("/sys/out.png")
    message = str(info.value)
    assert "\n" not in message and message.startswith("cannot write '/sys/out.png': ")
    # root: the folder refuses the attempt; anyone else: the permission bits already do
    assert ("folder '/sys' refuses new files" in message) == os.access("/sys", os.W_OK)


def test_the_check_of_a_target_leaves_its_folder_as_it_was(tmp_path):
    (tmp_path / "old.png").write_bytes(b"old")
    images.check_target(str(tmp_path / "new.exr"))
    images.check_target(str(tmp_path / "old.png"))
    assert sorted(os.listdir(tmp_path)) == ["old.png"]
    assert (tmp_path / "old.png").read_bytes() == b"old"
