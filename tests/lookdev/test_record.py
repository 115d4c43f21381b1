"""Recording refuses a film that `pipeline.passes` would render in tiles.

A buffer maps lane i of a pass to pixel i // spp of the whole film; a film of more than LANES_PER_PASS pixels is
rendered tile by tile, and its samples would land on the first tile's pixels (measured before the refusal: the
restyle of a 1100 x 1000 buffer differed from its own render by up to 2.85). Refused in one line, before
the first pass renders (after the buffer's cap on camera samples), in Python and on the command line (`--denoise expectation` records a buffer)."""
import subprocess
import sys

import pytest

from styletrace import api
from styletrace.errors import UsageError
from styletrace.lookdev.record import record
from styletrace.pipeline.passes import LANES_PER_PASS

from conftest import child_env  # noqa: F401  (tests/conftest.py: the source tree first on PYTHONPATH)


def test_a_tiled_film_is_refused_before_the_first_pass():
    scene = api.load_scene("cornell-box", 1025, 1024)
    assert 1025 * 1024 > LANES_PER_PASS
    with pytest.raises(UsageError, match=r"a buffer of 1025x1024 \(1049600 pixels\) is over the 1048576 pixels"):
        next(record(scene, api.make_integrator(style="cel", inner=1), 1))


def test_a_film_of_one_pass_is_recorded():
    scene = api.load_scene("cornell-box", 8, 6)
    prog, buf = next(record(scene, api.make_integrator(style="cel", inner=1), 1))
    assert buf.samples == 48


def test_the_command_line_refuses_in_one_line(tmp_path):
    res = subprocess.run([sys.executable, "-m", "styletrace", "render", "--denoise", "expectation", "--width", "1100",
                          "--height", "1000", "--spp", "1", "--inner", "1", "-q", "-o", str(tmp_path / "o.png")],
                         capture_output=True, text=True, env=child_env(), timeout=300)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and "is over the 1048576 pixels" in lines[0], res.stderr
    assert not (tmp_path / "o.png").exists()
