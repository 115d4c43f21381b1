"""Deterministic vertex normals (`styletrace.normals`): Mitsuba's own computed normals are the
truth, a file's own normals are never touched."""
import numpy as np

import styletrace
from styletrace.frontends.api import scene_dict
from styletrace.gate import mi
from styletrace.normals import TOLERANCE, angle_weighted, canonical_normals

styletrace.init()


def _dragon():
    return mi.load_dict(scene_dict("dragon", 16, 16))


def test_host_normals_match_mitsubas_computed_ones():
    params = mi.traverse(_dragon())
    positions = np.array(params["dragon.vertex_positions"], dtype=np.float64).reshape(-1, 3)
    faces = np.array(params["dragon.faces"], dtype=np.int64).reshape(-1, 3)
    loaded = np.array(params["dragon.vertex_normals"]).reshape(-1, 3)
    ours = angle_weighted(positions, faces)
    assert np.abs(ours - loaded).max() < TOLERANCE / 10  # measured 1.7e-6: far inside the tolerance


def test_computed_normals_are_replaced_and_the_same_on_every_load():
    buffers = set()
    for _ in range(2):
        scene = _dragon()
        assert canonical_normals(scene) == 1
        buffers.add(np.array(mi.traverse(scene)["dragon.vertex_normals"]).tobytes())
    assert len(buffers) == 1


def test_a_files_own_normals_stay():
    """A mesh whose normals were given (here: all tilted, not the angle-weighted ones) is left
    alone."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=np.float32)
    faces = np.array([[0, 1, 2], [1, 3, 2]], dtype=np.uint32)
    given = np.tile(np.array([0.6, 0.0, 0.8], dtype=np.float32), (4, 1))
    mesh = mi.Mesh("quad", 4, 2, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(positions.ravel())
    params["faces"] = mi.UInt32(faces.ravel())
    params["vertex_normals"] = mi.Float(given.ravel())
    params.update()
    scene = mi.load_dict({"type": "scene", "quad": mesh})
    assert canonical_normals(scene) == 0
    assert np.array_equal(np.array(mi.traverse(scene)["quad.vertex_normals"]).reshape(-1, 3), given)


def test_degenerate_faces_give_no_nan():
    positions = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [0, 1, 3]])  # the first is a line: zero area
    n = angle_weighted(positions, faces)
    assert np.isfinite(n).all()
    assert np.allclose(n[3], [0, 0, 1])
