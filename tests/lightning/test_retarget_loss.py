"""The unpaired cross-skeleton retarget term: pairing clips with other
skeletons of the batch, the limb-end velocity loss, and its place in the
LightningModule's losses (real bandai and dog windows)."""
from __future__ import annotations

import pytest
import torch

from satagraph.data.collate import collate_clips
from satagraph.data.features import DYNAMIC_LAYOUT
from satagraph.data.pairing import choose_partners, partner_batch
from satagraph.semantics import LIMBS
from satagraph.losses import limb_velocity_loss


def _mixed_batch(datamodule, per_group: int = 2):
    """Training windows of every skeleton group, interleaved."""
    ds = datamodule.datasets["train"]
    groups = {}
    for i in range(len(ds)):
        groups.setdefault(ds.group(i), []).append(i)
    picks = [idx for members in zip(*[g[:per_group] for g in groups.values()])
             for idx in members]
    return collate_clips([ds[i] for i in picks])


def _local_joint(batch, nodes):
    """Joint index within its skeleton of each node."""
    first = batch.clip_num_joints.cumsum(0) - batch.clip_num_joints
    stream = batch.node_stream[nodes]
    return stream - first[batch.stream_clip[stream]]


def test_dataset_clips_carry_limb_ends_by_description(datamodule):
    batch = _mixed_batch(datamodule)
    names = {"bandai": ["Hand_L", "Hand_R", "Foot_L", "Foot_R"],
             "dog": ["LeftHand", "RightHand", "LeftFoot", "RightFoot"]}
    ds = datamodule.datasets["train"]
    for meta in batch.meta:
        skeleton = next(f.skeleton for f, m in zip(ds.features, ds.files)
                        if m.path == meta["path"])
        assert len(meta["limb_ends"]) == len(LIMBS)
        assert [skeleton.names[j] for j in meta["limb_ends"]] == names[meta["dataset"]]


def test_choose_partners_never_pairs_a_skeleton_with_itself():
    keys = ["a", "b", "a", "c", "b"]
    partners = choose_partners(keys, torch.Generator().manual_seed(0))
    assert all(keys[p] != k for k, p in zip(keys, partners))
    assert choose_partners(["a", "a"]) == [-1, -1]


def test_partner_batch_builds_the_partners_rigs_with_the_clips_lengths(datamodule):
    batch = _mixed_batch(datamodule)
    pairing = partner_batch(batch, torch.Generator().manual_seed(1))
    target = pairing.target
    assert pairing.clips.tolist() == list(range(len(batch.meta)))
    for k, (i, p) in enumerate(zip(pairing.clips.tolist(), pairing.partners.tolist())):
        assert batch.meta[i]["dataset"] != batch.meta[p]["dataset"]
        assert target.clip_num_frames[k] == batch.clip_num_frames[i]
        assert target.clip_num_joints[k] == batch.clip_num_joints[p]
        assert torch.equal(target.joint_static[target.stream_clip == k],
                           batch.joint_static[batch.stream_clip == p])
        assert torch.equal(target.joint_semantic[target.stream_clip == k],
                           batch.joint_semantic[batch.stream_clip == p])
    # z of the paired clips in target order: every target frame has one
    assert torch.equal(batch.frame_time[pairing.frames], target.frame_time)
    # limb-end nodes: same limb, consecutive frames, frames t >= 1
    assert pairing.source_nodes.numel() == 4 * int((batch.clip_num_frames - 1).sum())
    assert torch.equal(batch.node_time[pairing.source_nodes],
                       batch.node_time[pairing.source_prev] + 1)
    assert torch.equal(target.node_time[pairing.target_nodes],
                       batch.node_time[pairing.source_nodes])
    src_limbs = _local_joint(batch, pairing.source_nodes)
    tgt_limbs = _local_joint(target, pairing.target_nodes)
    limb_of = {}
    for node, s_joint, t_joint in zip(pairing.source_nodes.tolist(), src_limbs.tolist(),
                                      tgt_limbs.tolist()):
        clip = int(batch.stream_clip[batch.node_stream[node]])
        k = batch.meta[clip]["limb_ends"].index(s_joint)
        partner = pairing.partners[pairing.clips.tolist().index(clip)]
        assert batch.meta[partner]["limb_ends"][k] == t_joint
        limb_of[k] = True
    assert sorted(limb_of) == [0, 1, 2, 3]


def test_partner_batch_is_none_for_one_skeleton(datamodule):
    ds = datamodule.datasets["train"]
    same = [i for i in range(len(ds)) if ds.group(i) == ds.group(0)][:3]
    assert partner_batch(collate_clips([ds[i] for i in same])) is None


def test_limb_velocity_loss_is_height_normalised(datamodule):
    batch = _mixed_batch(datamodule)
    pairing = partner_batch(batch, torch.Generator().manual_seed(2))
    x = batch.x[:, DYNAMIC_LAYOUT["x"]]
    # a target whose limb ends move exactly like the source's, in heights
    pos = torch.zeros(pairing.target.num_nodes, 3)
    ratio = (pairing.target_height / pairing.source_height)[:, None]
    step = (x[pairing.source_nodes] - x[pairing.source_prev]) * ratio
    order = torch.argsort(pairing.target_nodes)
    for n, prev, d in zip(pairing.target_nodes[order].tolist(),
                          pairing.target_prev[order].tolist(), step[order]):
        pos[n] = pos[prev] + d
    assert limb_velocity_loss(x, pos, pairing) < 1e-8
    moved = pos.clone()
    moved[pairing.target_nodes[0]] += 0.1
    assert limb_velocity_loss(x, moved, pairing) > 1e-4


def _losses_with(module, batch, name: str, weight: float):
    """The module's losses of one forward pass without and with the
    cross-skeleton term :obj:`name` at :obj:`weight`."""
    module.train()
    torch.manual_seed(0)
    out = module(batch)
    plain = module.compute_losses(out, batch)
    module.criterion.weights[name] = weight
    return out, plain, module.compute_losses(out, batch)


def test_module_adds_the_weighted_retarget_term_with_gradients(build_tiny_module,
                                                               datamodule):
    batch = _mixed_batch(datamodule)
    module = build_tiny_module("vae")
    out, plain, losses = _losses_with(module, batch, "retarget", 0.5)
    assert "retarget" not in plain
    assert losses["retarget"] > 0
    assert torch.allclose(losses["loss"], plain["loss"] + 0.5 * losses["retarget"])
    losses["retarget"].backward()
    for part in (module.model.decoder, module.model.encoder):
        grads = [p.grad for p in part.parameters() if p.grad is not None]
        assert grads and any(g.abs().sum() > 0 for g in grads)
    # same global step, same pairing: the term is reproducible
    again = module.compute_losses(out, batch)["retarget"]
    assert torch.equal(again, losses["retarget"])


def test_single_skeleton_batch_logs_a_zero_retarget_term(build_tiny_module, datamodule):
    """Every step logs the same keys (distributed runs sync them)."""
    ds = datamodule.datasets["train"]
    same = [i for i in range(len(ds)) if ds.group(i) == ds.group(0)][:2]
    batch = collate_clips([ds[i] for i in same])
    module = build_tiny_module("vae")
    module.criterion.weights["retarget"] = 0.5
    out = module(batch)
    losses = module.compute_losses(out, batch)
    assert losses["retarget"] == 0
    assert torch.equal(losses["loss"], module.criterion(out, batch, module.normalizer,
                                                        fps=module.fps)["loss"])


def test_partners_are_collated_with_the_batch_and_used_by_the_module(build_tiny_module,
                                                                     datamodule):
    """PartnerCollate pairs a batch the same way whoever collates it; the
    module's retarget term uses those partners, and the data module collates
    them once a module with a retarget weight is set up."""
    from satagraph.data.pairing import PartnerCollate
    ds = datamodule.datasets["train"]
    groups = {}
    for i in range(len(ds)):
        groups.setdefault(ds.group(i), []).append(i)
    clips = [ds[i] for members in zip(*[g[:2] for g in groups.values()]) for i in members]
    batch = PartnerCollate(seed=3)(clips)
    again = PartnerCollate(seed=3)([ds[i] for members in zip(*[g[:2] for g in groups.values()])
                                    for i in members])
    assert torch.equal(batch.pairing.partners, again.pairing.partners)
    assert torch.equal(batch.pairing.target_nodes, again.pairing.target_nodes)
    module = build_tiny_module("vae")
    module.criterion.weights["retarget"] = 0.5
    out = module(batch)
    with_partners = module.compute_losses(out, batch)["retarget"]
    assert torch.equal(module.compute_losses(out, batch)["retarget"], with_partners)
    # a batch without collated partners gets them drawn in the step
    assert module.retarget_loss(out["z"], collate_clips(clips)) > 0
    datamodule.pair_partners = False
    trainer = type("T", (), {"datamodule": datamodule})()
    module._trainer = trainer
    module.setup("fit")
    assert datamodule.pair_partners
    assert isinstance(datamodule.train_dataloader().collate_fn, PartnerCollate)
    datamodule.pair_partners = False


def test_root_transfer_loss_is_zero_for_a_root_moving_alike_in_leg_lengths():
    """Ground speed counts in leg lengths (a 1.8 m biped with 0.9 m legs and
    a 0.6 m quadruped with 0.4 m legs walking alike), the lowest joint in
    heights."""
    from satagraph.losses import root_transfer_loss
    r_s = torch.tensor([[0.3, 0.1, 1.5, 0.9], [0.0, 0.0, 1.2, 0.95]])
    h_s, h_t = torch.tensor([1.8, 1.8]), torch.tensor([0.6, 0.6])
    leg_s, leg_t = torch.tensor([0.9, 0.9]), torch.tensor([0.4, 0.4])
    low_s = torch.tensor([0.0, 0.18])
    alike = torch.cat([r_s[:, :1], r_s[:, 1:3] * (leg_t / leg_s)[:, None], r_s[:, 3:] * 0.5], 1)
    low_t = low_s * h_t / h_s
    # the root's own height is the partner's business: only turn, speed and the lowest joint
    assert root_transfer_loss(r_s, alike, h_s, h_t, low_s, low_t, leg_s, leg_t) < 1e-12
    in_heights = alike.clone()
    in_heights[:, 1:3] = r_s[:, 1:3] * (h_t / h_s)[:, None]  # alike in heights: too slow
    faster = alike.clone()
    faster[:, 2] *= 2
    floating = low_t + 0.1 * h_t
    turning = alike.clone()
    turning[:, 0] += 1.0
    for r_t, low in ((faster, low_t), (alike, floating), (turning, low_t), (in_heights, low_t)):
        assert root_transfer_loss(r_s, r_t, h_s, h_t, low_s, low, leg_s, leg_t) > 0.1


def test_module_adds_the_root_term_with_gradients_to_the_decoder(build_tiny_module,
                                                                 datamodule):
    module = build_tiny_module("vae")
    _, plain, losses = _losses_with(module, _mixed_batch(datamodule), "retarget_root", 0.3)
    assert "retarget" not in losses and losses["retarget_root"] > 0
    assert torch.allclose(losses["loss"], plain["loss"] + 0.3 * losses["retarget_root"])
    losses["retarget_root"].backward()
    grads = [p.grad for p in module.model.decoder.parameters() if p.grad is not None]
    assert grads and any(g.abs().sum() > 0 for g in grads)


def test_module_logs_the_carriage_term_with_gradients_to_the_decoder(build_tiny_module,
                                                                     datamodule):
    """``retarget_carriage`` alone switches the cross-skeleton decoding on
    (partners collated for it too); the step logs it and adds it weighted."""
    module = build_tiny_module("vae")
    batch = _mixed_batch(datamodule)
    _, plain, losses = _losses_with(module, batch, "retarget_carriage", 4.0)
    assert module._retarget_weight() == 4.0
    assert "retarget" not in losses and "retarget_root" not in losses
    assert losses["retarget_carriage"] > 0
    assert torch.allclose(losses["loss"], plain["loss"] + 4.0 * losses["retarget_carriage"])
    logged = {}
    module.log_dict = lambda terms, **kwargs: logged.update(terms)
    module.log = lambda name, value, **kwargs: logged.update({name: value})
    module._step(batch, "train")
    assert logged["train/retarget_carriage"] > 0
    losses["retarget_carriage"].backward()
    grads = [p.grad for p in module.model.decoder.parameters() if p.grad is not None]
    assert grads and any(g.abs().sum() > 0 for g in grads)


def test_carriage_loss_is_zero_for_each_partners_own_window(datamodule):
    """Real windows (Bandai and the dog, equal lengths): positions on the
    partners' rigs that are the partners' own windows carry as they do (0); every
    joint but the root raised by a tenth of the height reads 0.01 of each
    rig's non-root share."""
    from satagraph.losses import carriage_loss
    batch = _mixed_batch(datamodule)
    assert len(set(batch.clip_num_frames.tolist())) == 1
    pairing = partner_batch(batch, torch.Generator().manual_seed(4))
    x = batch.x[:, DYNAMIC_LAYOUT["x"]]
    own = torch.cat([x[batch.node_clip == p] for p in pairing.partners.tolist()])
    assert carriage_loss(own, x, pairing.target, batch, pairing.partners) < 1e-10
    # every joint but the root a tenth of the partner's height higher above it
    raised = own + 0.1 * pairing.target.heights("node")[:, None] * torch.tensor([0, 1.0, 0])
    raised[pairing.target.root_node] = own[pairing.target.root_node]
    joints = pairing.target.clip_num_joints.double()
    expected = (0.01 * (joints - 1) / joints).mean()
    loss = carriage_loss(raised, x, pairing.target, batch, pairing.partners)
    assert loss.item() == pytest.approx(expected.item(), rel=1e-4)
