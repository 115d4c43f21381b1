"""Rendering on Ray: passes and frames as tasks on a local instance or a cluster, checkpoints, resume.

    img = styletrace.render("cornell-box", style="cel", spp=256, cluster="local")   # or "HOST:6379"
    styletrace render --ray [ADDRESS] [--resume] [--frames N --orbit DEGREES] ...

- `describe`: scene descriptions that travel to workers (an mi.Scene does not pickle); per-worker cache.
- `plan`: the render as (tile, pass) units, exactly the launches of `api.passes`; their merge in order.
- `tasks`: what workers run (one unit, one frame), with Dr.Jit's threads set to the task's CPUs.
- `cluster`: joining Ray (local or by address).
- `checkpoint`: the running sum as an EXR plus a JSON manifest, atomically, for `--resume`.
- `run`: the driver of one image; `render`, the API's entry (`styletrace.render`).
- `orbit`, `frames`: turntables and lists of scenes as numbered images, a frame per task.
- `command`: the command line's hand-off.

Importing this package does not import Ray; the driver imports it when a render starts.
"""
