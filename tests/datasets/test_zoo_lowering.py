"""The zoo quadrupeds' lowering gestures (``sit``, ``lie``): the body goes
down and gets up in place, feet planted and flat, nothing under the
ground; drawn only when asked; captioned."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.datasets.captions import captions_for
from satagraph.datasets.zoo import CLIP_KINDS, generate_clip_with_facts, zoo_rigs
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.datasets.zoo.rigs import _is_below
from satagraph.datasets.zoo_captions import zoo_clip_of_row, zoo_phrasings

FRAMES = 240  # 8 s: the body goes down and gets up inside the clip


def _clip(kind: str, style: int, seed: int):
    rig = zoo_rigs(["quadruped"], seed=0)[style]
    motion, facts = generate_clip_with_facts(rig, kind, FRAMES, seed=seed)
    return rig, np.asarray(motion.global_positions()), facts


def _hips(pos: np.ndarray) -> np.ndarray:
    """The root's height over the lowest joint, per frame."""
    return pos[:, 0, 1] - pos[:, :, 1].min(axis=1)


@pytest.mark.parametrize("style", [0, 1, 2, 3])
@pytest.mark.parametrize("kind", ["sit", "lie"])
def test_the_body_goes_down_in_place_and_stays_above_the_ground(kind: str, style: int) -> None:
    rig, pos, facts = _clip(kind, style, seed=3)
    hips = _hips(pos)
    standing = hips.max()
    assert hips.min() < (0.6 if kind == "sit" else 0.45) * standing  # well down
    assert pos[:, :, 1].min() > -1e-3  # no joint under the ground
    skel = rig.skeleton
    # the horizontal root moves by the idle's sway only: no travel
    assert np.ptp(pos[:, 0, [0, 2]], axis=0).max() < 0.05 * rig.leg_length
    for leg in rig.legs:  # every foot stays on the ground
        foot = [j for j in range(skel.num_joints) if _is_below(skel, j, leg.foot)]
        assert pos[:, foot, 1].min(axis=1).max() < 0.01 * rig.leg_length
    assert (facts.kind, facts.speed_start, facts.speed_end) == (kind, 0.0, 0.0)


@pytest.mark.parametrize("style", [0, 1, 2, 3])
def test_a_sitting_body_points_its_nose_up_on_straight_fore_legs(style: int) -> None:
    rig, pos, _ = _clip("sit", style, seed=3)
    low = int(np.argmin(_hips(pos)))
    front = [leg for leg in rig.legs if leg.key.endswith("F")]
    shoulders = np.mean([pos[:, leg.upper, 1] for leg in front], axis=0)
    assert shoulders[low] - pos[low, 0, 1] > 0.2 * rig.leg_length  # shoulders above the hips
    assert shoulders[low] > 0.8 * shoulders.max()  # and still up


@pytest.mark.parametrize("style", [0, 1, 2, 3])
def test_a_lying_body_folds_its_legs_and_puts_its_feet_flat(style: int) -> None:
    rig, pos, _ = _clip("lie", style, seed=3)
    low = int(np.argmin(_hips(pos)))
    for leg in rig.legs:
        reach = np.linalg.norm(pos[:, leg.foot] - pos[:, leg.upper], axis=-1)
        assert reach[low] < 0.9 * reach.max()  # folded
        ankle = pos[:, leg.foot, 1]
        assert ankle[low] < 0.6 * ankle[0]  # the ankle comes down: the foot lies flat


def test_lowering_is_drawn_only_when_asked_and_captioned() -> None:
    plain = EndlessZoo(species=["quadruped"])
    assert {plain.sample(0, i, 32).kind for i in range(40)} <= set(CLIP_KINDS["quadruped"])
    asked = EndlessZoo(species=["quadruped"], kinds=["sit", "lie"])
    drawn = [asked.sample(0, i, 32) for i in range(12)]
    assert {s.kind for s in drawn} == {"sit", "lie"}
    texts = {c.text for s in drawn for c in captions_for(s)}
    assert any("sits" in t for t in texts) and any("lies down" in t for t in texts)
    with pytest.raises(ValueError, match="biped can do none of the kinds"):
        EndlessZoo(species=["biped", "quadruped"], kinds=["sit"])
    written = zoo_clip_of_row({"path": "zoo/zoo0-quadruped-abbrev-notail_lie_2.bvh"})
    assert written is not None and written.kind == "lie"
    assert "a quadruped folds its legs and lies down" in zoo_phrasings(written)
