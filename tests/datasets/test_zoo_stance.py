"""The zoo's stance: how far a rig's legs stretch when it stands
(``ZooRig.stance``), and the endless zoo's per-species ``stance_bend``."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.datasets.zoo.motions import generate_clip_with_facts
from satagraph.datasets.zoo.rigs import stance_of_bend
from satagraph.datasets.zoo.species import _BUILDERS
from satagraph.pipelines.quality import contact, knee_bend
from satagraph.transforms.canonical import canonicalize


def _biped(bend=None):
    rig = _BUILDERS["biped"]("mixamo", np.random.default_rng(2), "stance")
    return rig if bend is None else replace(rig, stance=stance_of_bend(bend))


def test_stance_of_bend_is_the_stretch_of_two_equal_bones():
    assert stance_of_bend(0.0) == 1.0
    assert stance_of_bend(36.0) == pytest.approx(0.951, abs=1e-3)  # the zoo's 0.95
    assert stance_of_bend(90.0) == pytest.approx(np.sqrt(0.5))


@pytest.mark.parametrize("bend", [0.0, 18.0, 30.0])
def test_a_biped_idles_with_its_knees_bent_as_its_stance_says(bend):
    """Standing, the knees bend by the stance's angle (a knee never quite
    straightens: 5 degrees at least), a few degrees more as a bent-legged
    body breathes; the zoo's own stance reads 40."""
    motion, _ = generate_clip_with_facts(_biped(bend), "idle", frames=45, seed=3)
    assert max(bend, 5.1) - 1.0 < knee_bend(motion) < max(bend, 5.1) + 5.0
    motion, _ = generate_clip_with_facts(_biped(), "idle", frames=45, seed=3)
    assert 36.0 < knee_bend(motion) < 44.0


def test_a_straight_legged_walker_keeps_its_feet_planted():
    """Rising over each planted leg changes the knees, not the contacts:
    the feet slide and hover as at the zoo's stance."""
    for kind in ("walk", "run", "turn"):
        straight, _ = generate_clip_with_facts(_biped(0.0), kind, frames=60, seed=1)
        crouched, _ = generate_clip_with_facts(_biped(), kind, frames=60, seed=1)
        assert knee_bend(straight) < 12.0 < 35.0 < knee_bend(crouched)
        assert np.allclose(contact(canonicalize(straight)), contact(canonicalize(crouched)),
                           atol=0.01)


def test_stance_bend_changes_only_the_named_species_stance():
    """A sample keeps its rig, clip kind, rest and names; only the named
    species' motion changes, and the same key draws the same bend."""
    plain = EndlessZoo(species=["biped", "bird"], seed=5)
    upright = EndlessZoo(species=["biped", "bird"], seed=5, stance_bend={"biped": [0, 10]})
    for index in range(len(plain.train_plans)):
        a, b = plain.sample(2, index, 30), upright.sample(2, index, 30)
        assert (a.species, a.kind, a.rest, a.noise) == (b.species, b.kind, b.rest, b.noise)
        assert a.motion.skeleton.names == b.motion.skeleton.names
        assert np.array_equal(a.motion.skeleton.offsets, b.motion.skeleton.offsets)
        same = np.array_equal(a.motion.rotations, b.motion.rotations)
        assert same == (a.species == "bird")
        again = upright.sample(2, index, 30)
        assert np.array_equal(again.motion.rotations, b.motion.rotations)


@pytest.mark.parametrize("spec, match", [
    ({"centaur": [0, 10]}, "unknown species 'centaur'"),
    ({"biped": [20, 10]}, r"\[20, 10\] is not a range of knee bends"),
    ({"biped": [0, 95]}, "0 <= low <= high < 90"),
])
def test_stance_bend_refuses_what_it_cannot_draw(spec, match):
    with pytest.raises(ValueError, match=match):
        EndlessZoo(species=["biped"], stance_bend=spec)


def test_satagraph_zoo_stance_bend_writes_upright_bipeds(tmp_path, capsys):
    """``satagraph zoo --stance-bend 8`` writes bipeds that idle on nearly
    straight knees (the zoo's own: 40); a bend it cannot draw, or one asked
    of the dialect benchmark, is a one-line error."""
    from satagraph.cli import main
    from satagraph.io import read_bvh
    args = ["zoo", "--species", "biped", "--clips", "1", "--kinds", "idle", "--frames", "30"]
    assert main(args + ["--stance-bend", "8", str(tmp_path / "up")]) == 0
    assert main(args + [str(tmp_path / "zoo")]) == 0
    name = "biped/zoo0-biped-mixamo_idle.bvh"
    assert knee_bend(read_bvh(tmp_path / "up" / name)) < 14.0
    assert knee_bend(read_bvh(tmp_path / "zoo" / name)) > 35.0
    capsys.readouterr()
    assert main(args + ["--stance-bend", "95", str(tmp_path / "bad")]) == 2
    assert "stance_bend is a knee bend in degrees" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()
    assert main(["zoo", "--dialect-variants", "--stance-bend", "8", str(tmp_path / "d")]) == 2
    assert "not drawn with --dialect-variants" in capsys.readouterr().err
