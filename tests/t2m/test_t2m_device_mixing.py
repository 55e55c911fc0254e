"""The text-to-motion module on a second device, emulated without one
(:class:`~tests.device_emulation.HostTracker`): its losses (frame and banked
batches), generation and the autoencoder's transfer mix no host tensor
with the model's."""
from __future__ import annotations

import torch

from tests.device_emulation import HostTracker
from tests.t2m.conftest import build_t2m, zoo_batch


def test_the_losses_make_nothing_on_the_host(autoencoder_ckpt):
    module = build_t2m(autoencoder_ckpt).train()
    batch = zoo_batch(5, mirror=0.5)
    banked = module.bank_batch(batch)
    banked = banked.collate(list(range(len(banked))))
    with HostTracker() as tracker:
        for each in (batch, banked):
            module.compute_losses(each, torch.Generator().manual_seed(0))["loss"].backward()
    assert tracker.mixes == []


def test_generation_and_transfer_mix_nothing_with_the_model(t2m_ckpt, zoo_skeletons):
    """Only the model's weights start on the device: files, rigs and caches
    are read on the host and must be moved before they meet them."""
    from satagraph.io import read_bvh
    from satagraph.pipelines import generate as G
    from satagraph.pipelines.inference import static_features, transfer
    from satagraph.data.features import motion_to_features
    from satagraph.transforms.canonical import canonicalize
    module = G.load_generator(str(t2m_ckpt))
    biped = read_bvh(str(zoo_skeletons["biped"]))
    quadruped = canonicalize(read_bvh(str(zoo_skeletons["quadruped"])))
    with HostTracker(module) as tracker:
        G.generate_on(module, "a person walks", biped, None, 0, G.GenerationSettings(rerank=2))
        G.generate_on(module, None, biped, 1.0, 0)
        transfer(module.autoencoder, motion_to_features(canonicalize(biped)),
                 static_features(quadruped))
    assert tracker.mixes == []
