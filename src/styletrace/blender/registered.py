"""Importing this module chooses the backend and registers styletrace's Mitsuba plugins
(`styletrace.init`). The add-on's property module imports it before the style and estimator
registries: registered in that order, the kernels F12 and the viewport trace are the same from one
render to the next and come from Dr.Jit's kernel cache (tests/blender/test_viewport.py times it).
"""
from styletrace import init

#: the active Mitsuba variant
VARIANT = init()
