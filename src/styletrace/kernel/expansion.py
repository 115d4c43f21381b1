"""The expansion pass: every pixel's E[X] and E[X^2] at its first stylized vertex, for the
series' b* = E[X^2] / E[X].

A render of PASS_SPP camera samples per pixel (seed: `pipeline.passes.expansion_seed`) in which
each lane's first stylized vertex draws ceil(m / PASS_SPP) children and sums r and r^2 per channel,
r = x - e (e: the vertex's emission), summed per pixel on the host. A render lane then reads its
pixel's means (`lane_pixels`) and `estimator_registry.series_with_pass` expands about b from them.

    maps = Expansion()                         # the integrator's
    maps.prepare(integrator, scene, m, seed)   # per film crop, before its passes (pipeline.passes)
    sets = maps.lookup(scene, width, m)        # in sample(): per set, the pixel's mean r and r^2
Design: docs/design/expansion_pass.md.
"""
from __future__ import annotations

import numpy as np

from styletrace.errors import SettingsError
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.jit import no_collection
from styletrace.kernel.launch import render_pass

#: Camera samples per pixel of the pass, each drawing ceil(m / PASS_SPP) children: the pixel's
#: footprint, not one point of it (a lane whose children are far brighter than its pixel's b
#: diverges: docs/design/expansion_pass.md).
PASS_SPP = 4


def crop_key(scene: mi.Scene) -> tuple:
    """What fixes the lane -> pixel layout of a render of the scene's first sensor: its film's crop
    and border.

    Args:
        scene: the scene.

    Returns:
        ((offset x, y), (width, height), border in pixels, 0 without sample_border).
    """
    film = scene.sensors()[0].film()
    border = int(film.rfilter().border_size()) if film.sample_border() else 0
    return (
        tuple(int(v) for v in film.crop_offset()),
        tuple(int(v) for v in film.crop_size()),
        border,
    )


def pixel_count(key: tuple) -> int:
    """The film pixels of a crop, its border included.

    Args:
        key: a `crop_key`.

    Returns:
        int.
    """
    (_, (w, h), border) = key
    return (w + 2 * border) * (h + 2 * border)


def lane_pixels(width: int, pixels: int) -> mi.UInt32:
    """The film pixel of every lane of a wavefront of `width` lanes over `pixels` pixels
    (Mitsuba's pixel-major layout: each pixel's samples side by side).

    Args:
        width: the wavefront's lanes. pixels: the film's pixels (`pixel_count`).

    Returns:
        mi.UInt32.

    Raises:
        SettingsError: `width` is no multiple of `pixels`.
    """
    if width % pixels:
        raise SettingsError(
            f"bad wavefront of {width} lanes for a film of {pixels} pixels with expansion_pass: "
            f"expected a multiple (Mitsuba's pixel-major layout)"
        )
    return dr.arange(mi.UInt32, width) // (width // pixels)


def moments(draw, sampler, active, m: int, known):
    """(sum of r, sum of r^2) over m draws x = `draw(sampler)` per active lane, r = x - known, in
    one symbolic loop.

    Args:
        draw: draw(sampler) -> one child x (mi.Color3f). sampler: the lane's random stream.
        active: the lanes that draw (mi.Bool). m: the draws per lane.
        known: the part of x that is the same in every child (the vertex's own emission).

    Returns:
        (mi.Color3f, mi.Color3f).
    """
    def cond(i, s1, s2, smp):
        return active & (i < m)

    def body(i, s1, s2, smp):
        r = draw(smp) - known
        return i + 1, s1 + r, s2 + r * r, smp

    _, s1, s2, _ = dr.while_loop(
        state=(mi.UInt32(0), mi.Color3f(0.0), mi.Color3f(0.0), sampler), cond=cond, body=body
    )
    return s1, s2


class Collector:
    """The pass's sums per lane (PASS_SPP lanes per pixel): r and r^2 per channel, and whether the
    lane reached a stylized vertex; summed per pixel on the host in a fixed order (float atomics
    would not be).

    Args:
        pixels: the film's pixels (`pixel_count`).
        m: the children per pixel (each lane draws ceil(m / PASS_SPP)).
    """

    def __init__(self, pixels: int, m: int):
        self.pixels, self.m = pixels, m
        self.children = -(-m // PASS_SPP)  # per camera sample: m per pixel in all (rounded up)
        lanes = pixels * PASS_SPP
        self.s1, self.s2 = dr.zeros(mi.Float, 3 * lanes), dr.zeros(mi.Float, 3 * lanes)
        self.hit = dr.zeros(mi.Float, lanes)

    def add(self, width: int, active, s1: mi.Color3f, s2: mi.Color3f) -> None:
        """Record the sums of the lanes that reached a stylized vertex.

        Args:
            width: the wavefront's lanes (PASS_SPP per pixel).
            active: the lanes that reached one (mi.Bool). s1, s2: their sums of r and r^2.

        Raises:
            SettingsError: the wavefront has not PASS_SPP lanes per pixel.
        """
        if width != self.pixels * PASS_SPP:
            raise SettingsError(
                f"bad wavefront of {width} lanes in the expansion pass: expected {PASS_SPP} per "
                "pixel"
            )
        lane = dr.arange(mi.UInt32, width)
        for c in range(3):
            dr.scatter(self.s1, s1[c], 3 * lane + c, active)
            dr.scatter(self.s2, s2[c], 3 * lane + c, active)
        dr.scatter(self.hit, mi.Float(1.0), lane, active)

    def means(self, key: tuple) -> list[tuple[np.ndarray, np.ndarray]]:
        """[(mean r, mean r^2) of each pixel's own children, the same over its 3 x 3 window], each
        (rows, columns, 3); a pixel without children of its own takes its window's.

        Args:
            key: the crop's `crop_key`.

        Returns:
            Two (mean r, mean r^2) pairs of float64 arrays.
        """
        (_, (w, h), border) = key
        rows, cols = h + 2 * border, w + 2 * border
        n = (
            np.asarray(self.hit, dtype=np.float64)
            .reshape(rows, cols, PASS_SPP)
            .sum(axis=2)[..., None]
        )
        n = n * self.children
        s1 = np.asarray(self.s1, dtype=np.float64).reshape(rows, cols, PASS_SPP, 3).sum(axis=2)
        s2 = np.asarray(self.s2, dtype=np.float64).reshape(rows, cols, PASS_SPP, 3).sum(axis=2)

        def window(a):  # sums over the 3 x 3 window (edges padded with nothing)
            p = np.pad(a, ((1, 1), (1, 1), (0, 0)))
            return sum(p[i:i + rows, j:j + cols] for i in range(3) for j in range(3))
        wn, w1, w2 = window(n), window(s1), window(s2)
        hole = n[..., 0] == 0
        n = np.where(hole[..., None], wn, n)
        s1 = np.where(hole[..., None], w1, s1)
        s2 = np.where(hole[..., None], w2, s2)
        return [
            (s1 / np.maximum(n, 1.0), s2 / np.maximum(n, 1.0)),
            (w1 / np.maximum(wn, 1.0), w2 / np.maximum(wn, 1.0)),
        ]


class Moments:
    """One crop's per-pixel means of r and r^2 on the device (one or more sets), and its key
    and seed.

    Args:
        key: the crop's `crop_key`. seed: the pass's seed.
        sets: (mean r, mean r^2) arrays of shape (rows, columns, 3) per set (`Collector.means`).
    """

    def __init__(self, key: tuple, seed: int, sets):
        self.key, self.seed = key, seed
        # (rows, cols, 3) each
        self.host = [(m1.astype(np.float32), m2.astype(np.float32)) for m1, m2 in sets]
        self.device = [
            (mi.Float(aligned(np.ravel(m1))), mi.Float(aligned(np.ravel(m2))))
            for m1, m2 in self.host
        ]
        self.pixels = pixel_count(key)

    def b_star(self, known=0.0) -> np.ndarray:
        """b* = E[x^2] / E[x] per pixel and channel for x = known + r (0 where E[x] is 0), before
        any clamp (the largest over the sets).

        Args:
            known: the part of x every child shares (a float, or an array that broadcasts).

        Returns:
            float64 array (rows, columns, 3).
        """
        out = None
        for m1, m2 in self.host:
            m1, m2 = m1.astype(np.float64), m2.astype(np.float64)
            e1, e2 = known + m1, known * known + 2.0 * known * m1 + m2
            b = np.where(e1 > 0, e2 / np.where(e1 > 0, e1, 1.0), 0.0)
            out = b if out is None else np.maximum(out, b)
        return out

    def lookup(self, width: int) -> list[tuple[mi.Color3f, mi.Color3f]]:
        """Each render lane's pixel's means.

        Args:
            width: the wavefront's lanes (a multiple of the crop's pixels).

        Returns:
            Per set, (mean r, mean r^2) as mi.Color3f.

        Raises:
            SettingsError: `width` is no multiple of the crop's pixels.
        """
        pix = lane_pixels(width, self.pixels)
        get = lambda a: mi.Color3f(*(dr.gather(mi.Float, a, 3 * pix + c) for c in range(3)))  # noqa: E731
        return [(get(m1), get(m2)) for m1, m2 in self.device]


class Expansion:
    """The pass results of the render under way, one per film crop (pipeline.passes renders tiles
    as crops)."""

    def __init__(self):
        self.maps: dict[tuple, Moments] = {}
        self.collector: Collector | None = None  # set while a pass is rendered

    def clear(self) -> None:
        self.maps = {}

    def prepare(self, integrator, scene: mi.Scene, m: int, seed: int) -> Moments:
        """The moments of the scene's current film crop, from a pass with `seed` (rendered once
        per crop and seed).

        Args:
            integrator: the `stylized` integrator whose pass it is. scene: the scene.
            m: the children per pixel (`expansion_pass`). seed: the pass's seed.

        Returns:
            Moments.
        """
        key = crop_key(scene)
        done = self.maps.get(key)
        if done is not None and done.seed == seed:
            return done
        self.collector = Collector(pixel_count(key), m)
        try:
            # as pipeline.passes: no scene finalised while the pass is recorded
            with no_collection():
                render_pass(scene, integrator, PASS_SPP, seed)
                sets = self.collector.means(key)
        finally:
            self.collector = None
        self.maps[key] = Moments(key, seed, sets)
        return self.maps[key]

    def lookup(self, scene: mi.Scene, width: int, m: int) -> list[tuple[mi.Color3f, mi.Color3f]]:
        """Each render lane's pixel's means, for the scene's current film crop.

        Args:
            scene: the scene. width: the wavefront's lanes.
            m: `expansion_pass` (for the message).

        Returns:
            Per set, (mean r, mean r^2) as mi.Color3f.

        Raises:
            SettingsError: no pass was prepared for the crop (a bare mi.render), or a bad width.
        """
        found = self.maps.get(crop_key(scene))
        if found is None:
            raise SettingsError(
                f"bad value {m} for 'expansion_pass' here: its pre-pass runs in styletrace's "
                "passes (styletrace.render, api.passes, the command line), not in a bare "
                "mi.render; render through them or use expansion_pass=0"
            )
        return found.lookup(width)


__all__ = ["Expansion", "Moments", "Collector", "moments", "lane_pixels", "crop_key"]
