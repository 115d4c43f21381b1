"""coordinate: the vertex's image coordinate and how it was found, as a colour (LLaT's lifting).

Reference: "Lifting Lines and Tone: Image-space Stylization in Path-space", Rex West, Sayan
Mukherjee and Yonghao Yue (ACM TOG 45(4), 2026), Section 5 (canonical lifting) and S2.5 (fallbacks).

No parameters. Closed form (no children): g = (s_x, s_y, method), s the image coordinate the
integrator computed for the vertex (`Vertex.s`, pixels right and up of the image centre;
kernel/anchors.py), method its code (kernel/mls.py): 0 the pixel (direct view), 1 the first-edge
pixel of an all-delta prefix, 2 MLS, 3 affine, 4 nearest anchor, 5 first-edge fallback. On a
styled object with one camera sample per pixel it is the lifting's coordinate and method AOV;
averaged over samples, their pixel mean.
Without a coordinate (a renderer that computes none): s the vertex's projection, method 0.
"""
from __future__ import annotations

from styletrace.gate import dr, mi
from styletrace.styles.base import Projection, Style, Vertex, projection
from styletrace.styles.registry import register_style


@register_style
class Coordinate(Style):
    """The coordinate style (the module doc).

    Args:
        **values: none are accepted (the style has no parameters).

    Raises:
        StyleError: any parameter given.
    """

    name = "coordinate"
    summary = "debug: the vertex's image coordinate (pixels) and how it was found (LLaT) as r, g, b"
    default_inner = 0
    wants_coordinate = True

    def __init__(self, **values):
        super().__init__(**values)
        self.projection = Projection()

    def prepare(self, scene: mi.Scene) -> None:
        self.projection = projection(scene)

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        if v.s is None:
            x, y = self.projection.pixels(v.p)
            return mi.Color3f(x, y, dr.zeros(mi.Float, dr.width(x)))
        return mi.Color3f(v.s.x, v.s.y, mi.Float(v.method))
