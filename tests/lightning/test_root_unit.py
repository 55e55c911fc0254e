"""``data.root_unit``: the root's ground speed and height in leg lengths
instead of character heights (the normaliser, its checkpoints, the data
module and a module's decoding onto another body)."""
from __future__ import annotations

import copy

import pytest
import torch

from satagraph.data.normalizer import FeatureNormalizer
from satagraph.experiment.train import build_datamodule


def test_root_lengths_are_divided_by_the_leg_and_the_rest_by_the_height():
    norm = FeatureNormalizer(root_unit="leg")  # unfitted: mean 0, std 1
    assert norm.root_unit == "leg"
    root = torch.tensor([[0.3, 1.0, -2.0, 0.8]])
    height, leg = torch.tensor([2.0]), torch.tensor([0.5])
    z = norm.normalize(root, "root", height, leg)
    # yaw rate untouched; x/z speed and root height in leg lengths
    torch.testing.assert_close(z, torch.tensor([[0.3, 2.0, -4.0, 1.6]]))
    torch.testing.assert_close(norm.denormalize(z, "root", height=height, leg=leg), root)
    static = torch.ones(1, 6)
    torch.testing.assert_close(norm.normalize(static, "static", height, leg), static / 2.0)
    assert FeatureNormalizer().normalize(root, "root", height, leg)[0, 1] == 0.5  # heights


def test_leg_unit_needs_leg_lengths_and_rejects_unknown_units():
    with pytest.raises(ValueError, match="pass leg="):
        FeatureNormalizer(root_unit="leg").normalize(torch.ones(1, 4), "root",
                                                     torch.ones(1))
    with pytest.raises(ValueError, match="root_unit must be one of"):
        FeatureNormalizer(root_unit="metre")


def test_root_unit_travels_in_the_state_dict_and_old_states_read_heights():
    state = FeatureNormalizer(root_unit="leg").state_dict()
    other = FeatureNormalizer()
    other.load_state_dict(state)
    assert other.root_unit == "leg"
    old = {k: v for k, v in FeatureNormalizer().state_dict().items() if k != "root_in_legs"}
    leg_norm = FeatureNormalizer(root_unit="leg")
    leg_norm.load_state_dict(old)
    assert leg_norm.root_unit == "height"


def test_data_root_unit_reaches_the_fitted_normaliser(_base_config):
    cfg = copy.deepcopy(_base_config)
    cfg["data"]["root_unit"] = "leg"
    dm = build_datamodule(cfg)
    dm.setup("fit")
    assert dm.normalizer.root_unit == "leg" and bool(dm.normalizer.fitted)
    feats = dm.datasets["train"].features
    # speeds in leg lengths: the fitted spread of the x/z speed is the
    # height-unit spread scaled by the files' height / leg ratios
    heights = FeatureNormalizer().fit(feats).root_std[1:3]
    ratio = dm.normalizer.root_std[1:3] / heights
    bounds = sorted(f.height / f.leg_length for f in feats)
    assert bool((ratio > 0.9 * bounds[0]).all() and (ratio < 1.1 * bounds[-1]).all())
    cfg["data"]["root_unit"] = "feet"
    with pytest.raises(ValueError, match="data.root_unit"):
        build_datamodule(cfg)


def test_a_latent_decoded_onto_longer_legs_travels_further(build_tiny_module, datamodule,
                                                           train_batch):
    """Leg unit: the same latent decoded onto the same body with legs read
    twice as long moves its root twice as far a second; height unit: the
    leg does not matter."""
    module = build_tiny_module("vae").eval()
    for unit, factor in (("leg", 2.0), ("height", 1.0)):
        module.normalizer.root_in_legs.fill_(unit == "leg")
        longer = copy.copy(train_batch)
        longer.clip_leg = train_batch.clip_leg * 2.0
        with torch.no_grad():
            z = module.encode(module.normalize_batch(train_batch))["z"]
            speeds = [module.denormalize_output(module.decode(
                z, module.normalize_batch(target)), target)["r"][:, 1:3]
                for target in (train_batch, longer)]
        torch.testing.assert_close(speeds[1], factor * speeds[0])


def test_inference_targets_carry_their_leg_length():
    """A decoding target built for inference (retarget, generate) carries
    its character's leg length, which a leg-unit model scales its root by
    (collation would otherwise assume half the height)."""
    from satagraph.data import motion_to_features
    from satagraph.data.collate import collate_clips
    from satagraph.data.examples import example_motion
    from satagraph.pipelines.inference import target_clip
    from satagraph.transforms import canonicalize
    import dataclasses
    feats = motion_to_features(canonicalize(example_motion(), unit_scale=1.0))
    feats = dataclasses.replace(feats, height=3.0 * feats.height)  # leg != half the height
    batch = collate_clips([target_clip(feats, 5, None)])
    assert feats.leg_length < 0.4 * feats.height
    torch.testing.assert_close(batch.legs("frame"), torch.full((5,), feats.leg_length))
