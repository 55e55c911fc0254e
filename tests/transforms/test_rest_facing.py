"""A rig read in its file's rest pose is shown to the model facing +Z."""
from __future__ import annotations

import numpy as np

from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.datasets.zoo.dialects import export_dialect
from satagraph.ops.rotation_numpy import yaw_of
from satagraph.transforms.canonical import body_forward, canonicalize
from satagraph.transforms.rest import restore_rest, shown_rest
from satagraph.transforms.rig_reading import with_rig

UP = np.array([0.0, 1.0, 0.0])


def _walk(up_axis: str, rig: int = 0, seed: int = 0):
    walk = generate_clip(zoo_rigs(["biped"])[rig], "walk", frames=90, seed=seed)
    return canonicalize(with_rig(export_dialect(walk, up_axis), up_axis, "m"), fps=30.0)


def _rest_yaw(skeleton) -> float:
    forward = body_forward(skeleton.rest_positions(), skeleton, UP)
    return float(np.degrees(yaw_of(forward)))


def test_a_rest_facing_away_is_turned_to_face_forward_and_back():
    """Stood up, a -Y-up rig's rest faces -Z (the zoo's -Y dialect is a
    half turn about X): it is shown turned about +Y to face +Z, every
    frame's joints where they were, and the turn is undone on the output;
    a +Y-up rig facing +Z is shown as it is."""
    from satagraph.transforms.rest import FACING_DEGREES, rest_facing_turn
    plain, flipped = _walk("+Y"), _walk("-Y")
    assert abs(_rest_yaw(plain.skeleton)) < 1e-6
    assert rest_facing_turn(plain.skeleton) is None
    shown, undo = shown_rest(plain, "auto")
    assert shown is plain and undo is None
    assert abs(abs(_rest_yaw(flipped.skeleton)) - 180.0) < 1e-6
    shown, undo = shown_rest(flipped, "auto")
    assert undo is not None
    assert abs(_rest_yaw(shown.skeleton)) < 1e-6
    np.testing.assert_allclose(shown.global_positions(), flipped.global_positions(), atol=1e-9)
    back = restore_rest(shown, undo, flipped.skeleton)
    np.testing.assert_allclose(back.global_positions(), flipped.global_positions(), atol=1e-9)
    np.testing.assert_allclose(back.rotations, flipped.rotations, atol=1e-9)
    assert FACING_DEGREES < 90.0


def test_a_retarget_onto_a_rig_facing_away_in_its_rest_walks_forward():
    """A biped walk onto a biped written -Y up was decoded walking
    backwards (the limbs' step correlation -0.93 and the body facing 177
    degrees from where it goes, on ccbase/007_01 and a zoo biped); shown
    its rest facing +Z, it walks as its source does."""
    from satagraph.experiment.train import load_module
    from satagraph.pipelines.inference import retarget_canonical
    from satagraph.pipelines.quality import heading_gap, step_correlation
    module = load_module("builtin").eval()
    source = generate_clip(zoo_rigs(["biped"])[1], "walk", frames=90, seed=3)
    target = with_rig(export_dialect(generate_clip(zoo_rigs(["biped"])[0], "walk", frames=90,
                                                   seed=0), "-Y"), "-Y", "m")
    src, out = retarget_canonical(module, source, target, module.embed)
    assert step_correlation(src, out) > 0.8
    gap = (heading_gap(out) - heading_gap(src) + 180.0) % 360.0 - 180.0
    assert abs(gap) < 20.0
