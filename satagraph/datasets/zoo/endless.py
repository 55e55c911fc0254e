r"""An endless zoo: a new rig and clip for every ``(seed, epoch, index)``.

Instead of the zoo's fixed skeletons (:func:`~satagraph.datasets.zoo.zoo_rigs`),
every sample draws a body plan and variant (:data:`~satagraph.datasets.zoo.VARIANTS`),
fresh proportions (the rig builders' random generator), a clip kind
(:data:`~satagraph.datasets.zoo.CLIP_KINDS`), a rest pose
(:data:`~satagraph.datasets.zoo.REST_POSES`) and a joint-naming noise
(:data:`~satagraph.datasets.zoo.NOISE_STYLES`). The result is a pure function
of the key, so any worker, restart or resumed run draws the same sample.

Body plans can be held out: a ``holdout`` entry is a species
(``"crab"``) or one variant of it (``"quadruped/abbrev"``); held-out plans
are never drawn for training (:meth:`EndlessZoo.sample` with
``holdout=False``) and only drawn for evaluation. Evaluation samples come
from a separate seed stream (:data:`EVAL_STREAMS`), so their rigs are
never trained on either.

Example::

    zoo = EndlessZoo(seed=0, holdout=["quadruped/abbrev"])
    sample = zoo.sample(epoch=3, index=17, frames=65)
    sample.motion, sample.species, sample.variant
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from satagraph.datasets.zoo.dialects import NOISE_STYLES, REST_POSES, Dialect, apply_dialect
from satagraph.datasets.zoo.motions import ClipFacts, generate_clip_with_facts
from satagraph.datasets.zoo.rigs import stance_of_bend
from satagraph.datasets.zoo.species import (_BUILDERS, _BUILDERS_BY_STYLE, SPECIES,
                                            VARIANTS, kinds_of)
from satagraph.motion import Motion

#: Seed streams: training samples, and the held-out seeds of validation
#: and test samples (never drawn in training).
EVAL_STREAMS = {"train": 0, "val": 1, "test": 2}

#: Default species of the endless zoo: the plans the rules read well and
#: the generator walks (``longtail``, 100 joints, is slower: opt in).
DEFAULT_SPECIES = ("biped", "quadruped", "bird", "hexapod", "snake", "fowl", "crab",
                   "spider")


@dataclass(frozen=True)
class ZooSample:
    """One endless-zoo sample: a canonical motion (metres, +Y up), what
    it was drawn as and what the clip does (:attr:`facts`, the truth of its
    captions)."""

    motion: Motion
    species: str
    variant: str
    kind: str
    rest: str
    noise: Optional[str]
    facts: Optional[ClipFacts] = None

    @property
    def plan(self) -> str:
        """``species/variant``."""
        return f"{self.species}/{self.variant}"


def _variant_names(species: str) -> List[str]:
    return [style for style, _ in VARIANTS[species]]


def _plans(species: Sequence[str]) -> List[Tuple[str, int]]:
    """``(species, variant index)`` of every variant of :obj:`species`."""
    return [(s, v) for s in species for v in range(len(VARIANTS[s]))]


def _matches(plan: Tuple[str, int], holdout: Sequence[str]) -> bool:
    species, v = plan
    return any(h == species or h == f"{species}/{VARIANTS[species][v][0]}"
               for h in holdout)


class EndlessZoo:
    r"""Samples new zoo rigs and clips, deterministic in ``(seed, stream,
    epoch, index)``.

    Args:
        species (list[str], optional): Body plans drawn (default
            :data:`DEFAULT_SPECIES`).
        holdout (list[str], optional): Held-out plans: species
            (``"crab"``) or variants (``"quadruped/abbrev"``), drawn only in
            evaluation streams. Held-out species need not be in
            :obj:`species`.
        rests (list[str]): Rest poses drawn (default: all of
            :data:`~satagraph.datasets.zoo.REST_POSES`).
        noise (float): Probability of noisy joint names.
        fps (float): Frame rate of the clips.
        seed (int): Base seed.
        kinds (list[str], optional): Clip kinds drawn, of those each species
            can do (:data:`~satagraph.datasets.zoo.species.ALL_KINDS`, which
            adds the gestures: ``bow`` and ``wave`` of bipeds, ``sit`` and
            ``lie`` of quadrupeds); default: each species'
            :data:`~satagraph.datasets.zoo.CLIP_KINDS`. Every drawn and
            held-out species must be able to do at least one of them.
        stance_bend (dict, optional): Species -> ``(low, high)``: the knee
            bend, in degrees, at which that species' rigs stand, drawn
            uniformly per sample (:attr:`~satagraph.datasets.zoo.rigs.ZooRig.stance`;
            e.g. ``{"biped": (5, 36)}``: upright humans to the zoo's
            crouch). Drawn apart from every other choice, so a sample keeps
            its rig, clip, rest and names; species not named keep the
            zoo's stance (36 degrees).
    """

    def __init__(self, species: Optional[Sequence[str]] = None,
                 holdout: Optional[Sequence[str]] = None,
                 rests: Sequence[str] = REST_POSES, noise: float = 0.3,
                 fps: float = 30.0, seed: int = 0,
                 kinds: Optional[Sequence[str]] = None,
                 stance_bend: Optional[Mapping[str, Sequence[float]]] = None) -> None:
        self.species = list(DEFAULT_SPECIES if species is None else species)
        self.holdout = list(holdout or [])
        for name in self.species + [h.split("/")[0] for h in self.holdout]:
            if name not in SPECIES:
                raise ValueError(f"endless zoo: unknown species {name!r}; choose from "
                                 f"{list(SPECIES)}")
        for h in self.holdout:
            if "/" in h and h.split("/", 1)[1] not in _variant_names(h.split("/")[0]):
                raise ValueError(f"endless zoo: unknown variant {h!r}; "
                                 f"{h.split('/')[0]} has {_variant_names(h.split('/')[0])}")
        bad = [r for r in rests if r not in REST_POSES]
        if bad:
            raise ValueError(f"endless zoo: unknown rest poses {bad}; choose from "
                             f"{list(REST_POSES)}")
        every = _plans(self.species)
        self.train_plans = [p for p in every if not _matches(p, self.holdout)]
        held_species = [h.split("/")[0] for h in self.holdout]
        self.holdout_plans = [p for p in _plans(dict.fromkeys(self.species + held_species))
                              if _matches(p, self.holdout)]
        if not self.train_plans:
            raise ValueError("endless zoo: every body plan is held out")
        self.rests, self.noise = list(rests), float(noise)
        self.fps, self.seed = float(fps), int(seed)
        self.kinds = kinds_of(self.species + held_species, kinds, "endless zoo")
        self.stance_bend = _stance_bends(stance_bend or {})

    def plans(self, holdout: bool = False) -> List[str]:
        """``species/variant`` names drawn for training (or held out)."""
        chosen = self.holdout_plans if holdout else self.train_plans
        return [f"{s}/{VARIANTS[s][v][0]}" for s, v in chosen]

    def species_of(self, index: int, holdout: bool = False) -> str:
        """The species of sample :obj:`index`: plans are visited in turn,
        so every plan is equally frequent and the group of a sample is known
        without drawing it."""
        plans = self.holdout_plans if holdout else self.train_plans
        return plans[index % len(plans)][0]

    def sample(self, epoch: int, index: int, frames: int, stream: str = "train",
               holdout: bool = False) -> ZooSample:
        r"""The sample of a key.

        Args:
            epoch (int): Epoch (training draws a new sample per epoch).
            index (int): Sample index.
            frames (int): Frames of the clip.
            stream (str): ``"train"``, ``"val"`` or ``"test"``: evaluation
                streams use seeds training never draws.
            holdout (bool): Draw from the held-out plans instead.

        Returns:
            ZooSample: The canonical motion and its description.
        """
        plans = self.holdout_plans if holdout else self.train_plans
        if not plans:
            raise ValueError("endless zoo: no held-out body plans")
        species, v = plans[index % len(plans)]
        rng = np.random.default_rng([self.seed, EVAL_STREAMS[stream], int(holdout),
                                     epoch, index])
        style, options = VARIANTS[species][v]
        build = _BUILDERS_BY_STYLE.get((species, style), _BUILDERS[species])
        name = f"endless-{species}-{style}-{epoch}-{index}"
        rig = build(style, np.random.default_rng(rng.integers(2 ** 63)), name, **options)
        if species in self.stance_bend:
            low, high = self.stance_bend[species]
            own = np.random.default_rng([self.seed, EVAL_STREAMS[stream], int(holdout),
                                         epoch, index, 1])
            rig = replace(rig, stance=stance_of_bend(own.uniform(low, high)))
        kinds = self.kinds[species]
        kind = kinds[int(rng.integers(len(kinds)))]
        motion, facts = generate_clip_with_facts(rig, kind, frames=frames, fps=self.fps,
                                                 seed=int(rng.integers(2 ** 31)))
        rest = self.rests[int(rng.integers(len(self.rests)))]
        noise = (NOISE_STYLES[int(rng.integers(len(NOISE_STYLES)))]
                 if rng.random() < self.noise else None)
        motion, _ = apply_dialect(motion, Dialect(rest=rest, noise=noise),
                                  seed=int(rng.integers(2 ** 31)))
        return ZooSample(motion, species, style, kind, rest, noise, facts)


def _stance_bends(spec: Mapping[str, Sequence[float]]) -> Dict[str, Tuple[float, float]]:
    """``stance_bend`` checked: known species, ``0 <= low <= high < 90``."""
    out = {}
    for name, bounds in spec.items():
        if name not in SPECIES:
            raise ValueError(f"endless zoo: stance_bend names unknown species {name!r}; "
                             f"choose from {list(SPECIES)}")
        low, high = (float(b) for b in bounds)
        if not 0.0 <= low <= high < 90.0:
            raise ValueError(f"endless zoo: stance_bend {name}: {list(bounds)} is not a "
                             "range of knee bends in degrees (0 <= low <= high < 90)")
        out[name] = (low, high)
    return out


__all__ = ["EVAL_STREAMS", "DEFAULT_SPECIES", "ZooSample", "EndlessZoo"]
