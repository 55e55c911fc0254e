r"""Which built-in autoencoder reads a set of rigs (``--ckpt auto``).

Two autoencoders ship: ``builtin``, trained on the zoo's bipeds,
quadrupeds, birds and fowl and the CMU-licensed humans, and
``builtin-wide``, the same network trained further on every body plan of
the zoo. On validation material (``benchmarks/pretrained_val.py``,
``experiments/PRETRAIN.md`` section 20) each is the better one on its own
side of a line the skeleton itself draws:

============================  ==============  ===================
validation group (JP, % of    ``builtin``     ``builtin-wide``
the height, median)
============================  ==============  ===================
zoo biped / quadruped / bird  4.9 / 6.0 / 3.1  5.3 / 11.5 / 8.9
Bandai (validation split)     10.0             11.3
zoo hexapod / crab / spider   148 / 241 / 63   10.5 / 12.1 / 17.7
zoo snake                     593              80
============================  ==============  ===================

A rig is read by ``builtin`` when its joints describe at most four limbs
(:func:`~satagraph.semantics.paired_legs` finds no numbered leg pairs) and
at least one limb end (:func:`~satagraph.semantics.limb_ends`); otherwise
(insects, crabs, spiders: six or more legs; snakes: no limbs) by
``builtin-wide``. A retarget uses one model for both rigs, so one rig of
the second kind makes it ``builtin-wide``.
"""
from __future__ import annotations

from pathlib import Path
from typing import NamedTuple, Optional, Sequence

from satagraph.semantics import limb_ends, paired_legs
from satagraph.skeleton import Skeleton

#: The name that picks a built-in autoencoder by the rigs.
AUTO = "auto"


class BuiltinChoice(NamedTuple):
    """A built-in autoencoder's name and why it was chosen."""
    name: str
    reason: str


def _plan(skeleton: Skeleton) -> Optional[str]:
    """What makes a rig one for ``builtin-wide`` (``None``: nothing)."""
    legs = paired_legs(skeleton)
    if legs:
        return f"{legs} legs in pairs"
    if not limb_ends(skeleton):
        return "no limbs"
    return None


def choose_builtin(skeletons: Sequence[Skeleton],
                   names: Optional[Sequence[str]] = None) -> BuiltinChoice:
    """The built-in autoencoder for :obj:`skeletons` (see the module).

    Args:
        skeletons (list): The rigs a command reads (a retarget's source and
            target).
        names (list, optional): What to call each in the reason (default:
            ``skeleton 0``, ...).
    """
    names = list(names) if names is not None else [f"skeleton {i}"
                                                    for i in range(len(skeletons))]
    for skeleton, name in zip(skeletons, names):
        plan = _plan(skeleton)
        if plan is not None:
            return BuiltinChoice("builtin-wide", f"{Path(name).name}: {plan}")
    return BuiltinChoice("builtin", "humans and animals of four limbs or fewer")


__all__ = ["AUTO", "BuiltinChoice", "choose_builtin"]
