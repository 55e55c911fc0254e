"""The zoo's gestures (``bow``, ``wave`` of bipeds; ``sit``, ``lie`` of
quadrupeds in `test_zoo_lowering.py`): what the motion does, how the
endless zoo draws them only when asked, and their captions."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.data.caption_datamodule import zoo_caption_datasets
from satagraph.data.endless import zoo_entry
from satagraph.datasets.captions import captions_for
from satagraph.datasets.zoo import (ALL_KINDS, CLIP_KINDS, GESTURE_KINDS, generate_clip,
                                    generate_clip_with_facts, zoo_rigs)
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.datasets.zoo_captions import zoo_clip_of_row, zoo_phrasings

FRAMES = 120


def _clip(kind: str, style: int = 0, seed: int = 4):
    rig = zoo_rigs(["biped"], seed=0)[style]
    motion, facts = generate_clip_with_facts(rig, kind, FRAMES, seed=seed)
    return rig, np.asarray(motion.global_positions()), facts


def _forward(rig, pos: np.ndarray) -> np.ndarray:
    """The body's facing direction on the ground at frame 0 (from the hips)."""
    left, right = rig.legs[0].upper, rig.legs[1].upper
    ahead = np.cross(pos[0, left] - pos[0, right], [0.0, 1.0, 0.0])
    return ahead / np.linalg.norm(ahead)


def _head(rig) -> int:
    return int(np.argmax(rig.skeleton.rest_positions()[:, 1]))


@pytest.mark.parametrize("style", [0, 1, 2, 3])
def test_a_bow_bends_forward_in_place_and_straightens(style: int) -> None:
    rig, pos, facts = _clip("bow", style)
    head, ahead = _head(rig), _forward(rig, pos)
    lean = (pos[:, head] - pos[:, 0]) @ ahead  # head ahead of the pelvis, metres
    height = np.ptp(pos[0, :, 1])
    assert lean[FRAMES // 2] - lean[0] > 0.15 * height  # bent forward at mid-clip
    assert abs(lean[-1] - lean[0]) < 0.03 * height  # upright again at the end
    assert pos[FRAMES // 2, head, 1] < pos[0, head, 1] - 0.05 * height
    assert np.ptp(pos[:, 0, [0, 2]], axis=0).max() < 0.05 * height  # stays in place
    feet = [leg.foot for leg in rig.legs]
    assert np.ptp(pos[:, feet], axis=0).max() < 0.01  # feet planted
    hands = [int(np.flatnonzero(rig.skeleton.parents == a)[0]) for a in rig.arms]
    below = pos[FRAMES // 2, hands, 1] < pos[FRAMES // 2, [rig.skeleton.parents[a]
                                                           for a in rig.arms], 1]
    assert below.all()  # the arms keep hanging
    assert (facts.kind, facts.speed_start, facts.speed_end) == ("bow", 0.0, 0.0)


@pytest.mark.parametrize("style", [0, 1, 2, 3])
def test_a_wave_raises_one_hand_above_the_head_and_swings_it(style: int) -> None:
    rig, pos, _ = _clip("wave", style)
    head = _head(rig)
    tips = [j for j in range(rig.skeleton.num_joints) if rig.skeleton.end_site[j]
            and any(_descends(rig, j, a) for a in rig.arms)]
    high = pos[:, tips, 1].max(axis=1)
    assert high[FRAMES // 2] > pos[FRAMES // 2, head, 1]  # a hand above the head
    assert high[0] < pos[0, head, 1] - 0.2  # and hanging at the start
    raised = max(tips, key=lambda j: pos[FRAMES // 2, j, 1])
    side = pos[:, raised] - pos[:, 0]
    middle = side[FRAMES // 3: 2 * FRAMES // 3]
    swing = middle - middle.mean(axis=0)
    crossings = np.count_nonzero(np.diff(np.sign(swing[:, 0] + swing[:, 2])) != 0)
    assert crossings >= 2 and np.abs(swing).max() > 0.03  # to and fro, by centimetres
    assert np.ptp(pos[:, 0, [0, 2]], axis=0).max() < 0.05 * np.ptp(pos[0, :, 1])


def _descends(rig, j: int, ancestor: int) -> bool:
    while j >= 0:
        if j == ancestor:
            return True
        j = int(rig.skeleton.parents[j])
    return False


def test_gestures_are_kinds_of_bipeds_and_quadrupeds_only() -> None:
    assert GESTURE_KINDS == {"biped": ("bow", "wave"), "quadruped": ("sit", "lie")}
    assert ALL_KINDS["biped"] == CLIP_KINDS["biped"] + ("bow", "wave")
    assert ALL_KINDS["quadruped"] == CLIP_KINDS["quadruped"] + ("sit", "lie")
    assert all(ALL_KINDS[s] == CLIP_KINDS[s] for s in CLIP_KINDS
               if s not in ("biped", "quadruped"))
    quadruped = zoo_rigs(["quadruped"], seed=0)[0]
    with pytest.raises(ValueError, match="quadruped has no clip kind 'bow'"):
        generate_clip(quadruped, "bow", 30)


def test_the_endless_zoo_draws_gestures_only_when_asked() -> None:
    plain = EndlessZoo(species=["biped"])
    assert {plain.sample(0, i, 32).kind for i in range(40)} <= set(CLIP_KINDS["biped"])
    asked = EndlessZoo(species=["biped"], kinds=["bow", "wave"])
    drawn = [asked.sample(0, i, 32) for i in range(12)]
    assert {s.kind for s in drawn} == {"bow", "wave"}
    mixed = EndlessZoo(species=["biped", "quadruped"], kinds=["walk", "bow"])
    kinds = {(s.species, s.kind) for s in (mixed.sample(0, i, 32) for i in range(24))}
    assert kinds == {("biped", "walk"), ("biped", "bow"), ("quadruped", "walk")}


def test_kinds_a_zoo_cannot_draw_are_refused() -> None:
    with pytest.raises(ValueError, match=r"unknown clip kinds \['curtsy'\]"):
        EndlessZoo(species=["biped"], kinds=["curtsy"])
    with pytest.raises(ValueError, match="quadruped can do none of the kinds"):
        EndlessZoo(species=["biped", "quadruped"], kinds=["bow"])


def test_gesture_captions() -> None:
    sample = EndlessZoo(species=["biped"], kinds=["bow"]).sample(0, 0, 64)
    texts = {c.text for c in captions_for(sample)}
    assert "a person bows" in texts and "a two-legged character bends forward in a bow" in texts
    row = {"path": "zoo/zoo0-biped-mixamo_wave_003.bvh"}
    wave = zoo_clip_of_row(row)
    assert wave is not None and wave.kind == "wave"
    assert "a person waves goodbye with one hand" in zoo_phrasings(wave)


def test_a_source_entry_with_kinds_gives_gesture_windows() -> None:
    spec = zoo_entry({"zoo": "endless", "species": ["biped"], "kinds": ["wave"],
                      "windows_per_epoch": 4})
    assert spec["kinds"] == ["wave"]
    data = zoo_caption_datasets(spec, "train", window=40, min_frames=32, seed=0)[0]
    clip = data[(0, 0)]
    assert clip.meta["kind"] == "wave" and "waves" in clip.meta["text"]


def test_write_zoo_writes_the_kinds_asked_for(tmp_path) -> None:
    from satagraph.datasets.captions import captions_for
    from satagraph.datasets.zoo import write_zoo

    rows = write_zoo(tmp_path, species=["biped"], clips=2, frames=40, kinds=["wave", "bow"])
    assert [r["kind"] for r in rows] == ["bow", "wave"] * 4  # ALL_KINDS' order
    assert all((tmp_path / r["path"]).is_file() for r in rows)
    assert "a person bows" in {c.text for c in captions_for(rows[0])}
    with pytest.raises(ValueError, match="write_zoo: quadruped can do none"):
        write_zoo(tmp_path / "none", species=["biped", "quadruped"], kinds=["bow"])
    assert not (tmp_path / "none").exists()


def test_the_zoo_cli_takes_kinds(tmp_path, capsys) -> None:
    from satagraph.cli import main

    assert main(["zoo", str(tmp_path / "z"), "--species", "biped", "--clips", "1",
                 "--frames", "30", "--kinds", "wave"]) == 0
    assert sorted(p.name for p in (tmp_path / "z" / "biped").iterdir())[0].endswith("_wave.bvh")
    with pytest.raises(SystemExit) as stop:
        main(["zoo", str(tmp_path / "y"), "--kinds", "curtsy"])
    assert stop.value.code == 2
    assert "invalid clip kind: 'curtsy' (choose from walk," in capsys.readouterr().err
    assert not (tmp_path / "y").exists()
