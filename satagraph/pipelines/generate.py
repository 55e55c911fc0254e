r"""Text-to-motion generation on any skeleton (``satagraph generate``).

A :class:`~satagraph.lightning.text_to_motion.TextToMotionModule`
checkpoint holds everything: the frozen SATA-RVQ that decodes codes onto a
skeleton, the generators, and the id of the text encoder (checked when it
is loaded). For every target skeleton:

1. the target is brought into the model's canonical frame
   (:func:`~satagraph.transforms.canonical.canonicalize`; a rig whose rest
   pose is a line is re-rested on its mean standing pose, as
   :func:`~satagraph.pipelines.inference.retarget_motion` does) and its
   static and semantic features give :math:`f_{skel}`;
2. the duration is the user's, or drawn from the length model given the
   text and the skeleton;
3. the masked transformer decodes layer-0 codes (iterative re-masking,
   classifier-free guidance that drops the text only), the residual
   transformer the other layers;
4. the autoencoder decodes the codes onto the target's frame graphs, and
   the motion goes back to the target's own rig (its rest pose, then axes,
   units, joint order and channel layout with
   :func:`~satagraph.transforms.canonical.decanonicalize`).

Every skeleton draws from a generator seeded by :obj:`seed` alone, so the
same seed gives the same motion, whatever other skeletons are asked for.
Nothing touches the network.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import List, Optional, Sequence, Tuple, Union

import numpy as np
import torch

from satagraph.ops.smoothing import gaussian_smooth
from satagraph.transforms.canonical import canonicalize, decanonicalize
from satagraph.transforms.carriage import CARRIAGE_MODES
from satagraph.transforms.foot_plant import plant_feet
from satagraph.transforms.ground import ground_at, lift_above_floor
from satagraph.pipelines.generate_inputs import SECONDS_RANGE, check_seconds, output_paths
from satagraph.data.collate import collate_clips
from satagraph.data.features import MotionFeatures, features_to_motion
from satagraph.semantics.evidence import call_semantic, evidence_from_features
from satagraph.pipelines.inference import (RigMemo, carried_as_character, cross_fade,
                                           default_windows, once_per_motion, restore_rest,
                                           shown_rest, static_features, target_clip,
                                           window_codes, window_plan)
from satagraph.io.checkpoint import CheckpointError
from satagraph.motion import Motion, require_motion


#: The :class:`GenerationSettings` fields that must be finite and >= 0 (or ``None``).
_NON_NEGATIVE = ("guidance", "residual_guidance", "temperature", "residual_temperature",
                 "smooth", "output_smooth", "root_smooth", "choice_temperature", "spread",
                 "residual_window", "window", "draw_guidance")


class SettingError(ValueError):
    """A :class:`GenerationSettings` number no sampling has a meaning for:
    ``"guidance must be a finite number >= 0, got nan"``.

    Args:
        field (str): The setting's field.
        problem (str): What is wrong with it, after the field's name.
    """

    def __init__(self, field: str, problem: str) -> None:
        self.field, self.problem = field, problem
        super().__init__(f"{field} {problem}")

    def __reduce__(self):
        """Pickled with its two arguments, as :class:`~satagraph.io.BVHError`."""
        return type(self), (self.field, self.problem)


@dataclass(frozen=True)
class GenerationSettings:
    """How to sample: decoding steps and guidance of the masked transformer
    (MoMask: 10 and 4), guidance of the residual transformer (MoMask: 5),
    temperature and the share of codes top-k keeps; the residual layers'
    own temperature (``residual_temperature``: 0, the most likely code, by
    default: on the zoo's validation prompts it gave R@3 0.57 against 0.50
    sampled at 1, FID 0.51 against 0.72, experiments/T2M.md section 11;
    ``None``: the same as layer 0's); how many RVQ layers to decode
    (``layers``: default all; the layers above are left out, as the RVQ's
    quantiser dropout trained it for); a Gaussian smoothing of the decoded
    latents over ``smooth`` frames (1.5 by default: on the zoo's validation
    prompts R@3 0.547 against 0.533 unsmoothed, FID 0.456 against 0.527,
    foot sliding 0.99 against 1.32 heights a second; 0: none; a decoder
    trained under its own ``latent_smooth`` smooths at least that much,
    :meth:`~satagraph.lightning.SATARVQModule.decode_codes`); a Gaussian
    smoothing of the decoded rotations and root features over
    ``output_smooth`` frames instead (:func:`smooth_decoded`; 0: none, the
    default), and of the root features (yaw rate, planar velocity, height)
    over ``root_smooth`` frames (2 by default: on four validation streams no
    rule had read, the zoo's FID 0.017 lower, R@3, actions and Bandai's
    R@3 kept, ``experiments/T2M.md`` section 77; ``None``:
    ``output_smooth``'s); whether the
    motion is put on the floor
    (:func:`~satagraph.transforms.ground.ground_at`: one vertical shift, the
    median lowest joint at 0, then each frame that would sink raised onto
    the floor, :func:`~satagraph.transforms.ground.lift_above_floor`) or
    keeps the decoder's root height; whether the body is lowered onto its
    standing feet and they are held still on the floor through their stances
    (:func:`~satagraph.transforms.foot_plant.plant_feet`; on by default:
    ``experiments/T2M.md`` section 47, on validation prompts R@3 0.799
    against 0.781, action 0.59 against 0.54, hover and foot sliding lower);
    MaskGIT's Gumbel
    noise on which tokens each decoding step keeps (``choice_temperature``)
    and how far apart it keeps them (``spread``, a share of their mean gap,
    :func:`~satagraph.nn.generators.sampling.spread_choice`; 0: by
    confidence alone, runs of one code grow, ``experiments/T2M.md`` sections
    20-21); the rest pose a rig is shown in (``rest``,
    :data:`~satagraph.transforms.rest.REST_MODES`: ``"auto"``, as
    ``retarget`` shows it, re-rests a line or captured rest on its mean
    standing pose; ``"file"``, as the generator's data showed it,
    ``experiments/T2M.md`` section 34); and the seconds of the windows the
    residual layers are filled in (``residual_window``, 0: the whole clip at
    once, the default; guided over a whole clip of three seconds or more,
    walks speed up along it, ``experiments/T2M.md`` section 57); and the
    seconds of the windows a longer clip is generated in (``window``:
    ``None``, the default, the window the generator was trained on, so
    that a clip longer than it is generated window after window, each
    continuing the half window before it, its residual layers filled in
    windows of that length too unless ``residual_window`` is set; 0: the
    whole clip at once, which past the trained length reads positions the
    transformers never learnt and slows to a shuffle, ``experiments/T2M.md``
    section 61); and how guidance enters the masked transformer's draws
    (``guide``, :data:`~satagraph.nn.generators.sampling.GUIDES`:
    ``"candidates"``, the default, the guided logits choose the top-k codes
    and logits guided by ``draw_guidance`` (2; 1: the conditional logits)
    draw among them, :func:`~satagraph.nn.generators.sampling.guided_candidates`;
    ``"logits"``, MoMask's, codes drawn from the guided logits, which makes
    walks, runs and dashes 30-45 % faster than real, ``experiments/T2M.md``
    sections 63-64); and the residual transformer's own (``residual_guide``:
    ``"logits"``, the default, whose extrapolation is what walks a person
    backward on a CMU rig; ``None``: ``guide``'s); and how many layer-0
    sequences are drawn for a prompt, the one the text explains best kept
    (``rerank``, :meth:`~satagraph.nn.generators.MaskedTransformer.text_score`;
    1, the default: one draw); and whether the motion is carried as the
    character carries itself in the target file's frames (``carriage``,
    :func:`~satagraph.pipelines.inference.carried_as_character`:
    ``"auto"``, the default, where it never puts down a limb the character
    stands on there: on the test skeletons the dog's and a zoo quadruped's
    forepaws come down, ``down`` 0.00 -> 0.92 and 0.86, direction and
    walk / run / dash speeds the same to the digit, ``experiments/T2M.md`` sections
    92-93; ``"always"``; ``"never"``, the decoder's carriage). The defaults, the masked
    transformer among candidates and the residual one from its guided
    logits, read R@3 0.818 against 0.775, FID 0.201 against 0.252 and
    Bandai's R@3 0.343 against 0.316 on validation prompts, against both
    drawing from the guided logits (section 66)."""

    steps: int = 10
    guidance: float = 4.0
    residual_guidance: float = 5.0
    temperature: float = 1.0
    topk_ratio: float = 0.1
    residual_temperature: Optional[float] = 0.0
    layers: Optional[int] = None
    smooth: float = 1.5
    ground: bool = True
    plant: bool = True
    output_smooth: float = 0.0
    root_smooth: Optional[float] = 2.0
    choice_temperature: float = 0.0
    spread: float = 0.0
    rest: str = "auto"
    residual_window: float = 0.0
    window: Optional[float] = None
    guide: str = "candidates"
    draw_guidance: float = 2.0
    residual_guide: Optional[str] = "logits"
    rerank: int = 1
    carriage: str = "auto"

    def __post_init__(self) -> None:
        """Refuse, in one line naming the field, numbers no sampling has a
        meaning for (a NaN guidance made every draw fail deep in
        ``torch.multinomial``); the guides' names are the sampler's to check."""
        for name in ("steps", "rerank") + (("layers",) if self.layers is not None else ()):
            if int(getattr(self, name)) < 1:
                raise SettingError(name, f"must be at least 1, got {getattr(self, name)}")
        for name in _NON_NEGATIVE:
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value >= 0):
                raise SettingError(name, f"must be a finite number >= 0, got {value}")
        if not 0 < self.topk_ratio <= 1:
            raise SettingError("topk_ratio", f"must be in (0, 1], got {self.topk_ratio}")
        if self.carriage not in CARRIAGE_MODES:
            raise SettingError("carriage", f"must be one of {list(CARRIAGE_MODES)}, "
                               f"got {self.carriage!r}")

    @property
    def residual_draw(self) -> str:
        """How guidance enters the residual transformer's draws:
        :attr:`residual_guide`, else :attr:`guide`."""
        return self.guide if self.residual_guide is None else self.residual_guide

    def window_frames(self, module) -> Optional[int]:
        """:attr:`window` in frames of :obj:`module` (``None``: whole clips;
        by default the window it was trained on, ``meta["window"]``, where
        recorded)."""
        if self.window is None:
            trained = (getattr(module, "meta", None) or {}).get("window")
            return int(trained) if trained else None
        return int(round(self.window * module.fps)) if self.window > 0 else None

    def residual_frames(self, module) -> Optional[int]:
        """:attr:`residual_window` in frames of :obj:`module`, else
        :meth:`window_frames` (``None``: whole clips)."""
        if self.residual_window > 0:
            return int(round(self.residual_window * module.fps))
        return self.window_frames(module)


def load_generator(ckpt: str = "builtin"):
    """A trained text-to-motion module from a checkpoint or weights file
    (``"builtin"``: the one shipped in the package), in eval mode.

    Args:
        ckpt (str): ``"builtin"``, a ``.ckpt`` checkpoint or a
            ``.safetensors`` weights file of a text-to-motion module.

    Returns:
        TextToMotionModule: The generator, ready for :func:`generate_on`.

    Raises:
        CheckpointError: Missing or damaged file, another kind of
            checkpoint (an autoencoder), or a text encoder other than the
            one it was trained with; one line naming :obj:`ckpt`.
    """
    from satagraph.lightning.text_to_motion import TextToMotionModule
    from satagraph.experiment.train import load_module
    from satagraph.io.weights import BUILTIN_VARIANTS, resolve_weights
    if ckpt in BUILTIN_VARIANTS:
        raise CheckpointError(f"{ckpt}: a built-in retargeting model, not a text-to-motion "
                              "one (generate's built-in model is --ckpt builtin)")
    ckpt = resolve_weights(ckpt, kind=TextToMotionModule.builtin_kind)  # a folder: its last.ckpt
    if not os.path.isfile(ckpt):
        raise CheckpointError(f"{ckpt}: no such checkpoint file")
    try:
        module = load_module(ckpt)
    except CheckpointError as err:
        text = str(err)
        raise CheckpointError(text if text.startswith(ckpt) else f"{ckpt}: {text}") from None
    except ValueError as err:  # e.g. a text encoder mismatch
        raise CheckpointError(f"{ckpt}: {err}") from None
    if not isinstance(module, TextToMotionModule):
        kind = (getattr(module, "meta", None) or {}).get("module", "?")
        raise CheckpointError(f"{ckpt}: a {kind!r} checkpoint, not a text-to-motion one "
                              "(train one with `satagraph train t2m_tiny`)")
    return module.eval()


@dataclass(frozen=True)
class RigInputs:
    """A skeleton as the model sees it: the canonical motion, the motion
    in the rest pose shown to the model (a line or captured rest re-rested on
    its mean standing pose, :func:`~satagraph.transforms.rest.shown_rest`),
    its static features, semantic embedding, and the rest rotations that
    undo the re-resting (``None``: none); :attr:`memo` keeps how the
    character carries itself in :attr:`canon`'s frames once computed
    (:func:`~satagraph.pipelines.inference.carried_as_character`)."""

    canon: Motion
    shown: Motion
    feats: MotionFeatures
    semantic: Optional[torch.Tensor]
    undo: Optional[np.ndarray]
    memo: RigMemo = field(default_factory=RigMemo, compare=False, repr=False)


def rig_inputs(module, target: Motion, rest: str = "auto") -> RigInputs:
    """The :class:`RigInputs` of a target for :obj:`module`, shown in the
    rest pose :obj:`rest` names (:data:`~satagraph.transforms.rest.REST_MODES`)."""
    canon = canonicalize(target, fps=module.fps)
    shown, undo = shown_rest(canon, rest)
    feats = static_features(shown)
    semantic = module.semantic_fn()
    sem = None if semantic is None else call_semantic(
        semantic, feats.skeleton, evidence_from_features(feats)).float()
    return RigInputs(canon, shown, feats, sem, undo)


def _frames(module, text_emb, skel_emb, seconds: Optional[float],
            generator: torch.Generator) -> int:
    """Frames to generate: the user's duration (:func:`check_seconds`), else
    a draw of the length model (at least two frames)."""
    if seconds is None:
        seconds = float(module.length.sample(text_emb, skel_emb, generator=generator)[0])
    else:
        check_seconds(seconds)
    return max(2, int(round(seconds * module.fps)))


@torch.no_grad()
def generate_on(module, text: Optional[str], target: Union[Motion, RigInputs],
                seconds: Optional[float] = None,
                seed: int = 0, settings: GenerationSettings = GenerationSettings(),
                known: Optional[torch.Tensor] = None,
                keep: Optional[torch.Tensor] = None) -> Motion:
    r"""A motion for :obj:`text` on :obj:`target`'s skeleton, on its own rig.

    Args:
        module: A :class:`~satagraph.lightning.text_to_motion.TextToMotionModule`.
        text (str, optional): The prompt (``None``: unconditional, the
            skeleton only).
        target (Motion or RigInputs): A motion of the target rig (its frames
            set the start position and facing; the rest pose and layout are
            kept), or its :func:`rig_inputs` for :obj:`module` and
            ``settings.rest``, made once for many prompts (made for each,
            0.4 s a prompt on the dog's 1531-frame clip, loaded 2-core VM).
        seconds (float, optional): Duration (default: drawn from the length
            model).
        seed (int): Seed of every draw.
        settings (GenerationSettings): Sampling settings.
        known (Tensor, optional): Layer-0 tokens :math:`(1, T)` to infill
            around (see :meth:`~satagraph.nn.generators.MaskedTransformer.generate`).
        keep (Tensor, optional): :math:`(1, T)` bool, which of :obj:`known`
            to keep.

    Returns:
        Motion: On the target's rig at the model's frame rate.
    """
    rig = target if isinstance(target, RigInputs) else rig_inputs(
        module, require_motion(target, "target"), settings.rest)
    module.eval()
    gen = torch.Generator().manual_seed(int(seed))
    device = module.device
    skel_batch = collate_clips([target_clip(rig.feats, 1, rig.semantic)]).to(device)
    skel_emb = module.skeleton_embedding(skel_batch)
    text_emb = None if text is None else module.encode_text([text])
    frames = _frames(module, text_emb, skel_emb, seconds, gen)
    lengths = torch.tensor([frames], device=device)
    base = _layer0(module, text_emb, skel_emb, lengths, settings, gen, known, keep)
    temperature = (settings.temperature if settings.residual_temperature is None
                   else settings.residual_temperature)
    codes = module.residual.generate(base, text_emb, skel_emb, lengths,
                                     settings.residual_guidance, temperature,
                                     settings.topk_ratio, gen, settings.layers,
                                     settings.residual_frames(module), settings.residual_draw,
                                     settings.draw_guidance)
    return decode_on(module, _all_layers(codes[0, :frames], module.num_quantizers), rig,
                     settings)


def _layer0(module, text_emb: Optional[torch.Tensor], skel_emb: torch.Tensor,
            lengths: torch.Tensor, settings: GenerationSettings, gen: torch.Generator,
            known: Optional[torch.Tensor], keep: Optional[torch.Tensor]) -> torch.Tensor:
    r"""Layer-0 codes of one prompt by the masked transformer: ``rerank``
    draws in one batch where a text is given, the one of the highest
    :meth:`~satagraph.nn.generators.MaskedTransformer.text_score` kept.

    Shapes:
        - **output**: :math:`(1, T)`
    """
    draws = max(int(settings.rerank), 1) if text_emb is not None else 1
    text_emb, skel_emb, lengths, known, keep = (
        None if x is None else x.repeat(draws, *[1] * (x.dim() - 1))
        for x in (text_emb, skel_emb, lengths, known, keep))
    base = module.masked.generate(text_emb, skel_emb, lengths, settings.steps,
                                  settings.guidance, settings.temperature,
                                  settings.topk_ratio, gen, known=known, keep=keep,
                                  choice_temperature=settings.choice_temperature,
                                  spread=settings.spread, window=settings.window_frames(module),
                                  guide=settings.guide, draw_guidance=settings.draw_guidance)
    if draws == 1:
        return base
    best = int(module.masked.text_score(base, text_emb, skel_emb, lengths, generator=gen).argmax())
    return base[best:best + 1]


def _all_layers(codes: torch.Tensor, num_quantizers: int) -> torch.Tensor:
    """Per-frame codes with the layers left out filled with ``-1`` (a
    dropped layer to the RVQ).

    Shapes:
        - **codes**: :math:`(T, Q')`, **output**: :math:`(T, Q)`
    """
    missing = num_quantizers - codes.size(-1)
    if missing <= 0:
        return codes
    return torch.cat([codes, codes.new_full((codes.size(0), missing), -1)], dim=-1)


#: Codes decoded as the decoder gives them: no smoothing, no carriage, no
#: grounding, no planting (:func:`decode_on`'s default).
RAW_DECODING = GenerationSettings(smooth=0.0, root_smooth=0.0, ground=False, plant=False,
                                  carriage="never")


def decode_on(module, codes: torch.Tensor, rig: RigInputs,
              settings: GenerationSettings = RAW_DECODING) -> Motion:
    r"""Per-frame codes decoded onto a target (:func:`rig_inputs`), back on
    its rig, as :obj:`settings` decode (:data:`RAW_DECODING`, the default:
    as the decoder gives them): the latents smoothed over ``smooth`` frames
    first (:meth:`~satagraph.lightning.SATARVQModule.decode_codes`), the
    decoded rotations and root features over ``output_smooth`` frames and
    the root's over ``root_smooth`` where it is set (:func:`smooth_decoded`),
    carried as the target character (``carriage``,
    :func:`~satagraph.pipelines.inference.carried_as_character`, checked on
    the floor), on the floor with ``ground``
    (:func:`~satagraph.transforms.ground.ground_at` and
    :func:`~satagraph.transforms.ground.lift_above_floor`), the feet held
    through their stances with ``plant``
    (:func:`~satagraph.transforms.foot_plant.plant_feet`). Decoded window
    by window (:func:`decode_windows`).

    Shapes:
        - **codes**: :math:`(T, Q)`
    """
    frames, num = codes.size(0), rig.feats.skeleton.num_joints
    decoded = decode_windows(module.autoencoder, codes, rig, settings.smooth)
    q, r = smooth_decoded(*decoded, settings.output_smooth, settings.root_smooth)
    q = q.view(frames, num, 6).cpu().double().numpy()
    r = r.cpu().double().numpy()
    done = replace(rig.feats, q=q, r=r, fps=module.fps, transform=rig.canon.transform)
    motion = restore_rest(features_to_motion(done, q=q, r=r, use_positions=False),
                          rig.undo, rig.canon.skeleton)
    on_floor = once_per_motion(_on_floor)  # the gate's reading reused where it keeps the motion
    motion = carried_as_character(motion, rig.canon, settings.carriage, on_floor, rig.memo,
                                  paced=False)  # no source to keep travel with: T2M.md 93
    if settings.ground:
        motion = on_floor(motion)
    if settings.plant:
        motion = plant_feet(motion)
    return decanonicalize(motion, rig.canon.transform, fps=module.fps)


def _on_floor(motion: Motion) -> Motion:
    """A canonical motion on the floor as ``ground`` puts it: its median
    lowest joint at 0, then each frame that would sink raised onto it."""
    return lift_above_floor(ground_at(motion))


def encode_windows(autoencoder, feats: MotionFeatures,
                   semantic: Optional[torch.Tensor] = None) -> torch.Tensor:
    r"""Per-frame codes of a motion's features by a SATA-RVQ, in its
    training windows as :func:`decode_windows` decodes them
    (:func:`~satagraph.pipelines.inference.window_codes`).

    Shapes:
        - **output**: :math:`(T, Q)`
    """
    return window_codes(autoencoder, [feats.to_clip(semantic=semantic)])[0]


def decode_windows(autoencoder, codes: torch.Tensor, rig: RigInputs,
                   smooth: float = 0.0) -> Tuple[torch.Tensor, torch.Tensor]:
    r"""Physical ``q`` and ``r`` of per-frame codes decoded onto :obj:`rig`
    in the autoencoder's training windows, a quarter of each shared with
    the next and cross-faded there, as ``retarget`` stitches them
    (:func:`~satagraph.pipelines.inference.window_plan`,
    :func:`~satagraph.pipelines.inference.cross_fade`; cut at each
    window's ``keep``, the pose jumped at every seam). The temporal
    layers' sinusoidal positions were learnt on that many frames; decoded
    whole, a 4-second walk lost its pace after the 64 frames the shipped
    RVQ was trained on (root speed falling to a third of the source's).

    Shapes:
        - **codes**: :math:`(T, Q)`
        - **output**: :math:`(T \cdot J, 6)` and :math:`(T, 4)`, of the decoder's
          dtype on the codes' device
    """
    window, overlap = default_windows(autoencoder)
    frames, num = codes.size(0), rig.feats.skeleton.num_joints
    q, r = np.empty((frames, num, 6)), np.empty((frames, 4))
    done, dtype = 0, None
    for start, stop, _ in window_plan(frames, window, overlap):
        target = collate_clips([target_clip(rig.feats, stop - start, rig.semantic)])
        out = autoencoder.decode_codes(codes[start:stop], target.to(codes.device), smooth)
        cross_fade(q, out["q"].view(stop - start, num, 6).cpu().double().numpy(), start, done)
        cross_fade(r, out["r"].cpu().double().numpy(), start, done)
        done, dtype = stop, out["q"].dtype
    return tuple(torch.from_numpy(x).to(codes.device, dtype)
                 for x in (q.reshape(-1, 6), r))


def smooth_decoded(q: torch.Tensor, r: torch.Tensor, sigma: float,
                   root_sigma: Optional[float] = None) -> Tuple[torch.Tensor, torch.Tensor]:
    r"""Decoded rotations (6D) and root features of one motion smoothed
    along time by a Gaussian of :obj:`sigma` frames, the root features by
    one of :obj:`root_sigma` where it is given
    (:func:`~satagraph.ops.smoothing.gaussian_smooth`; 0: as is). Where
    smoothing the latents averages codes that the decoder reads as
    different poses, and so shortens every swing, this smooths what was
    decoded (``experiments/T2M.md`` section 49).

    Shapes:
        - **q**: :math:`(T \cdot J, 6)`, **r**: :math:`(T, 4)`
        - **output**: the same
    """
    frames = torch.tensor([r.size(0)])
    q = gaussian_smooth(q.reshape(r.size(0), -1), frames, sigma).reshape(-1, 6)
    return q, gaussian_smooth(r, frames, sigma if root_sigma is None else root_sigma)


def write_all(motions: Sequence[Motion], paths: Sequence[str]) -> None:
    """Write every motion (each atomically); on a failure, the files this
    call wrote are removed again, so that no partial set is left, where
    they are still the ones it wrote (another run may have written one
    since)."""
    from satagraph.io import write_bvh
    written: List[Tuple[str, os.stat_result]] = []
    try:
        for motion, path in zip(motions, paths):
            existed = os.path.exists(path)
            write_bvh(motion, path)
            if not existed:
                written.append((path, os.stat(path)))
    except BaseException:
        for path, mine in written:
            if _same_write(path, mine):
                Path(path).unlink(missing_ok=True)
        raise


def _same_write(path: str, mine: os.stat_result) -> bool:
    """Whether :obj:`path` is still the file whose :func:`os.stat` was
    :obj:`mine` (an atomic write of another run is another file)."""
    try:
        now = os.stat(path)
    except FileNotFoundError:
        return False
    return os.path.samestat(now, mine) and (now.st_mtime_ns, now.st_size) == (
        mine.st_mtime_ns, mine.st_size)


__all__ = ["SECONDS_RANGE", "check_seconds", "SettingError", "GenerationSettings", "RigInputs",
           "rig_inputs", "load_generator", "generate_on", "RAW_DECODING", "decode_on",
           "output_paths", "write_all"]
