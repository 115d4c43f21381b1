"""From Blender's render settings to styletrace's pipeline: the scene, the integrator, the run of
F12.

The engine (F12), the restyle operator and the XML export all go through here, so that they agree on
the scene, the style and the pass split: `styletrace render FILE.xml --seed K --pass-spp N` renders
the image F12 renders with seed K and N camera samples per pass. F12 is a pipeline run (`run_f12`):
a Job of the exported scene, the settings' integrator and their Samples (split into camera samples x
children by the pipeline's rule, `pipeline.budget`), resolved (auto values pinned), with the
finisher of its Denoise and Record buffer settings (`denoise.finishers.plan`: plain, expectation or
image denoising, the recorded buffer).
"""
from __future__ import annotations

from typing import Callable, Iterator

import numpy as np

from styletrace.blender import build, exporter
from styletrace.blender.properties import settings_integrator_values
from styletrace.config.line_types import without_colours
from styletrace.frontends import api

LINE_MASK = "LineMask"
#: the image before denoising, beside the denoised Combined (as Cycles' "Noisy Image")
NOISY = "Noisy"
AOV_PASSES = {"variance": ("Variance", 3, "RGB"), "bias": ("Bias", 1, "X"),
              "children": ("Children", 1, "X")}
#: the data passes (`kernel.data_passes`) as Cycles 5.0 declares them: Blender's name, channels,
#: channel ids, pass type, and the view layer's property that asks for it (a dotted path: Cycles'
#: own add-on's settings of the view layer)
DATA_PASSES = {"depth": ("Depth", 1, "Z", "VALUE", "use_pass_z"),
               "normal": ("Normal", 3, "XYZ", "VECTOR", "use_pass_normal"),
               "vector": ("Vector", 4, "XYZW", "VECTOR", "use_pass_vector"),
               "position": ("Position", 3, "XYZ", "VECTOR", "use_pass_position"),
               "uv": ("UV", 3, "UVA", "VECTOR", "use_pass_uv"),
               "mist": ("Mist", 1, "Z", "VALUE", "use_pass_mist"),
               "object_index": ("Object Index", 1, "X", "VALUE", "use_pass_object_index"),
               "material_index": ("Material Index", 1, "X", "VALUE", "use_pass_material_index"),
               # Cycles' Denoising Data switch: it also adds Denoising Normal and Depth, which
               # styletrace does not write
               "albedo": ("Denoising Albedo", 3, "RGB", "COLOR", "cycles.denoising_store_passes"),
               "emission": ("Emission", 3, "RGB", "COLOR", "use_pass_emit")}
#: the Cryptomatte passes (`kernel.data_passes`' crypto_object and crypto_material): Cycles' type
#: name, its passes '<type>00', '<type>01', ... (RGBA, two ranks each), and the view layer's switch
CRYPTO_PASSES = {"crypto_object": ("CryptoObject", "use_pass_cryptomatte_object"),
                 "crypto_material": ("CryptoMaterial", "use_pass_cryptomatte_material")}


def switches() -> list[tuple[str, str]]:
    """Every pass the view layer can ask for and its switch, in the order they are written.

    Returns:
        [(key, the switch's path)]: `DATA_PASSES`' then `CRYPTO_PASSES`'.
    """
    return ([(key, v[-1]) for key, v in DATA_PASSES.items()]
            + [(key, v[-1]) for key, v in CRYPTO_PASSES.items()])


def render_passes(key: str) -> tuple[tuple[str, int, str, str], ...]:
    """The render passes of a data pass, as Cycles 5.0 declares them.

    Args:
        key: a key of `DATA_PASSES` or `CRYPTO_PASSES`.

    Returns:
        ((Blender's pass name, channels, channel ids, pass type), ...): one for a data pass, one
        RGBA layer per two ranks of a Cryptomatte pass ('CryptoObject00' ...).
    """
    if key in CRYPTO_PASSES:
        from styletrace.kernel.crypto_ranks import LEVELS
        kind = CRYPTO_PASSES[key][0]
        return tuple((f"{kind}{k:02d}", 4, "RGBA", "COLOR") for k in range(LEVELS // 2))
    name, channels, ids, kind, _ = DATA_PASSES[key]
    return ((name, channels, ids, kind),)


def pass_values(key: str, values: np.ndarray) -> list[tuple[str, np.ndarray, int]]:
    """A data pass's values cut into its render passes (`render_passes`).

    Args:
        key: the pass's key. values: its H x W (x C) array (`kernel.data_passes`).

    Returns:
        [(Blender's pass name, H x W (x channels) values, channels)].
    """
    passes = render_passes(key)
    if len(passes) == 1:
        return [(passes[0][0], values, passes[0][1])]
    return [(name, values[..., 4 * k:4 * k + 4], 4) for k, (name, *_) in enumerate(passes)]


def stamp_fields(view_layer_name: str, manifests: dict[str, dict[str, str]]) -> dict[str, str]:
    """The render result's metadata of the Cryptomatte passes, as Cycles writes them: the
    standard's keys of the type '<view layer>.<type>' (the name the compositor's Cryptomatte node
    looks for).

    Args:
        view_layer_name: the view layer's name. manifests: {type name: manifest}
            (`kernel.data_passes.MANIFEST`'s entry).

    Returns:
        {'cryptomatte/<key>/name' ...: value} (`cryptomatte.exr_metadata`).
    """
    from styletrace.cryptomatte import exr_metadata
    return exr_metadata({f"{view_layer_name}.{kind}": names for kind, names in manifests.items()})


def switch(view_layer, prop: str) -> tuple[object, str] | None:
    """The owner and the name of a data pass's switch (`DATA_PASSES`' last field).

    Args:
        view_layer: the `bpy.types.ViewLayer`. prop: the property's path ('use_pass_z',
            'cycles.denoising_store_passes').

    Returns:
        (owner, property name), or None where the owner is missing (Cycles' add-on is off).
    """
    *path, name = prop.split(".")
    owner = view_layer
    for part in path:
        owner = getattr(owner, part, None)
        if owner is None:
            return None
    return owner, name


def data_passes_of(view_layer) -> tuple[str, ...]:
    """The data passes a view layer asks for (its Data, Light and Cryptomatte pass switches,
    Cycles' own).

    Args:
        view_layer: the `bpy.types.ViewLayer`.

    Returns:
        Their keys in `switches` order (empty: none, and nothing is traced for them).
    """
    found = ((key, switch(view_layer, prop)) for key, prop in switches())
    return tuple(key for key, where in found if where is not None and getattr(*where))


def mist_of(scene):
    """The Mist pass's settings of a scene: its World's mist (Blender's defaults without a World).

    Args:
        scene: the `bpy.types.Scene`.

    Returns:
        The `kernel.mist.Mist`.
    """
    from styletrace.kernel.mist import Mist
    if scene.world is None:
        return Mist()
    m = scene.world.mist_settings
    return Mist(float(m.start), float(m.depth), m.falloff.lower())


def data_passes(runner, names: tuple[str, ...], motion=None, mist=None) -> dict:
    """F12's data passes, with the run's camera samples per pixel and seed.

    Args:
        runner: F12's `pipeline.runner.Runner` (`run_f12`). names: `data_passes_of`'s keys.
        motion: the frames around (`motion.frames_around`), or None.
        mist: the Mist pass's settings (`mist_of`), or None (Blender's defaults).

    Returns:
        {key: float32 array} (`kernel.data_passes.render_data_passes`).
    """
    from styletrace.kernel.data_passes import render_data_passes
    r = runner.resolved
    return render_data_passes(r.scene, names, r.spp, r.job.seed, motion, mist=mist)


def error_passes(settings) -> bool:
    """Whether F12 adds the error AOVs: not for a recorded render (it keeps the image only), nor a
    denoised one (the variance of the noisy pixel is not the error of the denoised one:
    docs/denoise.md).

    Args:
        settings: the scene's styletrace settings (`properties.SceneSettings`).

    Returns:
        True where `aovs` is on, Record buffer off and Denoise off.
    """
    return bool(settings.aovs and not settings.record_buffer and settings.denoise == "off")


def description(depsgraph, settings, warn: Callable[[str], None] = print,
                placements: dict | None = None) -> dict:
    """The scene description of the depsgraph (`exporter.export`), its sampler's sample count the
    settings' Samples (the budget a command line render of its XML spends).

    Args:
        depsgraph: the evaluated depsgraph. settings: the scene's styletrace settings.
        warn: called with each warning line.
        placements: a dict to fill with each shape's placement (the Vector pass's), or None.

    Returns:
        The description.
    """
    return exporter.export(depsgraph, spp=settings.samples, warn=warn, placements=placements)


def scene(depsgraph, settings, warn: Callable[[str], None] = print):
    """The loaded `mi.Scene` of the depsgraph (`api.load_scene` checks it as it checks every
    scene).

    Args:
        depsgraph: the evaluated depsgraph. settings: the scene's styletrace settings.
        warn: called with each warning line of the export.

    Returns:
        The mi.Scene.
    """
    return load(description(depsgraph, settings, warn))


def load(desc: dict):
    """The loaded `mi.Scene` of a scene description (`description`).

    Args:
        desc: the description.

    Returns:
        The mi.Scene.
    """
    return api.load_scene(build.description_scene_dict(desc))


def integrator(settings, aovs: bool | None = None, **override):
    """The `stylized` integrator of the render settings.

    Args:
        settings: the scene's styletrace settings. aovs: the error AOVs (None: the settings').
        **override: property values that replace the settings' (the line mask's colours).

    Returns:
        The StylizedIntegrator.

    Raises:
        StyletraceError: a refused value (one line).
    """
    values = settings_integrator_values(settings)
    values["aovs"] = settings.aovs if aovs is None else aovs
    values.update(override)
    return api.make_integrator_from(values)


def sampling(settings, integ) -> dict:
    """The Job's counts of the settings: Samples, and Camera samples where given (0: auto).

    Args:
        settings: the scene's styletrace settings (samples, spp). integ: the render's integrator
            (its values name inner_samples where Inner samples, or an override, gives them).

    Returns:
        {"samples", "spp"}: samples None where spp and the children are both given (they set the
        cost, as the command line's --spp with --inner; Samples is greyed out then), spp None
        where 0.
    """
    spp = int(settings.spp) or None
    given = spp is not None and "inner_samples" in getattr(integ, "values", {})
    return {"samples": None if given else int(settings.samples), "spp": spp}


def denoising(settings, denoise: bool = True, history=None):
    """The render settings' denoising options (`pipeline.denoising.Denoising`).

    Args:
        settings: the scene's styletrace settings (Denoise, its quality and footprint).
        denoise: False: off, whatever Denoise says (the line mask's renders).
        history: the frames' temporal history (`animation.frame_history`), or None.

    Returns:
        The Denoising.
    """
    from styletrace.pipeline.denoising import OFF, Denoising
    if not denoise:
        return OFF
    return Denoising(settings.denoise, quality=settings.denoise_quality,
                     footprint=settings.denoise_footprint, history=history)


def job(sc, integ, settings, denoise: bool = True, grow: bool | None = None, history=None):
    """The pipeline's Job of F12: the loaded scene, the settings' integrator as it is, their
    sampling (`sampling`; the pass split of `pass_spp`, tiles of the pass loop's own size) and
    denoising, in Blender's terms (`pipeline.terms.BLENDER`: errors name the fields' labels).
    With the Owen-scrambled Sobol pattern the passes grow from `pass_spp`, doubling up to the
    pass loop's size (the image is the same whatever the split, to float rounding; one launch
    per camera sample cost 30 ms each at 128 x 128).

    Args:
        sc: the loaded scene. integ: the integrator. settings: the scene's styletrace settings.
        denoise: False: not denoised, whatever Denoise says (`denoising`).
        grow: the passes grow (`passes.PassSplit.rounds`); None: where the loaded scene's
            sampler is `owen_sobol` (`owen_sobol_sampler.sequenced`).
        history: the frames' temporal history (`denoising`), or None.

    Returns:
        The `pipeline.job.Job`.
    """
    from styletrace.kernel.owen_sobol_sampler import sequenced
    from styletrace.pipeline.job import Job
    from styletrace.pipeline.terms import BLENDER
    if grow is None:
        grow = sequenced(sc)
    return Job(scene=sc, integrator=integ, seed=settings.seed, pass_spp=settings.pass_spp,
               lanes_per_pass=api.LANES_PER_PASS, pass_growth=grow,
               denoising=denoising(settings, denoise, history), terms=BLENDER,
               **sampling(settings, integ))


def run_f12(sc, settings, aovs: bool, keep: Callable | None = None, history=None):
    """F12's run: the job's `denoise.finishers.plan` (every front end's), the Denoise setting's
    finisher.

    Args:
        sc: the loaded scene. settings: the scene's styletrace settings. aovs: the error AOVs.
        keep: called with the buffer to restyle (Record buffer), or None.
        history: the frames' temporal history (Render Animation's, `animation.frame_history`),
            or None.

    Returns:
        The `pipeline.runner.Runner` (`runner.resolved.note`: why Denoise auto could not denoise).

    Raises:
        UsageError: the refusals (one line each; Record buffer with Denoise 'image'), before
            anything renders.
    """
    from styletrace.denoise.finishers import Image, Recording, plan
    from styletrace.errors import UsageError
    runner = plan(job(sc, integrator(settings, aovs=aovs), settings, history=history), scene=sc,
                  recording=Recording(label="<blender>", keep=keep))
    if isinstance(runner.finisher, Image) and keep is not None:
        raise UsageError("Record buffer with Denoise 'image': restyles of the noisy buffer would "
                         "not be the denoised image; use Denoise 'expectation' (its buffer keeps "
                         "the denoised expectation)")
    return runner


def f12_passes(sc, integ, settings) -> Iterator[api.Progress]:
    """The plain passes of `integ` with F12's sampling, not denoised (a pipeline run, auto values
    pinned): the line mask's.

    Args:
        sc: the loaded scene. integ: the integrator. settings: the scene's styletrace settings.

    Returns:
        An iterator of `Progress`.
    """
    from styletrace.pipeline.execute import InProcess
    from styletrace.pipeline.resolve import resolve
    from styletrace.pipeline.runner import Runner
    return Runner(resolve(job(sc, integ, settings, denoise=False), scene=sc),
                  InProcess()).passes()


def line_mask(sc, settings, should_stop: Callable[[], bool] = lambda: False) -> np.ndarray | None:
    """Where lines are drawn, in [0, 1]: the image with white lines minus the image with black
    lines, with the same seed. Line decisions do not depend on the line colour, so everything but
    the lines cancels exactly; this costs a second render of the lines' settings (docs/blender.md).

    Args:
        sc: the loaded scene. settings: the scene's styletrace settings.
        should_stop: asked after each pass; True abandons the mask.

    Returns:
        The mask, H x W float, or None where stopped.
    """
    images = []
    # a line type's own colour= would not follow the override: every type takes line_color for the
    # mask
    types = ({"line_types": without_colours(settings.line_types)} if settings.line_types.strip()
             else {})
    for colour in ("0,0,0", "1,1,1"):
        prog = None
        masked = integrator(settings, aovs=False, line_color=colour, line_gradient="", **types)
        for prog in f12_passes(sc, masked, settings):
            if should_stop():
                return None
        images.append(prog.image)
    return np.clip((images[1] - images[0]).mean(axis=2), 0.0, 1.0)
