"""The `styled` BSDF: forwards light transport to the BSDF it wraps; bad properties are one-line
errors."""
import numpy as np
import pytest

from styletrace.frontends.cli import main
from styletrace.gate import mi


def sphere_scene(bsdf):
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "to_world": mi.ScalarTransform4f().look_at([0, 0, 4], [0, 0, 0], [0, 1, 0]),
            "film": {"type": "hdrfilm", "width": 16, "height": 16, "rfilter": {"type": "box"}},
        },
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": {
            "type": "point",
            "position": [2, 2, 3],
            "intensity": {"type": "rgb", "value": 10},
        },
    }


def test_path_sees_the_wrapped_bsdf():
    """Under Mitsuba's own `path`, wrapping changes nothing: the same seed gives the same image."""
    plain = {"type": "roughconductor", "alpha": 0.2}
    wrapped = {"type": "styled", "style": "cel", "bsdf": dict(plain)}
    path = mi.load_dict({"type": "path"})
    a = mi.render(mi.load_dict(sphere_scene(plain)), integrator=path, spp=8, seed=3)
    b = mi.render(mi.load_dict(sphere_scene(wrapped)), integrator=path, spp=8, seed=3)
    np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-5, atol=1e-6)


XML = """<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer \
name="height" value="8"/></film></sensor>
  <shape type="sphere"><bsdf type="styled">{inside}</bsdf></shape>
</scene>"""


@pytest.mark.parametrize(
    "inside,message",
    [
        (
            '<string name="style" value="cel"/><string name="thresholds" value="0.5"/><string '
            'name="levels" value="0.5"/>'
            '<bsdf type="diffuse"/>',
            "bad value '0.5' for parameter 'levels'",
        ),
        ('<string name="style" value="cel"/>', "needs exactly one nested BSDF, found 0"),
        ('<bsdf type="diffuse"/>', "needs a 'style' property"),
        (
            '<string name="style" value="cel"/><float name="spacing" value="0.1"/><bsdf '
            'type="diffuse"/>',
            "unknown property 'spacing' for a 'styled' BSDF with style 'cel'",
        ),
        (
            '<string name="style" value="cel"/><string name="estimator" value="series"/><bsdf '
            'type="diffuse"/>',
            "estimator 'series' does not apply to style 'cel'",
        ),
    ],
)
def test_bad_styled_bsdf_is_one_line(tmp_path, capsys, inside, message):
    path = tmp_path / "s.xml"
    path.write_text(XML.format(inside=inside))
    assert main(["render", str(path), "-q", "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err
