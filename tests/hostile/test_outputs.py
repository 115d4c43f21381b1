"""Hostile outputs and sizes for the command line: each case is one line on stderr and its exit status.

`{tmp}` in an argument is the test's temporary folder; `setup` prepares files there first. Every case
must fail before rendering, so each takes well under a second after the backend is up.
"""
import os

import pytest

import styletrace
from styletrace.cli import main

styletrace.init()

SCENE = """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>
<integer name="height" value="4"/></film></sensor><shape type="sphere"/><emitter type="constant"/></scene>"""


def scene_file(tmp):
    (tmp / "scene.xml").write_text(SCENE)
    (tmp / "scene.exr").write_text(SCENE)
    os.symlink(tmp / "scene.exr", tmp / "link.exr")


def a_file(tmp):
    (tmp / "plain").write_text("not a folder")


def read_only(tmp):
    (tmp / "ro").mkdir()
    (tmp / "ro").chmod(0o500)


CORPUS = [
    # (command line, setup, exit status, message fragment)
    (["render", "--width", "1000000", "--height", "1000000", "-o", "{tmp}/x.png"], None, 2,
     "image 1000000x1000000 is too large"),
    (["render", "--width", "300000", "--height", "300000", "-o", "{tmp}/x.exr"], None, 2, "GiB available"),
    (["render", "{tmp}/scene.exr", "-o", "{tmp}/scene.exr"], scene_file, 2, "it is the scene file being rendered"),
    (["render", "{tmp}/scene.exr", "-o", "{tmp}/link.exr"], scene_file, 2, "it is the scene file being rendered"),
    (["render", "{tmp}/scene.exr", "-o", "{tmp}/./scene.exr"], scene_file, 2, "it is the scene file being rendered"),
    (["render", "{tmp}/new\nline.xml", "-o", "{tmp}/x.png"], None, 2, "new\\nline.xml' does not exist"),
    (["render", "-o", "{tmp}/no\nsuch/x.png"], None, 2, "no\\nsuch' does not exist"),
    (["render", "-o", "{tmp}/x\n.jpg"], None, 2, "bad output"),
    (["gallery", "-o", "{tmp}/no/such/dir"], None, 2, "folder '{tmp}/no/such' does not exist"),
    (["gallery", "-o", "{tmp}/plain"], a_file, 2, "expected a folder"),
    (["gallery", "--only", "nope\nx", "-o", "{tmp}/g"], None, 2, "unknown gallery setup(s) nope\\nx"),
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
