"""Species of the zoo, their skeleton variants and :func:`zoo_rigs`."""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from satagraph.data.zoo.bodies import _biped, _bird, _hexapod, _quadruped, _snake
from satagraph.data.zoo.rigs import ZooRig

SPECIES = ("biped", "quadruped", "bird", "hexapod", "snake")
CLIP_KINDS = {
    "biped": ("walk", "turn", "speed", "idle"),
    "quadruped": ("walk", "trot", "turn", "speed", "idle"),
    "bird": ("walk", "turn", "speed", "idle"),
    "hexapod": ("walk", "turn", "speed", "idle"),
    "snake": ("walk", "turn", "speed", "idle"),
}

VARIANTS: Dict[str, Tuple[Tuple[str, dict], ...]] = {
    "biped": (("mixamo", {}), ("blender", {}), ("smpl", {}), ("cmu", {})),
    "quadruped": (("frontleg", {"tail": True}), ("abbrev", {"tail": False}),
                  ("blender", {"tail": True}), ("mixamo", {"tail": False})),
    "bird": (("mixamo", {}), ("blender", {}), ("smpl", {})),
    "hexapod": (("insect", {}), ("insect_snake", {})),
    "snake": (("snake", {}), ("snake_blender", {}), ("snake_vertebra", {})),
}
_BUILDERS = {"biped": _biped, "quadruped": _quadruped, "bird": _bird,
             "hexapod": _hexapod, "snake": _snake}


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
            out.append(_BUILDERS[name](style, rng, rig_name, **options))
    return out


def _check_species(species: Optional[Sequence[str]]) -> List[str]:
    species = list(SPECIES if species is None else species)
    unknown = [s for s in species if s not in SPECIES]
    if unknown:
        raise ValueError(f"unknown species {unknown}: choose from {list(SPECIES)}")
    return species

