"""Sample reuse at the first stylized vertex (`reuse=pixels`): neighbouring camera samples pool
their children.

Reference
    Tong and Hachisuka, "Practical Stylized Nonlinear Monte Carlo Rendering", SIGGRAPH 2025: path
    filtering, here restricted to the first stylized vertex, with the image as the neighbour grid (a
    pixel window, no hash grid). Veach and Guibas, "Optimally Combining Sampling Techniques for
    Monte Carlo Rendering", SIGGRAPH 1995: the multi-sample balance heuristic that gives the pooled
    samples their weights. Bitterli, "Correlations and Reuse for Fast and Accurate Physically Based
    Light Transport" (PhD thesis, 2021), and Lin et al., "Generalized Resampled Importance
    Sampling", SIGGRAPH 2022: pairwise MIS.

Every camera sample i traces its ray to the first hit v_i and draws m children there (m = its style
slot's inner_samples), each split into one next-event sample (direction wl, E = L_e vis / p_light)
and one BSDF sample (direction wb, density p_i(wb), and the radiance Li arriving along it from the
ordinary path kernel, less the first emission it meets: next-event estimation has that). The pool
P(v) is v and its accepted neighbours among K drawn from the (2r+1)^2 pixel window (same sample
index of the pass): same style target, same BSDF object, shading normals with n.n' > NORMAL_MIN and
camera distances within DEPTH_TOL. Then, with v's own BSDF f_v (cosine included),

    direct(v)   = 1/(|P| m) sum_{k in P} sum_j f_v(wl_kj) E_kj      (neighbours' visibility reused)
    indirect(v) = sum_{k in P} sum_j f_v(wb_kj) Li_kj w_k(wb_kj) / (m p_k(wb_kj))
    L(v) = g( L_e(v) + direct + indirect )

with multi-sample MIS weights w_k over the pool's BSDF-sampling techniques (`reuse_mis`):
- balance: w_k = p_k / sum_{k' in P} p_k', i.e. each sample divided by the mixture density of the
  whole pool; (K+1)^2 m density evaluations per camera sample;
- pairwise: each neighbour's technique weighed against v's only, n = |P| - 1:
  w_k = p_k / (n p_k + p_v) for a neighbour's sample, w_v = (1/n) sum_k p_v / (n p_k + p_v) for v's
  own; the weights still sum to one for every direction, at (2K+1) m evaluations.
Either is unbiased for the integral at v wherever the neighbours' incident radiance equals v's (a
plane under a uniform sky: exactly), whatever their normals, since v's own technique covers its
whole hemisphere. Dividing by the sampling neighbour's own density alone (weights='own') misses the
directions a neighbour cannot sample: the tests' negative control. g sees a mean of |P| m samples
instead of m, so the Jensen bias of direct application shrinks accordingly, at the price of the
geometric mismatch between neighbours (blurred shadow edges and style thresholds within the window;
docs/reuse.md measures it).

With stylize=first_n_hits (N >= 2 levels) v is the level-0 vertex and a child is `bounce.bounce`'s:
next-event samples reach delta lights only, and a BSDF sample's Li is the stylized value of the
level-1 vertex it reaches, estimated for that child alone by the ordinary tree
(`integrator.stylized(1, ...)`, its own n(1) children, recursively for N > 2) or the environment
where it escapes. The deeper levels are thus done first; level 0 then pools exactly as above. With
reuse_deep=world (N = 2 only) level 1 pools too, as in Tong and Hachisuka's path filtering: all
children of a batch are drawn at once (`world.level1`), the level-1 vertices they reach (one per
child) draw m2 children each (`children.draw`: ordinary paths beyond the last level), and each pools
with the accepted ones of K2 candidates from its jittered cell of a world-space grid (world_grid.py:
same target, BSDF and normal, within distance h), with the same weights as above; g of that pooled
value is the child's Li.

Light is split by technique, not by MIS, at pooling lanes: MIS weights computed at different
vertices would not sum to one at v. Lanes whose BSDF has a delta or null component, closed-form
styles and escaped rays use their own children only (the ordinary estimate, with MIS); a pool of v
alone is the ordinary estimate too. Neighbours are looked up within one pass of one crop window
(`api.passes` tiles images above a million pixels; a window is clipped at a tile's edge). The
children of a pass are stored (16 floats each, side by side), so a pass is split into batches of
samples per pixel of at most BATCH_CHILDREN children.

With an adaptive count n0:n_max (`refine.py`), lanes draw n0 children, pool them, and then the lanes
whose pooled mean AdaptiveDirect's rule finds too close to a style threshold (or too curved), told
the pool's C = sum_P c_k samples and their second moment, draw n_max - n0 more and recompute their
pools with every member's children: direct / C; balance with Veach's multi-sample weights with
per-member counts c_k, 1 / sum_k c_k p_k; pairwise by layers, one per child index j over the members
with c_k > j, averaged with weights |P_j| / C (`pool.py`).

The package, one layer per module, bottom up: scope.py (what a render reads: the integrator's public
per-render state, the lanes' style slots), children.py (drawing and storing children), pool.py (the
pixel window and the pooled estimate), world.py (reuse_deep=world: the second level pooled in world
space), refine.py (the refinement round of n0:n_max), batch.py (one batch: camera, first hits,
children, pools, g), loop.py (the pass loop).
"""
from styletrace.kernel import reuse_pool as pool
from styletrace.kernel.reuse_loop import render_reuse
from styletrace.kernel.reuse_pool import pool_pixels, window

__all__ = ["pool", "pool_pixels", "render_reuse", "window"]
