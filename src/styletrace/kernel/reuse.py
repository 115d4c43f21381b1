"""Sample reuse at the first stylized vertex (`reuse=pixels`): neighbouring camera samples pool
their children (Tong and Hachisuka's path filtering, with the image as the neighbour grid).

A camera sample's pool P(v) is v and its accepted neighbours among K of the (2r+1)^2 pixel window;
g sees L_e(v) + direct + indirect over the pool's children, the BSDF samples weighted by
multi-sample MIS (`reuse_mis`: balance or pairwise). With reuse_deep=world the second level pools
too, in world space; an adaptive count n0:n_max adds a refinement round. One layer per module,
bottom up: reuse_scope, reuse_children, reuse_pool, reuse_world (world_grid), reuse_refine,
reuse_batch, reuse_loop (the pass loop, `render_reuse`).
Design: docs/design/sample_reuse.md.
"""
from styletrace.kernel import reuse_pool as pool
from styletrace.kernel.reuse_loop import render_reuse
from styletrace.kernel.reuse_pool import pool_pixels, window

__all__ = ["pool", "pool_pixels", "render_reuse", "window"]
