"""The buffer file: round trip, version field, atomic writes, one-line errors; in memory, a recorded
buffer's arrays stay where the kernel wrote them until read (the same numbers then), and a copy of
the arrays is a copy of the names only."""
import json
import os

import numpy as np
import pytest

import styletrace
from styletrace.errors import UsageError
from styletrace.lookdev.buffer import VERSION, Arrays, bytes_per_camera_sample, load_buffer
from styletrace.lookdev.record import render_buffer
from styletrace.lookdev.restyle import restyle


@pytest.fixture(scope="module")
def buf():
    return render_buffer("cornell-box", style="cel", spp=2, inner=2, seed=1, width=12, height=10)


def test_round_trip(buf, tmp_path):
    path = buf.save(str(tmp_path / "b.npz"))
    assert os.listdir(tmp_path) == ["b.npz"]  # no temporary file left behind
    back = load_buffer(path)
    assert back.header == buf.header and back.header["version"] == VERSION
    for k, a in buf.arrays.items():
        np.testing.assert_array_equal(back.arrays[k], a)
    np.testing.assert_array_equal(restyle(path, style="color_map"), restyle(buf, style="color_map"))


def test_size_per_camera_sample_is_what_the_docs_say(buf):
    assert buf.camera_samples == 12 * 10 * 2
    per = bytes_per_camera_sample("first_hit")
    assert buf.nbytes == buf.camera_samples * per == buf.camera_samples * 65
    assert bytes_per_camera_sample("first_object_hit") == 81


def test_the_api_names(buf, tmp_path):
    path = buf.save(str(tmp_path / "c.npz"))
    back = styletrace.load_buffer(path)
    np.testing.assert_array_equal(
        styletrace.restyle(back, style="sepia"), restyle(buf, style="sepia")
    )
    assert styletrace.render_buffer is render_buffer


def test_bad_files(buf, tmp_path):
    with pytest.raises(UsageError, match="does not exist"):
        load_buffer(str(tmp_path / "none.npz"))
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(UsageError, match="'.*junk.npz' is not a styletrace buffer"):
        load_buffer(str(junk))
    newer = dict(buf.header, version=VERSION + 1)
    path = str(tmp_path / "newer.npz")
    np.savez(path, header=np.frombuffer(json.dumps(newer).encode(), dtype=np.uint8), **buf.arrays)
    with pytest.raises(
        UsageError,
        match=f"format version {VERSION + 1}; this styletrace reads version {VERSION} and earlier",
    ):
        load_buffer(path)
    with pytest.raises(UsageError, match="the extension must be .npz"):
        buf.save(str(tmp_path / "b.exr"))
    with pytest.raises(UsageError, match="does not exist"):
        buf.save(str(tmp_path / "no" / "b.npz"))


@pytest.mark.parametrize("make", ["xml", "other arrays", "other header"])
def test_a_file_that_is_no_buffer_is_named_in_one_line(make, tmp_path, capsys):
    """A scene file, numpy's own .npz or another program's header: "not a styletrace buffer",
    never numpy's advice on pickles; `styletrace restyle` says it with exit status 2."""
    if make == "xml":
        path = tmp_path / "scene.xml"
        path.write_text('<scene version="3.0.0"/>')
    elif make == "other arrays":
        path = tmp_path / "other.npz"
        np.savez(path, a=np.zeros(3))
    else:
        path = tmp_path / "header.npz"
        np.savez(path, header=np.frombuffer(b'{"format": "else"}', dtype=np.uint8))
    with pytest.raises(UsageError) as info:
        load_buffer(path)
    assert str(info.value) == (f"{str(path)!r} is not a styletrace buffer: expected the .npz file "
                               f"of `styletrace render --buffer` or Buffer.save")
    from styletrace.frontends.cli import main
    assert main(["restyle", str(path), "--style", "cel", "-o", str(tmp_path / "r.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is not a styletrace buffer" in err and "pickle" not in err


def test_a_saved_buffer_keeps_its_pilot_and_camera(buf, tmp_path):
    """Auto values (cel thresholds, hatching's pixel spacing) resolve from what the file keeps,
    as before saving."""
    back = load_buffer(buf.save(str(tmp_path / "p.npz")))
    assert (
        back.pilot_nbytes == buf.pilot_nbytes > 0 and back.header["sensor"] == buf.header["sensor"]
    )
    for style in ("cel", "hatching"):
        np.testing.assert_array_equal(restyle(back, style=style), restyle(buf, style=style))


def test_recorded_arrays_stay_on_the_device_until_read():
    b = render_buffer("cornell-box", style="cel", spp=2, inner=2, seed=1, width=8, height=6,
                      pass_spp=1)
    a = b.arrays
    assert not a.on_host("p") and a.length("p") == b.camera_samples == 8 * 6 * 2
    assert len(a.parts("p")) == 2  # one per pass
    nbytes = b.nbytes
    p = a["p"]  # read: joined on the host once
    assert p.shape == (3, b.camera_samples) and p.dtype == np.float32 and a.on_host("p")
    assert a["p"] is p and b.nbytes == nbytes
    np.testing.assert_array_equal(p, np.concatenate([np.asarray(x) for x in a.parts("p")], -1))
    assert a["slot"].dtype == np.int8 and a["pixel"].dtype == np.uint32


def test_a_copy_shares_the_arrays_not_the_names():
    a = Arrays({"x": np.arange(3.0)})
    a.append("x", np.arange(2.0))
    b = a.copy()
    b["y"] = np.zeros(5)
    del b["x"]
    assert list(a) == ["x"] and list(b) == ["y"]
    np.testing.assert_array_equal(a["x"], [0, 1, 2, 0, 1])
    assert len(a.parts("x")) == 1  # host parts joined once, not kept twice
