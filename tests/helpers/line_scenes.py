"""The scene of the lifted-lines tests (tests/kernel): a box seen directly (left) and, with a
plane behind the camera, in a mirror ball (right; `flat`: a flat mirror facing the camera, turned
8 degrees, instead)."""
import numpy as np

from styletrace.gate import dr, mi

RES = 64


def line_scene(alpha=0.0, flat=False, res=RES, light=None) -> dict:
    """The scene as a dict; `light`: a constant environment's grey radiance (None: no light at
    all)."""
    T = mi.ScalarTransform4f
    ball = {"type": "conductor", "material": "none"} if alpha == 0 else \
        {"type": "roughconductor", "material": "none", "distribution": "ggx", "alpha": alpha}
    grey = {"type": "diffuse"}
    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 40,
            "to_world": T().look_at(origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
        },
        "box": {
            "type": "cube",
            "bsdf": grey,
            "to_world": T().translate([-1.4, 0, 0]) @ T().rotate([1, 1, 0], 30) @ T().scale(0.7),
        },
        "ball": {
            "type": "rectangle",
            "bsdf": ball,
            "to_world": T().translate([1.4, 0, 0]) @ T().rotate([0, 1, 0], -8) @ T().scale(1.0),
        }
        if flat
        else {"type": "sphere", "center": [1.4, 0, 0], "radius": 1.1, "bsdf": ball},
        "back": {
            "type": "rectangle",
            "bsdf": grey,
            "to_world": T().translate([1.0, 0.5, 8])
            @ T().rotate([0, 1, 0], 180)
            @ T().scale([1.5, 1.0, 1]),
        },
    }
    if light is not None:
        d["light"] = {"type": "constant", "radiance": {"type": "rgb", "value": [light] * 3}}
    return d


def reference(sc, t, spp=16, seed=3):
    """Image-space lines: the pair test on id(s), the shape seen along the perfectly specular
    path from s (reflection about the shading normal at the ball), with the type's stencil and
    count."""
    w = h = RES
    n = w * h * spp
    idx = np.arange(n) // spp
    col, row = (idx % w).astype(np.float32), (idx // w).astype(np.float32)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, n)
    jx, jy = np.array(sampler.next_2d())
    from styletrace.kernel.lifted_lines import Lifted
    lifted = Lifted(sc, [t], depth=2)
    s = mi.Point2f(w / 2 - col - jx, h / 2 - row - jy)
    ball = [x for x in sc.shapes() if x.id() == "ball"][0]
    ball_id = dr.reinterpret_array(mi.UInt32, mi.ShapePtr(ball))

    def ident(p):
        ray = lifted._ray(p, mi.Bool(True))
        si = sc.ray_intersect(ray)
        sid = dr.select(si.is_valid(), dr.reinterpret_array(mi.UInt32, si.shape), 0xFFFFFFFF)
        on_ball = si.is_valid() & (sid == ball_id)
        n_ = mi.Vector3f(si.sh_frame.n)
        r2 = si.spawn_ray(dr.normalize(ray.d - 2 * dr.dot(ray.d, n_) * n_))
        si2 = sc.ray_intersect(r2, active=on_ball)
        sid2 = dr.select(si2.is_valid(), dr.reinterpret_array(mi.UInt32, si2.shape), 0xFFFFFFFE)
        return np.array(dr.select(on_ball, sid2, sid))

    fired = np.zeros(n, bool)
    for _ in range(t.count):
        du, dv = lifted._offsets(t, sampler), lifted._offsets(t, sampler)
        fired |= ident(s + du) != ident(s + dv)
    return fired.reshape(h, w, spp).mean(axis=2)


def ball_mask(sc):
    """Pixels whose centre ray hits the ball, two pixels inside its rim."""
    from styletrace.config.line_types import LineType
    from styletrace.kernel.lifted_lines import Lifted
    lifted = Lifted(sc, [LineType("shape_id")], depth=1)
    col, row = np.meshgrid(np.arange(RES), np.arange(RES))
    s = mi.Point2f(
        (RES / 2 - col - 0.5).ravel().astype(np.float32),
        (RES / 2 - row - 0.5).ravel().astype(np.float32),
    )
    si = sc.ray_intersect(lifted._ray(s, mi.Bool(True)))
    ball = [x for x in sc.shapes() if x.id() == "ball"][0]
    m = np.array(si.is_valid()) & (np.array(dr.reinterpret_array(mi.UInt32, si.shape)) ==
                                   np.array(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(ball)))[0])
    m = m.reshape(RES, RES)
    # inside, not its rim
    return m & np.roll(m, 2, 0) & np.roll(m, -2, 0) & np.roll(m, 2, 1) & np.roll(m, -2, 1)
