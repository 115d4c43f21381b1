"""Render Animation with the styletrace engine: the seed of a frame, and how a cancel ends the
sequence.

Blender owns the animation loop (frame range, output paths, file formats): it sets each frame,
evaluates the depsgraph and calls the engine's `render`, then writes the frame. The engine renders
every frame, and F12 too, with `frame_seed`, so the noise changes from frame to frame and an F12 of
frame f gives the file Render Animation writes for f. A cancelled frame ends the sequence
(`stop_message`): docs/blender.md, Animation.
"""
from __future__ import annotations

from typing import Any

from styletrace.blender.overridden import Overridden
from styletrace.denoise.temporal import FrameView, History

#: seeds are 32-bit (`scene.arguments.SEED_MAX`)
SEEDS = 1 << 32


def frame_seed(seed: int, frame: int) -> int:
    """The seed a render of `frame` uses: `seed + frame - 1` modulo 2^32 (frame 1 keeps `seed`).

    Args:
        seed: the Seed render setting (>= 0).
        frame: Blender's frame number (any integer; Blender allows frames below 1).
    Returns:
        The seed in [0, 2^32).
    """
    return (int(seed) + int(frame) - 1) % SEEDS


def at_frame(settings: Any, frame: int) -> Overridden:
    """`settings` with the seed of `frame` (`frame_seed`); everything else is the settings' own.

    Args:
        settings: the scene's styletrace render settings. frame: Blender's frame number.
    Returns:
        An `Overridden` view of `settings`.
    """
    return Overridden(settings, seed=frame_seed(settings.seed, frame))


#: Render Animation's history of denoised estimates (`denoise.temporal`): one animation renders
#: at a time in a Blender process
HISTORY = History()
#: the data passes each frame traces for it: where its pixels' surfaces were, and what they are
REUSE_PASSES = ("depth", "normal", "vector")


def settings_values(owner: Any, skip: tuple[str, ...] = ("rna_type", "seed")) -> dict:
    """Every value of a settings block, its nested blocks (the style's parameters) included, but
    those of `skip`.

    Args:
        owner: Blender settings (a PropertyGroup, or an `Overridden` view of one).
        skip: property names left out (the seed: each frame has its own).

    Returns:
        {name: value}, lists as tuples and nested blocks as dicts.
    """
    out: dict = {}
    for prop in owner.bl_rna.properties:
        name = prop.identifier
        if name in skip or prop.type == "COLLECTION":
            continue
        value = getattr(owner, name)
        if prop.type == "POINTER":
            value = None if value is None else settings_values(value, skip)
        elif not isinstance(value, str) and hasattr(value, "__len__"):
            value = tuple(value)
        out[name] = value
    return out


def frame_history(settings: Any, passes: dict, first: bool) -> History:
    """Start HISTORY at a frame of Render Animation: the history of the frames before, carried
    to where this frame sees their surfaces (its Depth, Normal and Vector, REUSE_PASSES: a surface
    uncovered, or seen from outside the last image, starts again), kept while every setting but
    the seed stays (another setting starts it again, and that frame renders as without it).
    Changes the settings do not show (a light, a material) start their pixels again by the
    history's own test. Only denoised renders blend with it (docs/temporal.md).

    Args:
        settings: the frame's render settings. passes: its data passes of REUSE_PASSES
            (`f12.data_passes`, with the frames around).
        first: the animation's first frame: an earlier animation's history is forgotten.

    Returns:
        HISTORY.
    """
    if first:
        HISTORY.start(None)
    view = FrameView.from_passes(passes["depth"], passes["normal"], passes["vector"])
    HISTORY.start(settings_values(settings), view)  # compared by value
    return HISTORY


def stop_message(frame: int, spp_done: int, spp_total: int) -> str:
    """The error line that ends Render Animation after a cancel during `frame`.

    An error report is the one way a Python engine stops Blender's animation loop
    (docs/design/blender_frames_previews.md).

    Args:
        frame: the cancelled frame. spp_done, spp_total: its finished and asked camera samples per
        pixel.
    Returns:
        One line for Blender's report.
    """
    return (
        f"styletrace: cancelled during frame {frame} after {spp_done} of {spp_total} spp: "
        f"Render Animation stops here; this frame is not written (its finished passes are in "
        f"the Render Result), the frames before it are"
    )
