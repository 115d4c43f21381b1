"""The one render pipeline: describe a render (`job.Job`), resolve it once (`resolve`), run
it (`runner`).

- `job`: the frozen description every front end builds (scene source, defines, size, given settings,
  seed, spp, pass split).
- `carried`: the max_depth, rr_depth and hide_emitters a scene's own Mitsuba integrator shares
  with `stylized`.
- `resolve`: load, merge the scene's own integrator settings, pin the `auto` values.
- `passes`: the pass loop (tiles, seeds, the float32 sum, memory checks).
- `execute`: the executors, the passes in process or as Ray tasks; `render_pipeline`, which
  `styletrace.render` is.
- `runner`: one run of a resolved job by an executor and a finisher: checks, passes, stops, writes.
- `signals`: Ctrl-C and SIGTERM during a run that writes files, its progress bar and
  one-line messages.
- `sizing`: camera samples per pass for the backend and device.
- `ray_*`: rendering on Ray (`ray_run` the driver, `ray_plan` the units, `ray_tasks` what workers
  run, `ray_describe` scenes that travel, `ray_checkpoint`, `ray_cluster`); `frames` and `orbit`:
  sequences of frames, each a run of the runner.

Importing this package needs the backend chosen (`styletrace.init()`): its modules import Mitsuba.
"""
