"""Test-time refinement of the latent: ``reconstruct --refine`` and
:meth:`~satagraph.lightning.MotionAutoencoderModule.refine_latent`."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.io.weights import builtin_path
from satagraph.motion import Motion

pytestmark = pytest.mark.skipif(not builtin_path().is_file(),
                                reason="no built-in weights ship in this checkout")


@pytest.fixture(scope="module")
def module():
    from satagraph.experiment.train import load_module
    return load_module("builtin").eval()


@pytest.fixture(scope="module")
def trot() -> Motion:
    return generate_clip(zoo_rigs(["quadruped"], seed=7)[0], "trot", frames=48, seed=5)


def _error(source: Motion, output: Motion) -> float:
    """Mean global joint position error over the source's height."""
    a, b = source.global_positions(), output.global_positions()
    return float(np.linalg.norm(a - b, axis=-1).mean() / source.height())


def _batch(module, motion: Motion):
    """A physical batch of one window of a canonical motion, as inference builds it."""
    from satagraph.data.collate import collate_clips
    from satagraph.pipelines.inference import source_features
    from satagraph.transforms.canonical import canonicalize
    _, feats = source_features(canonicalize(motion, fps=30.0), "auto")
    embedding = module.embed(feats.skeleton)
    return collate_clips([feats.to_clip(0, 32, embedding)])


@pytest.mark.slow
def test_refined_reconstruction_is_closer_to_its_clip(module, trot) -> None:
    from satagraph.pipelines.inference import reconstruct_canonical
    errors = []
    for refine in (0, 20):
        src, out = reconstruct_canonical(module, trot, module.embed, ground=False, mirror=False,
                                         two_rests=False, refine=refine)
        errors.append(_error(src, out))
    assert errors[1] < 0.85 * errors[0]  # 0.053 -> 0.043 of the height


def test_refine_latent_lowers_the_loss_and_leaves_the_weights_alone(module, trot) -> None:
    batch = _batch(module, trot)
    source = module.normalize_batch(batch)
    before = {k: v.clone() for k, v in module.state_dict().items()}

    def loss(z: torch.Tensor) -> float:
        with torch.no_grad():
            out = module.denormalize_output(dict(enc, z=z, **module.decode(z, source)), batch)
            return float(module.criterion(out, batch, module.normalizer)["loss"])

    with torch.no_grad():
        enc = module.encode(source)
        z = module.refine_latent(enc, source, batch, steps=6)
    assert z.shape == enc["z"].shape and not z.requires_grad
    assert loss(z) < 0.9 * loss(enc["z"])
    assert all(p.grad is None for p in module.parameters())
    assert all(torch.equal(before[k], v) for k, v in module.state_dict().items())
    same = module(batch, refine=6)
    assert torch.allclose(same["z"], z, atol=1e-4)  # forward(refine=) is the same fit


@pytest.mark.parametrize("refine, said", [(-1, "0 or more"), (True, "whole number"),
                                          (2.5, "whole number")])
def test_bad_refine_is_one_line_before_any_work(module, trot, refine, said) -> None:
    from satagraph.pipelines.inference import reconstruct_motion
    with pytest.raises(ValueError, match=said):
        reconstruct_motion(module, trot, refine=refine)


def test_a_module_that_cannot_refine_is_refused_by_name() -> None:
    from satagraph.pipelines.inference import check_settings

    class Fixed(torch.nn.Module):
        pass
    check_settings(Fixed(), 64, 16, "auto", False, refine=0)
    with pytest.raises(ValueError, match="a Fixed cannot fit its latent"):
        check_settings(Fixed(), 64, 16, "auto", False, refine=3)


def test_progress_hears_of_every_window_of_every_reading(module, trot) -> None:
    from satagraph.pipelines.inference import reconstruct_motion, window_plan
    heard: list = []
    reconstruct_motion(module, trot, window=16, overlap=4, mirror=True, refine=1,
                       progress=heard.append)
    windows = len(window_plan(trot.num_frames, 16, 4))
    assert windows > 1 and sum(heard) == 2 * windows  # the clip and its mirror image
    assert all(0 < n <= 16 for n in heard)  # one call a batch of at most 16 windows
