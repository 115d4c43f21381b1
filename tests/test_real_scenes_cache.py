"""The row cache of benchmarks/real_scenes.py: a stopped run goes on where it stopped, rows keyed
by code, scene, style and size; and where the panel is looked for. No render: numpy only."""
import json
import os
import sys

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


@pytest.fixture(scope="module")
def rs():
    sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
    try:
        import real_scenes
    finally:
        sys.path.pop(0)
    return real_scenes


def image(value):
    return np.full((3, 4, 3), value, dtype=np.float32)


def test_a_kept_row_is_not_rendered_again_and_the_rest_is_in_order(rs, tmp_path):
    """Rows put before a stop are found by a new cache on the same folder (a new process);
    only the keys it lacks are left to render, in the order asked."""
    wanted = [rs.row_key("abc", "classroom", s, 24) for s in (rs.REFERENCE, "identity", "cel")]
    cache = rs.RowCache(tmp_path)
    cache.put(wanted[0], {"time": 1.0}, image(0.5))
    cache.put(wanted[1], {"time": 2.0}, image(0.25))
    kept = rs.RowCache(tmp_path).rows()
    assert rs.to_render(wanted, kept) == [wanted[2]]
    assert rs.to_render(wanted, kept, fresh=True) == wanted
    row = kept[wanted[1]]
    assert (row["code"], row["scene"], row["style"], row["size"], row["time"]) == (
        "abc", "classroom", "identity", 24, 2.0)
    np.testing.assert_array_equal(cache.image(row), image(0.25))


def test_the_key_tells_code_scene_style_and_size_apart(rs, tmp_path):
    cache = rs.RowCache(tmp_path)
    cache.put(rs.row_key("abc", "classroom", "cel", 24), {"time": 1.0}, image(0.5))
    kept = cache.rows()
    for other in (("abd", "classroom", "cel", 24), ("abc", "etoile", "cel", 24),
                  ("abc", "classroom", "gamma", 24), ("abc", "classroom", "cel", 256)):
        assert rs.to_render([rs.row_key(*other)], kept) == [rs.row_key(*other)]


def test_a_torn_last_line_is_skipped_and_the_next_row_is_read(rs, tmp_path):
    """A crash in the middle of an append leaves a torn line: its row is rendered again, and the
    next row starts a line of its own."""
    cache = rs.RowCache(tmp_path)
    first = rs.row_key("abc", "classroom", "identity", 24)
    cache.put(first, {"time": 1.0}, image(0.5))
    with open(cache.file, "a") as f:
        f.write('{"code": "abc", "scene": "classroom", "sty')
    assert list(cache.rows()) == [first]
    second = rs.row_key("abc", "classroom", "cel", 24)
    cache.put(second, {"time": 3.0}, image(0.5))
    assert set(cache.rows()) == {first, second}


def test_the_later_of_two_rows_wins_and_a_row_without_its_image_is_not_kept(rs, tmp_path):
    cache = rs.RowCache(tmp_path)
    key = rs.row_key("abc", "classroom", "cel", 24)
    cache.put(key, {"time": 1.0}, image(0.5))
    stored = cache.put(key, {"time": 2.0}, image(0.75))
    assert cache.rows()[key]["time"] == 2.0
    np.testing.assert_array_equal(cache.image(cache.rows()[key]), image(0.75))
    os.remove(tmp_path / stored["image"])
    assert cache.rows() == {}


def test_rows_of_another_row_format_are_not_kept(rs, tmp_path):
    cache = rs.RowCache(tmp_path)
    key = rs.row_key("abc", "classroom", "cel", 24)
    stored = cache.put(key, {"time": 1.0}, image(0.5))
    cache.file.write_text(json.dumps(dict(stored, format=rs.ROW_FORMAT + 1)) + "\n")
    assert cache.rows() == {}


def test_the_panel_is_given_then_the_environment_then_shared_where_it_exists(rs, tmp_path):
    shared, legacy = tmp_path / "shared", tmp_path / "legacy"
    env = {"STYLETRACE_PANEL": str(tmp_path / "env")}
    assert rs.panel_folder(None, {}, shared, legacy) == legacy
    shared.mkdir()
    assert rs.panel_folder(None, {}, shared, legacy) == shared
    assert rs.panel_folder(None, env, shared, legacy) == tmp_path / "env"
    assert rs.panel_folder(str(tmp_path / "given"), env, shared, legacy) == tmp_path / "given"
