"""Hostile outputs and sizes for the command line: each case is one line on stderr and its exit
status.

`{tmp}` in an argument is the test's temporary folder; `setup` prepares files there first. Every
case must fail before rendering, so each takes well under a second after the backend is up.
"""
import os
import stat
import tempfile

import numpy as np
import pytest

import styletrace
from styletrace.frontends.cli import main
from styletrace.gate import mi

styletrace.init()

SCENE = """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer \
name="width" value="4"/>
<integer name="height" value="4"/></film></sensor><shape type="sphere"/><emitter \
type="constant"/></scene>"""


def scene_file(tmp):
    (tmp / "scene.xml").write_text(SCENE)
    (tmp / "scene.exr").write_text(SCENE)
    os.symlink(tmp / "scene.exr", tmp / "link.exr")


def a_file(tmp):
    (tmp / "plain").write_text("not a folder")


def tiny_scene(tmp):
    (tmp / "tiny.xml").write_text(SCENE)


def odd_targets(tmp):
    """Names that are no regular file: a fifo, links to a device, a fifo, a folder, and a link
    loop."""
    tiny_scene(tmp)
    os.mkfifo(tmp / "fifo.exr")
    os.mkfifo(tmp / "frame_0001.exr")  # the second image of `--frames 2 -o frame.exr`
    (tmp / "dir").mkdir()
    os.symlink("/dev/null", tmp / "null.exr")
    os.symlink(tmp / "fifo.exr", tmp / "to_fifo.png")
    os.symlink(tmp / "dir", tmp / "to_dir.exr")
    os.symlink(tmp / "loop.exr", tmp / "loop.exr")


def read_only(tmp):
    (tmp / "ro").mkdir()
    (tmp / "ro").chmod(0o500)


CORPUS = [
    # (command line, setup, exit status, message fragment)
    (
        ["render", "--width", "1000000", "--height", "1000000", "-o", "{tmp}/x.png"],
        None,
        2,
        "image 1000000x1000000 is too large",
    ),
    (
        ["render", "--width", "300000", "--height", "300000", "-o", "{tmp}/x.exr"],
        None,
        2,
        "GiB available",
    ),
    (
        ["render", "{tmp}/scene.exr", "-o", "{tmp}/scene.exr"],
        scene_file,
        2,
        "it is the scene file being rendered",
    ),
    (
        ["render", "{tmp}/scene.exr", "-o", "{tmp}/link.exr"],
        scene_file,
        2,
        "it is the scene file being rendered",
    ),
    (
        ["render", "{tmp}/scene.exr", "-o", "{tmp}/./scene.exr"],
        scene_file,
        2,
        "it is the scene file being rendered",
    ),
    (
        ["render", "{tmp}/tiny.xml", "-o", "{tmp}/fifo.exr"],
        odd_targets,
        2,
        "'{tmp}/fifo.exr': it is a fifo;",
    ),
    (
        ["render", "{tmp}/tiny.xml", "-o", "{tmp}/null.exr"],
        odd_targets,
        2,
        "'{tmp}/null.exr': it is a character device (a link to '/dev/null')",
    ),
    (
        ["render", "{tmp}/tiny.xml", "-o", "{tmp}/to_fifo.png"],
        odd_targets,
        2,
        "to_fifo.png': it is a fifo (a link",
    ),
    (
        ["render", "{tmp}/tiny.xml", "-o", "{tmp}/to_dir.exr"],
        odd_targets,
        2,
        "to_dir.exr': it is a folder (a link",
    ),
    (
        ["render", "{tmp}/tiny.xml", "-o", "{tmp}/loop.exr"],
        odd_targets,
        2,
        "loop.exr': it is not a usable path",
    ),
    (
        ["render", "{tmp}/tiny.xml", "--frames", "2", "-o", "{tmp}/frame.exr"],
        odd_targets,
        2,
        "'{tmp}/frame_0001.exr': it is a fifo;",
    ),
    (
        ["render", "{tmp}/tiny.xml", "-q", "--buffer", "{tmp}/b.npz", "-o", "{tmp}/x.exr"],
        lambda tmp: (tiny_scene(tmp), os.mkfifo(tmp / "b.npz")),
        2,
        "'{tmp}/b.npz': it is a fifo;",
    ),
    (
        ["render", "{tmp}/new\nline.xml", "-o", "{tmp}/x.png"],
        None,
        2,
        "new\\nline.xml' does not exist",
    ),
    (["render", "-o", "{tmp}/no\nsuch/x.png"], None, 2, "no\\nsuch' does not exist"),
    (["render", "-o", "{tmp}/x\n.jpg"], None, 2, "bad output"),
    (["gallery", "-o", "{tmp}/no/such/dir"], None, 2, "folder '{tmp}/no/such' does not exist"),
    (["gallery", "-o", "{tmp}/plain"], a_file, 2, "expected a folder"),
    (
        ["gallery", "--only", "nope\nx", "-o", "{tmp}/g"],
        None,
        2,
        "unknown gallery setup(s) nope\\nx",
    ),
]


@pytest.mark.parametrize("argv,setup,status,message", CORPUS, ids=[c[3] for c in CORPUS])
def test_hostile_output_is_one_line(argv, setup, status, message, tmp_path, capsys):
    if setup is not None:
        setup(tmp_path)
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(args) == status
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("styletrace: error: "), err
    assert message.replace("{tmp}", str(tmp_path)) in err
    if setup is odd_targets:  # refused untouched
        assert stat.S_ISFIFO(os.lstat(tmp_path / "fifo.exr").st_mode)
        assert stat.S_ISFIFO(os.lstat(tmp_path / "frame_0001.exr").st_mode)
        for name in ("null.exr", "to_fifo.png", "to_dir.exr", "loop.exr"):
            assert os.path.islink(tmp_path / name)
        assert os.readlink(tmp_path / "null.exr") == "/dev/null" and stat.S_ISCHR(
            os.stat("/dev/null").st_mode
        )
        assert sorted(os.listdir(tmp_path / "dir")) == []


def links(tmp):
    """out.exr -> ../real/target.exr (relative), and chain.png -> hop.png -> ../real/deep.png."""
    tiny_scene(tmp)
    (tmp / "real").mkdir()
    (tmp / "links").mkdir()
    (tmp / "real" / "target.exr").write_text("old")
    os.symlink(os.path.join("..", "real", "target.exr"), tmp / "links" / "out.exr")
    os.symlink(os.path.join("..", "real", "deep.png"), tmp / "links" / "hop.png")  # not there yet
    os.symlink("hop.png", tmp / "links" / "chain.png")


@pytest.mark.parametrize("name,target", [("out.exr", "target.exr"), ("chain.png", "deep.png")])
def test_an_output_that_is_a_link_is_written_through_it(tmp_path, monkeypatch, name, target):
    """The image lands in the link's final target, through a temporary file beside that target
    (so that the rename stays within one folder and file system); the links stay links, pointing
    where they did."""
    links(tmp_path)
    folders = []
    real_mkstemp = tempfile.mkstemp

    def mkstemp(*args, **kw):
        folders.append(os.path.realpath(kw["dir"]))
        return real_mkstemp(*args, **kw)

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    before = {n: os.readlink(tmp_path / "links" / n) for n in ("out.exr", "hop.png", "chain.png")}
    assert (
        main(
            [
                "render",
                str(tmp_path / "tiny.xml"),
                "--spp",
                "1",
                "-q",
                "-o",
                str(tmp_path / "links" / name),
            ]
        )
        == 0
    )
    assert {n: os.readlink(tmp_path / "links" / n) for n in before} == before
    assert os.path.isfile(tmp_path / "real" / target) and sorted(
        os.listdir(tmp_path / "links")
    ) == sorted(before)
    # the check before the render and the write both make their temporary file beside the target
    assert folders and set(folders) == {str(tmp_path / "real")}
    assert np.asarray(mi.Bitmap(str(tmp_path / "real" / target))).shape[:2] == (4, 4)


def test_gallery_fails_before_it_renders(tmp_path, capsys):
    """A missing parent folder is refused before anything is written or rendered."""
    assert main(["gallery", "--quick", "-o", str(tmp_path / "a" / "b")]) == 2
    assert not (tmp_path / "a").exists()


def test_read_only_gallery_folder(tmp_path, capsys):
    read_only(tmp_path)
    if os.access(tmp_path / "ro", os.W_OK):
        pytest.skip("running as root: permission bits are not enforced")
    assert main(["gallery", "--quick", "-o", str(tmp_path / "ro")]) == 2
    assert "permission denied" in capsys.readouterr().err


def test_unknown_gallery_setup_creates_nothing(tmp_path, capsys):
    assert main(["gallery", "--only", "nope", "-o", str(tmp_path / "g")]) == 2
    assert not (tmp_path / "g").exists()
