"""The Python API checks what the command line checks: a loaded model, a
motion where a motion is expected, a valid clip, a duration in range."""
from __future__ import annotations

import pytest

from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.experiment.train import load_module
from satagraph.motion import require_motion


@pytest.fixture(scope="module")
def walk():
    return generate_clip(zoo_rigs(["biped"])[0], "walk", frames=40, seed=1)


def test_a_path_where_a_motion_is_expected_says_how_to_read_it(walk) -> None:
    from satagraph.transforms.canonical import canonicalize
    assert require_motion(walk) is walk
    with pytest.raises(TypeError, match=r"expected a satagraph Motion, got str; read it "
                       r"first: satagraph.io.read_bvh\('walk.bvh'\)"):
        canonicalize("walk.bvh")


def test_retarget_and_reconstruct_check_their_inputs_as_the_cli_does(walk) -> None:
    from satagraph.data.validate import MotionValidationError
    from satagraph.pipelines.inference import reconstruct_motion, retarget_motion
    module = load_module("builtin")
    assert not module.training  # loaded for inference: the same input decodes the same
    with pytest.raises(TypeError, match="expected a loaded model, got 'builtin'"):
        retarget_motion("builtin", walk, walk)
    with pytest.raises(MotionValidationError, match="1 frame.*at least 2 are needed"):
        reconstruct_motion(module, walk.slice(0, 1))
    one_joint = walk.with_(skeleton=walk.skeleton.subset([0]), rotations=walk.rotations[:, :1],
                           translations=walk.translations[:, :1])
    with pytest.raises(MotionValidationError, match="at least two joints"):
        retarget_motion(module, walk, one_joint)


def test_a_rig_built_in_code_without_channels_is_told_how_to_give_them(walk) -> None:
    """A Skeleton built from names, parents and offsets (its channels are
    optional) was refused by ``reconstruct_motion`` as a rig 'no motion can
    be written onto', with nothing written and no word of what to add."""
    from satagraph.data.validate import MotionValidationError
    from satagraph.motion import Motion
    from satagraph.pipelines.inference import reconstruct_motion
    from satagraph.skeleton import Skeleton
    skel = walk.skeleton
    bare = Skeleton(list(skel.names), skel.parents, skel.offsets)
    motion = Motion(bare, walk.rotations, walk.translations, fps=walk.fps)
    with pytest.raises(MotionValidationError, match=r"<motion>: its root joint 'Hips' has no "
                       r"CHANNELS.*a Skeleton built in code: give it channels"):
        reconstruct_motion(load_module("builtin"), motion)


@pytest.mark.parametrize("seconds", [-1.0, 0.0, 1000.0, float("nan")])
def test_generate_on_refuses_a_duration_generate_refuses(walk, seconds: float) -> None:
    from satagraph.pipelines.generate import generate_on, load_generator
    with pytest.raises(ValueError, match="between 0.1 and 60 seconds"):
        generate_on(load_generator("builtin"), "a person walks", walk, seconds=seconds)


def test_the_text_to_motion_module_is_exported_with_the_others() -> None:
    from satagraph.lightning import TextToMotionModule, __all__
    from satagraph.lightning.text_to_motion import TextToMotionModule as where
    assert TextToMotionModule is where and "TextToMotionModule" in __all__


def test_a_checkpoint_of_an_unregistered_module_names_the_file(tmp_path) -> None:
    """A subclass registered in code this process has not run: the error
    names the file and says to import that code first."""
    import copy

    import torch

    from satagraph.io.checkpoint import CheckpointError
    module = load_module("builtin")
    hparams = copy.deepcopy(dict(module.hparams))
    hparams["meta"] = dict(hparams["meta"], module="my_module")
    path = tmp_path / "mine.ckpt"
    torch.save({"state_dict": module.state_dict(), "hyper_parameters": hparams}, path)
    with pytest.raises(CheckpointError, match=f"{path}: a 'my_module' model, which is not "
                       "registered here"):
        load_module(str(path))
