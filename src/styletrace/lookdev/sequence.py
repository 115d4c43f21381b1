"""The per-camera-sample sequence of children and uniforms an estimator consumed: record, replay.

Every estimator draws from two sources, `draw(carry)` and `uniform(carry)`, fed by the lane's one
stream, so a camera sample's estimate is fixed by its sequence of calls and their results.
`Recorder` notes every call of every slot's estimator in call order (children in a shared pool,
uniforms in a slab) and sorts them per lane into seq_count, seq_kind, child and uniform; a lane that
overflows keeps its prefix. `replay` runs a slot's estimator over the stored events and marks lanes
that ask for an event not stored, or of the other kind; `restyle` refuses those. See
docs/design/expectation_buffer.md.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from styletrace.config.estimator_registry import SERIES_MAX_TERMS, make_estimator
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned

#: most children (on average over a pass) and uniforms (each) per camera sample; bounds the pass's
#: scratch (28 bytes per place) and the stored sequence (13 bytes per child, 5 per uniform)
MAX_EVENTS_PER_SAMPLE = 64
CHILD, UNIFORM = 1, 0


def budget(slots) -> int:
    """The pool entries per camera sample that a pass's recorder reserves.

    Args:
        slots: the recording's StyleSlots (closed-form styles draw nothing).

    Returns:
        Twice the expected draws of every slot's estimator (each draw may bring a uniform: Russian
        roulette) plus 4 per slot (the uniforms of the estimator's start), in
        [4, MAX_EVENTS_PER_SAMPLE].
    """
    total = 0.0
    for slot in slots:
        if slot.style.closed_form:
            continue
        est = make_estimator(slot, 0, None)
        draws = est.mean_draws
        # adaptive truncation: the pilot plus every term
        if draws is None or not math.isfinite(draws):
            draws = slot.n(0) + SERIES_MAX_TERMS
        total += 2.0 * draws + 4.0
    return int(min(MAX_EVENTS_PER_SAMPLE, max(4, math.ceil(total))))


class Recorder:
    """The kernel side of one pass: the children's pool, the uniforms' slab and the per-lane
    counters (threaded through the estimator's carry).

    Args:
        width: the pass's lanes (camera samples).
        per_sample: places per lane: the pool holds width * per_sample children in all, the slab
            per_sample uniforms per lane (`budget`).
    """

    def __init__(self, width: int, per_sample: int):
        self.width, self.per_sample = width, per_sample
        # children: one pool for the pass, places handed out by dr.scatter_inc (a loop body draws
        # at one place, and Dr.Jit allows one scatter_inc on a counter per symbolic region)
        self.capacity = max(1, width * per_sample)
        self.counter = dr.zeros(mi.UInt32, 1)
        self.lane_of = dr.zeros(mi.UInt32, self.capacity)
        self.pos = dr.zeros(mi.UInt32, self.capacity)
        self.value = dr.zeros(mi.Color3f, self.capacity)
        # uniforms: `per_sample` places per lane (an estimator may ask for them at several places
        # per body)
        self.u_pos = dr.zeros(mi.UInt32, self.capacity)
        self.u_value = dr.zeros(mi.Float, self.capacity)
        self.lanes = dr.arange(mi.UInt32, width)
        self.count = dr.zeros(mi.UInt32, width)    # events so far per lane, all slots together
        self.ucount = dr.zeros(mi.UInt32, width)   # uniforms so far per lane

    def child(self, count: mi.UInt32, x) -> mi.UInt32:
        """Note one child of each drawing lane (the symbolic loop masks the others) in the pool.

        Args:
            count: mi.UInt32, the lane's events so far (the child's position in its sequence).
            x: the child's radiance (mi.Color3f); dropped where the pool is full.

        Returns:
            count + 1.
        """
        idx = dr.scatter_inc(self.counter, mi.UInt32(0))
        ok = idx < self.capacity
        dr.scatter(self.lane_of, self.lanes, idx, ok)
        dr.scatter(self.pos, count, idx, ok)
        dr.scatter(self.value, mi.Color3f(x), idx, ok)
        return count + 1

    def uniform(self, count: mi.UInt32, ucount: mi.UInt32, u) -> tuple[mi.UInt32, mi.UInt32]:
        """Note one uniform number of each drawing lane in the slab.

        Args:
            count, ucount: mi.UInt32, the lane's events and uniforms so far.
            u: mi.Float, the number drawn; dropped past the lane's per_sample places.

        Returns:
            (count + 1, ucount + 1).
        """
        ok = ucount < self.per_sample
        idx = self.lanes * self.per_sample + ucount
        dr.scatter(self.u_pos, count, idx, ok)
        dr.scatter(self.u_value, mi.Float(u), idx, ok)
        return count + 1, ucount + 1

    def collect(self) -> dict[str, np.ndarray]:
        """The pass's sequences in the buffer's compact form (call after the pass's kernel ran)."""
        dr.eval(self.counter, self.lane_of, self.pos, self.value, self.u_pos, self.u_value,
                self.ucount)
        used = min(int(self.counter[0]), self.capacity)
        c_lane = np.asarray(self.lane_of, dtype=np.int64)[:used]
        c_pos = np.asarray(self.pos, dtype=np.int64)[:used]
        c_val = np.stack([np.asarray(self.value[i], dtype=np.float32)[:used] for i in range(3)])
        stored = np.minimum(np.asarray(self.ucount, dtype=np.int64), self.per_sample)
        # (width, per_sample): the slab's places that hold a uniform
        slab = np.arange(self.per_sample, dtype=np.int64)[None, :] < stored[:, None]
        u_lane = np.nonzero(slab)[0]
        u_pos = np.asarray(self.u_pos, dtype=np.int64).reshape(self.width, self.per_sample)[slab]
        u_val = np.asarray(self.u_value,
                           dtype=np.float32).reshape(self.width, self.per_sample)[slab]
        lane = np.concatenate([c_lane, u_lane])
        pos = np.concatenate([c_pos, u_pos])
        kind = np.concatenate([np.full(used, CHILD, np.uint8),
                               np.full(u_lane.size, UNIFORM, np.uint8)])
        value = np.concatenate([c_val, np.stack([u_val, u_val * 0, u_val * 0])], axis=1)
        order = np.lexsort((pos, lane))
        lane, pos, kind, value = lane[order], pos[order], kind[order], value[:, order]
        first = np.searchsorted(lane, np.arange(self.width, dtype=np.int64))
        # each lane's prefix that was stored
        keep = pos == np.arange(lane.size, dtype=np.int64) - first[lane]
        lane, kind, value = lane[keep], kind[keep], value[:, keep]
        return {
            "seq_count": np.bincount(lane, minlength=self.width).astype(np.uint32),
            "seq_kind": kind,
            "child": np.ascontiguousarray(value[:, kind == CHILD]),
            "uniform": np.ascontiguousarray(value[0, kind == UNIFORM]),
        }


def offsets(arrays: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each camera sample's events, children and uniforms start in the flat arrays.

    Args:
        arrays: a sequence buffer's arrays (seq_count, seq_kind).

    Returns:
        (first event, first child, first uniform): int64 arrays of N + 1 entries, the last one
        each total.
    """
    ev = np.concatenate([[0], np.cumsum(arrays["seq_count"], dtype=np.int64)])
    ck = np.concatenate([[0], np.cumsum(arrays["seq_kind"], dtype=np.int64)])
    return ev, ck[ev], ev - ck[ev]


def device_arrays(arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    """The sequence on the Dr.Jit backend, for `replay`.

    Args:
        arrays: a sequence buffer's arrays (seq_count, seq_kind, child, uniform).

    Returns:
        ev_start, ev_end, ch_start, un_start (mi.UInt32 per sample), kind (mi.UInt32 per event),
        child (mi.Color3f), uniform (mi.Float); flat arrays padded by one entry so that gathers
        never see an empty array (the pad is never read: gathers are masked by each lane's range).
    """
    ev, ch, un = offsets(arrays)
    pad = lambda a: np.concatenate([a, np.zeros(a.shape[:-1] + (1,), a.dtype)], axis=-1)  # noqa: E731
    child = pad(arrays["child"])
    return {
        "ev_start": mi.UInt32(aligned(ev[:-1], np.uint32)),
        "ev_end": mi.UInt32(aligned(ev[1:], np.uint32)),
        "ch_start": mi.UInt32(aligned(ch[:-1], np.uint32)),
        "un_start": mi.UInt32(aligned(un[:-1], np.uint32)),
        "kind": mi.UInt32(aligned(pad(arrays["seq_kind"]), np.uint32)),
        "child": mi.Color3f(*(mi.Float(aligned(child[i])) for i in range(3))),
        "uniform": mi.Float(aligned(pad(arrays["uniform"]))),
    }


def replay(d: dict[str, Any], slot_of: mi.Int32, slots, v) -> tuple[mi.Color3f, mi.Bool]:
    """Run each slot's estimator over the stored sequences instead of a stream.

    Args:
        d: the sequence's Dr.Jit arrays (`device_arrays`).
        slot_of: mi.Int32, each lane's slot index (-1: no stylized vertex).
        slots: the StyleSlots to evaluate; v: the lanes' Vertex.

    Returns:
        (mi.Color3f value per lane, mi.Bool per lane: its estimator asked for an event that is not
        stored, or of the other kind).
    """

    def take(carry, kind):
        e, c, u, bad = carry
        ok = (e < d["ev_end"]) & (dr.gather(mi.UInt32, d["kind"], e, e < d["ev_end"]) == kind)
        return ok, (e + 1, c + (1 if kind == CHILD else 0), u + (1 if kind == UNIFORM else 0),
                    bad | ~ok)

    total, bad_final = mi.Color3f(0.0), mi.Bool(False)
    carry = (mi.UInt32(d["ev_start"]), mi.UInt32(0), mi.UInt32(0),
             dr.zeros(mi.Bool, dr.width(slot_of)))
    for i, slot in enumerate(slots):
        style = slot.style
        here = slot_of == i
        if style.closed_form:
            total = dr.select(here, style.apply(mi.Color3f(0.0), v), total)
            continue

        def draw(carry, *_):
            ok, new = take(carry, CHILD)
            x = dr.gather(mi.Color3f, d["child"], d["ch_start"] + carry[1], ok)
            if style.per_sample:
                x = style.apply(x, v)
            return x, new

        def uniform(carry):
            ok, new = take(carry, UNIFORM)
            return dr.gather(mi.Float, d["uniform"], d["un_start"] + carry[2], ok), new

        value, carry = make_estimator(slot, 0, v).run(draw, carry, uniform, here, like=mi.Color3f)
        total = dr.select(here, value, total)
        bad_final = dr.select(here, carry[3], bad_final)
    return total, bad_final


def seq_bytes(arrays: dict[str, np.ndarray]) -> int:
    """The bytes of a buffer's sequence arrays.

    Args:
        arrays: a sequence buffer's arrays.

    Returns:
        The bytes of seq_count, seq_kind, child and uniform together.
    """
    return sum(arrays[k].nbytes for k in ("seq_count", "seq_kind", "child", "uniform"))


__all__ = ["Recorder", "replay", "budget", "offsets", "device_arrays", "MAX_EVENTS_PER_SAMPLE",
           "seq_bytes"]
