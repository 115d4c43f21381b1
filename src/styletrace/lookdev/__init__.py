"""Look development: record an expectation buffer once, restyle it in milliseconds, fit θ.

    buffer.py       what each camera sample stores; the file format (.npz + JSON header)
    record.py       `render_buffer`: a render that also records the buffer (a recording `stylized`)
    sequence.py     the children and uniforms an unbiased estimator consumed: recorded, replayed
    restyle.py      `restyle`: g_θ over the stored samples on the active backend, per pixel
    film_filter.py  the film's reconstruction filter: where each sample fell, and its splat
    fit.py          `fit`: θ that make the restyled image match a target (Dr.Jit's AD, descent)

The `restyle` and `fit` subcommands and `render --buffer` are `frontends.lookdev_commands`'s.
See docs/lookdev.md. Importing this package loads neither Dr.Jit nor Mitsuba; its modules do.
"""
