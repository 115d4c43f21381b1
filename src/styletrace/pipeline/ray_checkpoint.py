"""Checkpoints of a render on Ray: the sum of the finished passes as an EXR, and a JSON manifest.

    ck = Checkpoint("out.png", settings)   # OUT.checkpoint.json + OUT.checkpoint-<generation>.exr
    ck.save(total, rounds_done)            # atomically; the previous generation's EXR removed
    total, rounds_done = ck.load()         # for --resume; UsageError if the settings differ
    ck.remove()                            # once the render is written

The EXR holds the float32 running *sum* of the finished passes, so a resumed render is
bit-identical to an undisturbed one; the manifest records the render's settings and, per tile, the
passes summed (`rounds_done`). A new generation's EXR is written before the manifest that names it.
Design: docs/design/ray_rendering.md.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from styletrace.errors import UsageError
from styletrace.images import write_bytes_atomically, write_image

VERSION = 1


def _plain_settings(value: Any) -> Any:
    """Settings as JSON reads them back (tuples as lists, other objects by repr), for comparison."""
    return json.loads(json.dumps(value, sort_keys=True, default=repr))


@dataclass(frozen=True)
class Checkpoints:
    """Whether and how often a render on Ray checkpoints its finished passes.

    Args:
        output: the image's path, beside which the checkpoint is kept (None: no checkpoint).
        resume: continue from the checkpoint. every: seconds between checkpoints.
    """
    output: str | None = None
    resume: bool = False
    every: float = 10.0


class Checkpoint:
    """The checkpoint of one render's output (see the module doc).

    Args:
        output: the render's output path, OUT.
        settings: the render's settings (`ray_run.settings_of`), compared as JSON reads them back.
    """
    def __init__(self, output: str, settings: dict[str, Any]):
        self.output = output
        self.manifest = output + ".checkpoint.json"
        self.settings = _plain_settings(settings)
        self.generation = 0
        self.saved_rounds: list[int] | None = None

    def _image(self, generation: int) -> str:
        return f"{self.output}.checkpoint-{generation}.exr"

    def exists(self) -> bool:
        return os.path.isfile(self.manifest)

    def save(self, total: np.ndarray, rounds_done: list[int]) -> None:
        """Write a new generation (its EXR, then the manifest naming it); drop the previous EXR.

        Args:
            total: the float32 running sum of the finished passes, H x W x 3.
            rounds_done: per tile, how many of its passes the sum holds; nothing is written when
                they are those of the last save.
        """
        if self.saved_rounds == list(rounds_done):
            return  # nothing new since the last one
        generation = self.generation + 1
        write_image(total, self._image(generation))
        body = {
            "version": VERSION,
            "settings": self.settings,
            "rounds_done": [int(r) for r in rounds_done],
            "image": os.path.basename(self._image(generation)),
            "generation": generation,
        }
        write_bytes_atomically(json.dumps(body, indent=1, sort_keys=True).encode(), self.manifest)
        old, self.generation, self.saved_rounds = self.generation, generation, list(rounds_done)
        self._drop(old)

    def _drop(self, generation: int) -> None:
        try:
            os.remove(self._image(generation))
        except FileNotFoundError:
            pass

    def load(self) -> tuple[np.ndarray, list[int]]:
        """The saved sum and rounds per tile; refuses (one line) a checkpoint of other settings."""
        if not self.exists():
            raise UsageError(
                f"cannot resume {self.output!r}: no checkpoint {self.manifest!r} (it is written "
                "while a --ray render runs and removed when it finishes)"
            )
        try:
            with open(self.manifest) as f:
                body = json.load(f)
            saved = body["settings"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise UsageError(
                f"cannot resume {self.output!r}: unreadable checkpoint {self.manifest!r} ({exc})"
            ) from None
        if saved != self.settings:
            diff = sorted(
                k for k in set(saved) | set(self.settings) if saved.get(k) != self.settings.get(k)
            )
            k = diff[0]
            raise UsageError(
                f"cannot resume {self.output!r}: its checkpoint was made with other settings ({k} "
                f"{json.dumps(saved.get(k))}, now {json.dumps(self.settings.get(k))}); drop "
                "--resume to start over"
            )
        import mitsuba as mi
        path = os.path.join(os.path.dirname(os.path.abspath(self.manifest)), body["image"])
        try:
            total = np.array(mi.Bitmap(path), dtype=np.float32)[..., :3].copy()
        except Exception as exc:
            raise UsageError(
                f"cannot resume {self.output!r}: cannot read {path!r} ({exc})"
            ) from None
        self.generation, self.saved_rounds = int(body["generation"]), list(body["rounds_done"])
        return total, list(body["rounds_done"])

    def remove(self) -> None:
        """After the final image is written: the manifest first, so no manifest names a
        missing EXR."""
        if self.exists():
            os.remove(self.manifest)
        self._drop(self.generation)


__all__ = ["Checkpoints", "Checkpoint", "VERSION"]
