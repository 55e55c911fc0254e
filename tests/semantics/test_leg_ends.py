"""Every leg's end (``leg_ends``): an arthropod's middle pairs too, and the
four limbs' ends on any other body."""
from __future__ import annotations

import pytest

from satagraph.datasets.zoo import zoo_rigs
from satagraph.semantics import describe_joints, leg_ends, limb_ends


@pytest.mark.parametrize("species, legs", [("hexapod", 6), ("crab", 6), ("spider", 8)])
def test_an_arthropod_has_an_end_for_every_leg(species: str, legs: int) -> None:
    for rig in zoo_rigs([species], seed=3)[:2]:
        skeleton = rig.skeleton
        ends = leg_ends(skeleton)
        texts = describe_joints(skeleton)
        assert len(ends) == legs == len(set(ends))
        assert set(limb_ends(skeleton).values()) <= set(ends)  # front and hind among them
        assert all("limb terminal segment" in texts[j] and "leg pair" in texts[j]
                   for j in ends)
        assert sum("middle limb" in texts[j] for j in ends) == legs - 4


@pytest.mark.parametrize("species", ["biped", "quadruped", "bird", "longtail"])
def test_a_body_of_four_limbs_or_fewer_keeps_its_limb_ends(species: str) -> None:
    for rig in zoo_rigs([species], seed=3)[:2]:
        assert leg_ends(rig.skeleton) == sorted(limb_ends(rig.skeleton).values())
