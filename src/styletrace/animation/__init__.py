"""Sequences of frames from the command line and on Ray: a turntable of one scene or a list of
files, rendered in chunks of consecutive frames with temporal reuse.

Modules: `frame_chunks` (what a frame needs, in a form that pickles; chunks; a chunk's run, with
its history), `frames` (the chunks in this process, numbered images, the manifest that resumes
them), `ray_frames` (each chunk one Ray streaming task, each frame written as it comes back).
They sit above the denoisers (`denoise.finishers`, `denoise.temporal`), which every frame's run
uses. Design: docs/temporal.md, docs/design/ray_rendering.md.
"""
