"""Look development: record an expectation buffer once, restyle it in milliseconds, fit θ to a
target.

    buffer.py   the buffer: what each camera sample stores, the file format (.npz + JSON header)
    record.py   `render_buffer`: a render that also records the buffer (a recording `stylized`
    integrator)
    sequence.py the children and uniforms an unbiased estimator consumed: recorded per camera
    sample, replayed restyle.py  `restyle`: g_θ over the stored samples on the active Dr.Jit
    backend, accumulated per pixel
    fit.py      `fit`: θ that make the restyled image match a target, by gradient descent with
    Dr.Jit's AD
    commands.py the `restyle` and `fit` subcommands and `render --buffer`

See docs/lookdev.md. Importing this package loads neither Dr.Jit nor Mitsuba; its modules do.
"""
