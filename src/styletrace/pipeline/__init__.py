"""The one render pipeline: describe a render (`job.Job`), resolve it once (`resolve`), run it
(`runner`).

Modules: `job` (the frozen description), `terms` (how the caller names its settings),
`denoising` (the denoising asked for, and the method a render gets), `budget` (samples split into
camera samples x children), `carried` (what a scene's Mitsuba integrator shares with `stylized`),
`resolve` (load, merge, choose the denoising, split once, pin `auto` values), `passes` (the pass
loop), `execute` (the passes in process or on Ray), `runner` (one run: checks, passes, stops,
writes), `signals` (Ctrl-C, SIGTERM, the progress bar), `sizing` (camera samples per pass), `ray_*`
(rendering on Ray), `orbit` (a turntable's cameras; the frames themselves: `styletrace.animation`).

Importing this package needs the backend chosen (`styletrace.init()`): its modules import Mitsuba.
Design: docs/design/render_pipeline.md.
"""
