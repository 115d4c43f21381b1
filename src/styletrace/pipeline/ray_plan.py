"""A render as independent (tile, pass) units, and their sum in the single-process order.

    layout, units = plan_units(Plan(width, height, spp, seed, split))   # split: a PassSplit
    merge = Merge(width, height, spp, layout)
    merge.add(unit, rendered_tile)    # any order; summed per tile in the order of pass_loop.passes
    merge.progress()                  # a pipeline.passes.Progress: spp_done, image

The units are exactly the kernel launches of `pass_loop.passes` (its tiles, pass size and seeds),
so which worker renders a unit changes nothing; `Merge` adds each tile's passes in round order with
the same float32 operations, so the merged image is bit-identical to the single-process render of
the same seed and split. Design: docs/design/ray_rendering.md.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.pipeline import passes as pass_loop  # the pass loop whose launches these are
from styletrace.pipeline.passes import Unit


@dataclass(frozen=True)
class Plan:
    """What fixes a render's units, and so what a checkpoint must match (`ray_run.settings_of`).

    Args:
        width, height: the film's size. spp: camera samples per pixel. seed: the render's seed.
        split: the pass split (`pass_loop.PassSplit`).
    """
    width: int
    height: int
    spp: int
    seed: int = 0
    split: pass_loop.PassSplit = pass_loop.PassSplit()


def plan_units(plan: Plan) -> tuple[list[pass_loop.Tile], list[Unit]]:
    """The tiles of the film and every unit of the render, in launch order.

    Args:
        plan: the film's size, camera samples per pixel, seed and pass split.

    Returns:
        (tiles, units): round r of tile t is launch index r * tiles + t, seeded with
        `pass_loop.pass_seed(seed, index)`, of the split's round r camera samples per pixel
        (`PassSplit.rounds`, as the pass loop), continuing its tile's sequence after the rounds
        before it.
    """
    layout, rounds = plan.split.rounds(plan.width, plan.height, plan.spp)
    starts = [sum(rounds[:r]) for r in range(len(rounds))]
    units = [Unit(r * len(layout) + t, t, r, n, pass_loop.pass_seed(plan.seed, r * len(layout) + t),
                  starts[r])
             for r, n in enumerate(rounds) for t in range(len(layout))]
    return layout, units


class Merge:
    """The running float32 sum of the finished units, added per tile in round order.

    Args:
        width, height: the film's size. spp: camera samples per pixel. layout: the tiles
            (`plan_units`).
        total, rounds_done: a resumed checkpoint's sum (H x W x 3) and rounds per tile (None: none).
    """

    def __init__(self, width: int, height: int, spp: int, layout: list[pass_loop.Tile],
                 total: np.ndarray | None = None, rounds_done: list[int] | None = None):
        self.spp, self.layout = spp, layout
        self.total = np.zeros((height, width, 3), dtype=np.float32) if total is None else total
        self.rounds_done = list(rounds_done) if rounds_done is not None else [0] * len(layout)
        self.counts = np.zeros(len(layout), dtype=np.int64)
        self._pending: dict[tuple[int, int], tuple[Unit, np.ndarray]] = {}

    def restore_counts(self, units: list[Unit]) -> None:
        """Count the samples per tile of the rounds already done (after a resume).

        Args:
            units: every unit of the render (`plan_units`).
        """
        for u in units:
            if u.round < self.rounds_done[u.tile]:
                self.counts[u.tile] += u.spp

    def add(self, unit: Unit, tile_image: np.ndarray) -> int:
        """Take a unit's rendered crop window; an early one waits for its tile's earlier rounds.

        Args:
            unit: the unit rendered. tile_image: its crop window, float32 h x w x 3.

        Returns:
            How many units this call added to the sum (0 while it waits).
        """
        self._pending[(unit.tile, unit.round)] = (unit, tile_image)
        added = 0
        t = unit.tile
        while (t, self.rounds_done[t]) in self._pending:
            u, arr = self._pending.pop((t, self.rounds_done[t]))
            tile = self.layout[t]
            self.total[tile.dest] += arr[tile.keep] * np.float32(u.spp)  # as pass_loop.passes does
            self.counts[t] += u.spp
            self.rounds_done[t] += 1
            added += 1
        return added

    def progress(self) -> pass_loop.Progress:
        return pass_loop.Progress(self.spp, self.total, self.counts, self.layout)


__all__ = ["Unit", "Plan", "plan_units", "Merge"]
