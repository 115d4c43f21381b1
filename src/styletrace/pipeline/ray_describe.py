"""Scene descriptions that travel to Ray workers, and loading them there (cached per
worker process).

    spec = SceneSpec.of("cornell-box", width=256, height=256)   # or an XML path, or a scene dict
    scene, integrator = load_on_worker(spec, values, variant)    # in a worker, cached

An `mi.Scene` cannot be pickled, so a worker receives what `api.load_scene` takes: a built-in name,
an XML path or a scene dict (its Mitsuba scalar values encoded as class name and numbers), the size
and the defines. A worker keeps the last CACHE_SIZE scenes and integrators it loaded (`CACHE`), so a
render's later passes on it load nothing. Design: docs/design/ray_rendering.md.
"""
from __future__ import annotations

import hashlib
import os
import pickle
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

from styletrace.errors import UsageError

#: Scenes (with their integrators) a worker process keeps loaded; frames of an XML list go through
#: it in turn.
CACHE_SIZE = 2
CACHE: "OrderedDict[bytes, Any]" = OrderedDict()

_TAG = "__styletrace_mitsuba_value__"


def _encode(value: Any, where: str) -> Any:
    """A scene dict with its Mitsuba scalar values as (tag, class name, nested lists)."""
    if isinstance(value, dict):
        return {k: _encode(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_encode(v, where) for v in value)
    module = type(value).__module__ or ""
    if module.startswith(("mitsuba", "drjit")):
        import numpy as np
        name = type(value).__name__
        if name.startswith("ScalarAffineTransform") or name.startswith("ScalarTransform"):
            return (_TAG, "ScalarTransform4f", np.asarray(value.matrix, dtype=np.float64).tolist())
        if name.startswith("Scalar") and hasattr(value, "__len__"):
            return (_TAG, name, np.asarray(value, dtype=np.float64).tolist())
        raise UsageError(
            f"cannot send the scene dict to Ray workers: {where[1:]} holds a {name}; use plain "
            f"numbers, Mitsuba scalar values, or an XML file"
        )
    return value


def _decode(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _decode(v) for k, v in value.items()}
    if isinstance(value, tuple) and len(value) == 3 and value[0] == _TAG:
        import mitsuba as mi
        import numpy as np
        cls = getattr(mi, value[1])
        return cls(np.asarray(value[2])) if value[1] == "ScalarTransform4f" else cls(*value[2])
    if isinstance(value, (list, tuple)):
        return type(value)(_decode(v) for v in value)
    return value


@dataclass(frozen=True)
class SceneSpec:
    """What `api.load_scene` needs, in a picklable form."""
    scene: Any  # a built-in name, an absolute XML path, or an encoded scene dict
    width: int | None = None
    height: int | None = None
    load_kwargs: dict = field(default_factory=dict)

    @classmethod
    def of(
        cls, scene: Any, width: int | None = None, height: int | None = None, **load_kwargs: Any
    ) -> "SceneSpec":
        """The spec of a scene argument.

        Args:
            scene: a built-in name, an XML path (made absolute where the file exists), a scene
                dict or None. width, height: the film (None: the scene's).
            **load_kwargs: further arguments of the load (the defines of an XML file).

        Returns:
            The SceneSpec (a scene dict's Mitsuba scalar values encoded).

        Raises:
            UsageError: an mi.Scene, or a scene dict holding a value that cannot travel.
        """
        if scene is None or isinstance(scene, dict):
            return cls(_encode(scene, "") if scene else scene, width, height, dict(load_kwargs))
        if isinstance(scene, (str, os.PathLike)):
            name = os.fspath(scene)
            # a relative path means the driver's folder; workers of a local cluster run elsewhere
            if os.path.isfile(name):
                name = os.path.abspath(name)
            return cls(name, width, height, dict(load_kwargs))
        raise UsageError(
            f"bad scene {type(scene).__name__} for a cluster render: Ray workers cannot receive an "
            f"mi.Scene; pass a built-in name, an XML path or a scene dict"
        )

    def describe(self) -> Any:
        """A JSON-able summary for a checkpoint's manifest (dict scenes by their hash)."""
        scene = self.scene if not isinstance(self.scene, dict) else "dict:" + self.key().hex()[:16]
        return {"scene": scene, "width": self.width, "height": self.height,
                "load_kwargs": {k: repr(v) for k, v in sorted(self.load_kwargs.items())}}

    def key(self) -> bytes:
        return hashlib.sha256(
            pickle.dumps(
                (self.scene, self.width, self.height, sorted(self.load_kwargs.items())), protocol=4
            )
        ).digest()


def load_on_worker(spec: SceneSpec, values: dict, variant: str):
    """(scene, integrator) for a worker, cached by the scene and the integrator's values: after
    `init(variant)`, the pipeline's `resolve` with the driver's values, so that every worker
    pins the `auto` values the driver pinned.

    Args:
        spec: the scene. values: the driver's integrator values. variant: Mitsuba's variant.

    Returns:
        (the mi.Scene, its `stylized` integrator).

    Raises:
        UsageError: load arguments other than `defines`.
    """
    from styletrace.scene import plugins as runtime
    runtime.init(variant)
    key = spec.key() + hashlib.sha256(repr(sorted(values.items())).encode()).digest()
    if key in CACHE:
        CACHE.move_to_end(key)
        return CACHE[key]
    from styletrace.kernel.integrator import StylizedIntegrator
    from styletrace.pipeline.job import Job
    from styletrace.pipeline.resolve import resolve
    unknown = sorted(set(spec.load_kwargs) - {"defines", "sampler"})
    if unknown:
        raise UsageError(
            f"bad scene arguments {', '.join(unknown)} for a cluster render: a scene takes defines "
            "and a sampler only"
        )
    scene = _decode(spec.scene) if isinstance(spec.scene, dict) else spec.scene
    # the render pipeline's resolve, with the driver's resolved values as the integrator: the same
    # load, and scene-relative 'auto' values pinned on the whole scene before any tile's crop (the
    # pilot is deterministic: fixed seed, our path kernel), so every worker pins what the driver did
    job = Job(
        scene=scene,
        width=spec.width,
        height=spec.height,
        defines=dict(spec.load_kwargs.get("defines") or {}),
        sampler=spec.load_kwargs.get("sampler"),
        integrator=StylizedIntegrator.from_values(values),
        lanes_per_pass=1,
    )
    resolved = resolve(job)
    loaded = (resolved.scene, resolved.integrator)
    CACHE[key] = loaded
    while len(CACHE) > CACHE_SIZE:
        CACHE.popitem(last=False)
    return loaded


__all__ = ["SceneSpec", "load_on_worker", "CACHE", "CACHE_SIZE"]
