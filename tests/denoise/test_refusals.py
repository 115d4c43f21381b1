"""Every combination `--denoise` does not support is refused in one line with exit status 2,
before rendering; so is a missing `denoise` extra (the message names it)."""
import subprocess
import sys

import pytest
from conftest import child_env  # noqa: F401  (tests/conftest.py: the source tree first on PYTHONPATH)

import styletrace
from styletrace.errors import UsageError

SMALL = ["--width", "16", "--height", "16", "--spp", "2", "--inner", "2", "-q"]


def run_cli(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "styletrace", "render", *args],
        capture_output=True,
        text=True,
        env=env or child_env(),
        timeout=300,
    )


REFUSED = [
    (["--denoise", "expectation", "--lines"], "feature lines"),
    (["--denoise", "expectation", "--reuse", "pixels"], "--reuse pixels"),
    (
        [
            "--denoise",
            "expectation",
            "--style",
            "saturation",
            "--stylize",
            "first_n_hits",
            "--stylize-depth",
            "2",
            "--inner",
            "2,2",
        ],
        "first_n_hits",
    ),
    (
        ["--denoise", "expectation", "--style", "gamma", "--estimator", "series"],
        "estimator 'series'",
    ),
    (["--denoise", "expectation", "--inner", "2:8"], "adaptive counts"),
    (["--denoise", "expectation", "--style", "acp"], "style 'acp'"),
    (["--denoise", "expectation", "--ray"], "renders in this process"),
    (["--denoise", "image", "--buffer", "x.npz"], "--buffer with --denoise image"),
    (["--denoise", "sharpen"], "invalid choice"),
    (["--denoise", "image", "--denoise-quality", "best"], "invalid choice"),
    (["--denoise", "expectation", "--coverage", "5"], "bad value '5' for coverage"),
    (["--denoise", "expectation", "--coverage", "lots"], "bad value 'lots' for coverage"),
    (["--denoise", "image", "--coverage", "16"], "applies to --denoise expectation only"),
    (["--coverage", "16"], "applies to --denoise expectation only"),
    (
        ["--denoise", "expectation", "--denoise-uncertainty", "-1"],
        "bad value '-1' for denoise uncertainty",
    ),
    (
        ["--denoise", "expectation", "--denoise-uncertainty", "nan"],
        "bad value 'nan' for denoise uncertainty",
    ),
    (
        ["--denoise", "image", "--denoise-uncertainty", "0.3"],
        "applies to --denoise expectation only",
    ),
]


@pytest.mark.parametrize("args,words", REFUSED, ids=[w for _, w in REFUSED])
def test_refused_in_one_line(tmp_path, args, words):
    extra = SMALL[:6] + (SMALL[6:8] if "--inner" not in args else []) + ["-q"]
    res = run_cli(*args, *extra, "-o", str(tmp_path / "out.png"))
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], res.stderr
    assert not (tmp_path / "out.png").exists()


def test_without_the_extra_the_command_names_it(tmp_path):
    """A `pyoidn` that cannot be imported (a package first on the path that raises ImportError)
    stands in for an install without the extra."""
    blocked = tmp_path / "block" / "pyoidn"
    blocked.mkdir(parents=True)
    (blocked / "__init__.py").write_text("raise ImportError('pyoidn is not installed (test)')\n")
    env = child_env()
    env["PYTHONPATH"] = f"{tmp_path / 'block'}:{env['PYTHONPATH']}"
    res = run_cli("--denoise", "expectation", *SMALL, "-o", str(tmp_path / "out.png"), env=env)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "styletrace[denoise]" in lines[0], res.stderr


def test_python_api_refuses_the_same(monkeypatch):
    with pytest.raises(UsageError, match="feature lines"):
        styletrace.render("cornell-box", style="cel", spp=1, inner=2, width=8, height=8, lines=True,
                          denoise="expectation")
    with pytest.raises(UsageError, match="bad value 'median' for denoise"):
        styletrace.render("cornell-box", spp=1, width=8, height=8, denoise="median")
    with pytest.raises(UsageError, match="cluster"):
        styletrace.render("cornell-box", spp=1, width=8, height=8, denoise="expectation",
                          cluster="local")
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import pyoidn now raises ImportError
    with pytest.raises(UsageError, match=r"styletrace\[denoise\]"):
        styletrace.render("cornell-box", spp=1, width=8, height=8, denoise="image")
