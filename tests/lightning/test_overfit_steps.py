"""The whole retargeting path can learn a walk: the pretrain_zoo model,
trained on windows of one zoo biped walk, reconstructs it with the legs in
step (what benchmarks/pretrained.py measures on the built-in model)."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from satagraph.experiment.config import load_config
from satagraph.data import motion_to_features
from satagraph.transforms import canonicalize
from satagraph.data.collate import collate_clips
from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.pipelines.inference import reconstruct_canonical
from satagraph.pipelines.quality import retarget_quality
from satagraph.experiment.train import module_class


def _fit(module, batch, steps: int) -> None:
    opt = torch.optim.Adam(module.parameters(), lr=1e-3)
    module.train()
    for _ in range(steps):
        loss = module.compute_losses(module(batch), batch)["loss"]
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(module.parameters(), 0.5)
        opt.step()
    module.eval()


@pytest.mark.slow
def test_pretrain_model_learns_one_walk_in_step() -> None:
    torch.manual_seed(0)
    cfg = load_config("pretrain_zoo")
    motion = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=64, seed=1)
    module = module_class(cfg["module"])(model=cfg["model"], loss=cfg["loss"],
                                         meta={"semantic_encoder": "offline", "window": 32})
    feats = motion_to_features(canonicalize(motion, fps=30.0))
    module.normalizer.fit([feats])
    semantic = module.embed(feats.skeleton)
    batch = collate_clips([feats.to_clip(a, a + 32, semantic) for a in (0, 16, 32)])

    src, before = reconstruct_canonical(module, motion)
    assert retarget_quality(src, before, ("steps",))["steps"] < 0.5
    _fit(module, batch, 150)
    src, after = reconstruct_canonical(module, motion)
    quality = retarget_quality(src, after, ("steps", "travel"))
    error = np.linalg.norm(src.global_positions() - after.global_positions(), axis=-1)
    assert quality["steps"] > 0.9
    assert 0.9 < quality["travel"] < 1.1
    assert error.mean() / src.height() < 0.06
