"""The expansion pass: every pixel's E[X] and E[X^2] at its first stylized vertex, for the
series' b*.

Why (docs/estimators.md, "Gamma and the series estimators"): a series estimate is a sum of products
of (x - b) / b over children, whose second moments grow like rho^k with rho = E[(X - b)^2] / b^2;
rho is smallest at b* = E[X^2] / E[X] (rho = cv^2 / (1 + cv^2) < 1). b* is a ratio of moments that
the rare bright children dominate, so it needs many children (64 per pixel measured on three firefly
scenes; 16 fail): too many to draw per estimate, cheap once per pixel. This module draws them once
per pixel, before the render.

How
    The pass is Mitsuba's own render loop at PASS_SPP camera samples per pixel (another seed than
    the render's passes: `api.expansion_seed`), with the integrator in collecting mode: at the first
    stylized vertex each lane draws ceil(m / PASS_SPP) children and keeps the sums of r and r^2 per
    channel, r = x - e, e the vertex's own emission (part of every child, known per lane: it is
    added back per lane, so a render lane on a light in a pixel whose pass saw the wall beside it
    still gets a b above its emission); nothing else is estimated there. The sums are taken per
    pixel on the host. Mitsuba lays a wavefront out pixel by pixel, each pixel's spp samples next to
    each other (lane i is pixel i // spp of the film's crop, border included;
    SamplingIntegrator::render in Mitsuba's integrator.cpp), so `lane_pixels` is a render lane's
    pixel. A render lane then reads its pixel's moments (`Moments.lookup`), a function of its lane
    only, never of its own children, and `estimator_registry.series_with_pass` expands about b =
    PASS_B_SCALE x the larger of E[(e + R)^2] / E[e + R] over the pixel's own children and over its
    3 x 3 window's (9x the children: a bright child that one pixel's m missed is often seen by its
    neighbours'), with its own e: the series estimate stays unbiased. A pixel whose pass samples
    reached no stylized vertex (they saw the environment) takes its window's moments, else none (b
    falls to the style's floor).

    maps = Expansion()                            # the integrator's
    # per film crop, before its passes (api.passes does it)
    maps.prepare(integrator, scene, m, seed)
    # in sample(): the lane's pixel's mean r and r^2 (Color3f)
    m1, m2 = maps.lookup(scene, width, m)
"""
from __future__ import annotations

import numpy as np

from styletrace.errors import SettingsError
from styletrace.gate import dr, mi
from styletrace.jit import no_collection

#: Camera samples per pixel of the pass, each drawing ceil(m / PASS_SPP) children: the pixel's
#: footprint, not one point of it (a lane whose children are far brighter than its pixel's b
#: diverges: see the docstring).
PASS_SPP = 4


def crop_key(scene: mi.Scene) -> tuple:
    """What fixes the lane -> pixel layout of a render of the scene's first sensor: its film's crop
    and border."""
    film = scene.sensors()[0].film()
    border = int(film.rfilter().border_size()) if film.sample_border() else 0
    return (
        tuple(int(v) for v in film.crop_offset()),
        tuple(int(v) for v in film.crop_size()),
        border,
    )


def pixel_count(key: tuple) -> int:
    (_, (w, h), border) = key
    return (w + 2 * border) * (h + 2 * border)


def lane_pixels(width: int, pixels: int) -> mi.UInt32:
    """The film pixel of every lane of a wavefront of `width` lanes over `pixels` pixels."""
    if width % pixels:
        raise SettingsError(
            f"bad wavefront of {width} lanes for a film of {pixels} pixels with expansion_pass: "
            f"expected a multiple (Mitsuba's pixel-major layout)"
        )
    return dr.arange(mi.UInt32, width) // (width // pixels)


def moments(draw, sampler, active, m: int, known):
    """(sum of r, sum of r^2) over m draws x = `draw(sampler)` per active lane, r = x - known (the
    part of x that is the same in every child: the vertex's own emission), in one symbolic loop."""
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
    would not be)."""

    def __init__(self, pixels: int, m: int):
        self.pixels, self.m = pixels, m
        self.children = -(-m // PASS_SPP)  # per camera sample: m per pixel in all (rounded up)
        lanes = pixels * PASS_SPP
        self.s1, self.s2 = dr.zeros(mi.Float, 3 * lanes), dr.zeros(mi.Float, 3 * lanes)
        self.hit = dr.zeros(mi.Float, lanes)

    def add(self, width: int, active, s1: mi.Color3f, s2: mi.Color3f) -> None:
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
        (rows, columns, 3); a pixel without children of its own takes its window's."""
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
    and seed."""

    def __init__(self, key: tuple, seed: int, sets):
        self.key, self.seed = key, seed
        # (rows, cols, 3) each
        self.host = [(m1.astype(np.float32), m2.astype(np.float32)) for m1, m2 in sets]
        self.device = [
            (mi.Float(np.ascontiguousarray(m1).ravel()), mi.Float(np.ascontiguousarray(m2).ravel()))
            for m1, m2 in self.host
        ]
        self.pixels = pixel_count(key)

    def b_star(self, known=0.0) -> np.ndarray:
        """b* = E[x^2] / E[x] per pixel and channel for x = known + r (0 where E[x] is 0), before
        any clamp (the largest over the sets)."""
        out = None
        for m1, m2 in self.host:
            m1, m2 = m1.astype(np.float64), m2.astype(np.float64)
            e1, e2 = known + m1, known * known + 2.0 * known * m1 + m2
            b = np.where(e1 > 0, e2 / np.where(e1 > 0, e1, 1.0), 0.0)
            out = b if out is None else np.maximum(out, b)
        return out

    def lookup(self, width: int) -> list[tuple[mi.Color3f, mi.Color3f]]:
        pix = lane_pixels(width, self.pixels)
        get = lambda a: mi.Color3f(*(dr.gather(mi.Float, a, 3 * pix + c) for c in range(3)))  # noqa: E731
        return [(get(m1), get(m2)) for m1, m2 in self.device]


class Expansion:
    """The pass results of the render under way, one per film crop (api.passes renders tiles
    as crops)."""

    def __init__(self):
        self.maps: dict[tuple, Moments] = {}
        self.collector: Collector | None = None  # set while a pass is rendered

    def clear(self) -> None:
        self.maps = {}

    def prepare(self, integrator, scene: mi.Scene, m: int, seed: int) -> Moments:
        """The moments of the scene's current film crop, from a pass with `seed` (rendered once
        per crop)."""
        key = crop_key(scene)
        done = self.maps.get(key)
        if done is not None and done.seed == seed:
            return done
        self.collector = Collector(pixel_count(key), m)
        try:
            with no_collection():  # as api.passes: no scene finalised while the pass is recorded
                mi.render(scene, integrator=integrator, spp=PASS_SPP, seed=seed)
                sets = self.collector.means(key)
        finally:
            self.collector = None
        self.maps[key] = Moments(key, seed, sets)
        return self.maps[key]

    def lookup(self, scene: mi.Scene, width: int, m: int) -> list[tuple[mi.Color3f, mi.Color3f]]:
        found = self.maps.get(crop_key(scene))
        if found is None:
            raise SettingsError(
                f"bad value {m} for 'expansion_pass' here: its pre-pass runs in styletrace's "
                "passes (styletrace.render, api.passes, the command line), not in a bare "
                "mi.render; render through them or use expansion_pass=0"
            )
        return found.lookup(width)


__all__ = ["Expansion", "Moments", "Collector", "moments", "lane_pixels", "crop_key"]
