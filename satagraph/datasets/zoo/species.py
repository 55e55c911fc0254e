"""Species of the zoo, their skeleton variants and :func:`zoo_rigs`.

New species only ever go at the END of :data:`SPECIES` and new variants at
the end of their tuple in :data:`VARIANTS`: rigs are seeded by ``(seed,
species index, variant index)`` and clips by the rig's position in the
zoo, so this keeps every existing rig and clip byte-identical."""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from satagraph.datasets.zoo.bodies import _biped, _bird, _hexapod, _quadruped, _snake
from satagraph.datasets.zoo.creatures import _bip01, _crab, _fingerwing, _longtail, _spider
from satagraph.datasets.zoo.rigs import ZooRig

#: Body plans: ``fowl`` are birds in exporter dialects (``Bip01_*`` with
#: legs and wings off one spine joint, finger-named wings), ``longtail`` a
#: long-tailed quadruped of about 100 joints.
SPECIES = ("biped", "quadruped", "bird", "hexapod", "snake", "fowl", "crab",
           "spider", "longtail")
#: Clip kinds per body plan (:mod:`satagraph.datasets.zoo.motions` says what
#: each does); kinds added later come last, so that a zoo written with the
#: first kinds only (``write_zoo(clips=N)``) stays the same.
_LEGGED = ("walk", "turn", "speed", "idle", "start", "stop", "look", "jump")
_TRAVEL = ("back", "side", "run")
CLIP_KINDS = {
    "biped": _LEGGED + ("reach",) + _TRAVEL,
    "quadruped": ("walk", "trot") + _LEGGED[1:] + _TRAVEL,
    "bird": _LEGGED + _TRAVEL,
    "hexapod": _LEGGED + _TRAVEL,
    "snake": ("walk", "turn", "speed", "idle"),
    "fowl": _LEGGED + _TRAVEL,
    "crab": _LEGGED + _TRAVEL,
    "spider": _LEGGED + _TRAVEL,
    "longtail": ("walk", "trot") + _LEGGED[1:] + _TRAVEL,
}
#: Gestures: kinds a species can do that the endless zoo draws only when a
#: source asks for them (``kinds``), so that the draws of :data:`CLIP_KINDS`
#: (and every model trained on them) stay as they were.
GESTURE_KINDS: Dict[str, Tuple[str, ...]] = {"biped": ("bow", "wave"),
                                             "quadruped": ("sit", "lie")}
#: Every kind a species can do: :data:`CLIP_KINDS`, then its gestures.
ALL_KINDS = {s: kinds + GESTURE_KINDS.get(s, ()) for s, kinds in CLIP_KINDS.items()}

VARIANTS: Dict[str, Tuple[Tuple[str, dict], ...]] = {
    "biped": (("mixamo", {}), ("blender", {}), ("smpl", {}), ("cmu", {})),
    "quadruped": (("frontleg", {"tail": True}), ("abbrev", {"tail": False}),
                  ("blender", {"tail": True}), ("mixamo", {"tail": False})),
    "bird": (("mixamo", {}), ("blender", {}), ("smpl", {})),
    "hexapod": (("insect", {}), ("insect_snake", {})),
    "snake": (("snake", {}), ("snake_blender", {}), ("snake_vertebra", {})),
    "fowl": (("bip01", {}), ("fingerwing", {})),
    "crab": (("plain", {}), ("abdomen", {"abdomen": True})),
    "spider": (("plain", {}), ("palps", {"palps": True})),
    "longtail": (("tail32", {"tail_joints": 32}), ("tail36", {"tail_joints": 36})),
}
_BUILDERS = {"biped": _biped, "quadruped": _quadruped, "bird": _bird,
             "hexapod": _hexapod, "snake": _snake, "fowl": _bip01,
             "crab": _crab, "spider": _spider, "longtail": _longtail}
_BUILDERS_BY_STYLE = {("fowl", "fingerwing"): _fingerwing}


def kinds_of(species: Sequence[str], kinds: Optional[Sequence[str]] = None,
             who: str = "zoo") -> Dict[str, Tuple[str, ...]]:
    """Species -> the clip kinds to draw for it: of :obj:`kinds`, those the
    species can do (:data:`ALL_KINDS`, in that order); each species'
    :data:`CLIP_KINDS` when :obj:`kinds` is ``None``.

    Raises:
        ValueError: An unknown kind, or a species that can do none of
            :obj:`kinds` (the message starts with :obj:`who`).
    """
    if kinds is None:
        return {s: CLIP_KINDS[s] for s in species}
    known = set().union(*ALL_KINDS.values())
    unknown = [k for k in kinds if k not in known]
    if unknown:
        raise ValueError(f"{who}: unknown clip kinds {unknown}; choose from {sorted(known)}")
    out = {s: tuple(k for k in ALL_KINDS[s] if k in kinds) for s in species}
    empty = [s for s, chosen in out.items() if not chosen]
    if empty:
        raise ValueError(f"{who}: {', '.join(empty)} can do none of the kinds {list(kinds)}")
    return out


def zoo_rigs(species: Optional[Sequence[str]] = None, seed: int = 0) -> List[ZooRig]:
    r"""The zoo's skeletons: every variant of every requested species.

    Proportions are drawn from a generator seeded by ``(seed, species,
    variant)``, so a subset of species gives the same skeletons as the full
    zoo.

    Args:
        species (list[str], optional): Species from :data:`SPECIES`
            (default: all).
        seed (int): Random seed.
    """
    out = []
    for name in _check_species(species):
        s = SPECIES.index(name)
        for v, (style, options) in enumerate(VARIANTS[name]):
            rng = np.random.default_rng([seed, s, v])
            tag = "" if "tail" not in options else (
                "-tail" if options["tail"] else "-notail")
            rig_name = f"zoo{seed}-{name}-{style}{tag}"
            build = _BUILDERS_BY_STYLE.get((name, style), _BUILDERS[name])
            out.append(build(style, rng, rig_name, **options))
    return out


def _check_species(species: Optional[Sequence[str]]) -> List[str]:
    species = list(SPECIES if species is None else species)
    unknown = [s for s in species if s not in SPECIES]
    if unknown:
        raise ValueError(f"unknown species {unknown}: choose from {list(SPECIES)}")
    return species

