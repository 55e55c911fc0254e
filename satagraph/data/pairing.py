r"""Cross-skeleton partners within a batch, for unpaired retargeting losses.

Every clip of a :class:`~satagraph.data.FrameBatch` is paired with another
clip of the batch on a different skeleton (another dataset, species or
augmented rig); :func:`partner_batch` builds the frame graphs of the
partners' skeletons with the clips' own lengths, so that a model can decode
each clip's latents onto its partner's rig, and the node indices of the
limb ends (see :mod:`satagraph.semantics.limbs`) that such a
retargeted motion should move like the source's.
"""
from __future__ import annotations

import hashlib
from itertools import accumulate
from typing import List, NamedTuple, Optional

import torch
from torch import Tensor

from satagraph.data.clip import MotionClip
from satagraph.data.collate import FrameBatch, collate_clips
from satagraph.data.features import DYNAMIC_CHANNELS, ROOT_CHANNELS


class Pairing(NamedTuple):
    r"""Clips paired with a partner skeleton (see :func:`partner_batch`).

    Shapes (:math:`B'` paired clips, :math:`K` limb-end samples at frames
    :math:`t \geq 1`):
        - **target**: a :class:`FrameBatch` of :math:`B'` clips
        - **clips**, **partners**: :math:`(B',)` indices into the batch
        - **frames**: :math:`(G',)` source frame graphs, in target order
        - **source_nodes**, **source_prev**: :math:`(K,)` a limb end's node
          in the source batch at frame :math:`t` and :math:`t - 1`
        - **target_nodes**, **target_prev**: :math:`(K,)` the same limb's end
          in :obj:`target`
        - **source_height**, **target_height**: :math:`(K,)` heights of the
          two characters
    """
    target: FrameBatch
    clips: Tensor
    partners: Tensor
    frames: Tensor
    source_nodes: Tensor
    source_prev: Tensor
    target_nodes: Tensor
    target_prev: Tensor
    source_height: Tensor
    target_height: Tensor


def choose_partners(keys: List[tuple],
                    generator: Optional[torch.Generator] = None) -> List[int]:
    """For each clip, a random clip with another skeleton key (``-1``
    where every clip shares its skeleton)."""
    out = []
    for key in keys:
        others = [j for j, other in enumerate(keys) if other != key]
        pick = int(torch.randint(len(others), (1,), generator=generator)) if others else 0
        out.append(others[pick] if others else -1)
    return out


class _Rig(NamedTuple):
    """One clip's skeleton, on the CPU."""
    static: Tensor
    semantic: Tensor
    parents: Tensor
    edge_attr: Tensor


def _rigs(batch: FrameBatch) -> List[_Rig]:
    """Every clip's skeleton, with one device-to-host copy per attribute."""
    frames, joints = batch.clip_num_frames.tolist(), batch.clip_num_joints.tolist()
    static = batch.joint_static.detach().cpu().float().split(joints)
    semantic = batch.joint_semantic.detach().cpu().float().split(joints)
    parent = batch.stream_parent.cpu().split(joints)
    edges = batch.edge_attr.detach().cpu().float().split(
        [2 * (j - 1) * t for j, t in zip(joints, frames)])
    starts = list(accumulate([0] + joints[:-1]))
    return [_Rig(static[k], semantic[k], torch.where(parent[k] < 0, -1, parent[k] - starts[k]),
                 edges[k][:2 * (joints[k] - 1)]) for k in range(len(joints))]


def _motionless(rig: _Rig, num_frames: int, meta: dict) -> MotionClip:
    """A clip of :obj:`num_frames` frames on :obj:`rig`, without motion."""
    num = rig.parents.numel()
    return MotionClip(dynamic=torch.zeros(num_frames, num, DYNAMIC_CHANNELS),
                      root=torch.zeros(num_frames, ROOT_CHANNELS), static=rig.static,
                      semantic=rig.semantic, parents=rig.parents,
                      edge_attr=rig.edge_attr, meta=dict(meta))


def partner_batch(batch: FrameBatch,
                  generator: Optional[torch.Generator] = None) -> Optional[Pairing]:
    r"""Pairs every clip with a clip of another skeleton in :obj:`batch` and
    builds the partners' frame graphs with the clips' lengths.

    Limb ends come from :attr:`FrameBatch.clip_limb_ends` (each clip's
    ``meta["limb_ends"]``, set by :class:`~satagraph.data.MotionDataset`);
    limbs missing on either side are left out.

    Args:
        batch (FrameBatch): The source batch.
        generator (torch.Generator, optional): Random source of the pairing.

    Returns:
        Pairing or None: ``None`` when all clips share one skeleton.
    """
    rigs = _rigs(batch)
    keys = [(str(m.get("skeleton")), tuple(r.parents.tolist()))
            for m, r in zip(batch.meta, rigs)]
    partners = choose_partners(keys, generator)
    clips = [i for i, p in enumerate(partners) if p >= 0]
    if not clips:
        return None
    pairs = [partners[i] for i in clips]
    frames = batch.clip_num_frames.tolist()
    device = batch.x.device
    target = collate_clips([_motionless(rigs[p], frames[i], batch.meta[p])
                            for i, p in zip(clips, pairs)]).to(device)
    frame_mask = torch.isin(batch.frame_clip, torch.tensor(clips, device=device))
    return Pairing(target, torch.tensor(clips, device=device),
                   torch.tensor(pairs, device=device), frame_mask.nonzero().view(-1),
                   *[t.to(device) for t in _limb_nodes(batch, clips, pairs)])


def _limb_nodes(batch: FrameBatch, clips: List[int], partners: List[int]) -> List[Tensor]:
    """Node indices (frames ``t >= 1``) and heights of the paired limb ends."""
    frames, joints = batch.clip_num_frames.tolist(), batch.clip_num_joints.tolist()
    ends, heights = batch.clip_limb_ends.tolist(), batch.clip_height.tolist()
    src_offset = [0]
    for t, j in zip(frames, joints):
        src_offset.append(src_offset[-1] + t * j)
    rows: List[List[Tensor]] = [[] for _ in range(6)]
    tgt_offset = 0
    for i, p in zip(clips, partners):
        time = torch.arange(1, frames[i])
        for a, b in zip(ends[i], ends[p]):
            if a < 0 or b < 0:
                continue
            src = src_offset[i] + time * joints[i] + a
            tgt = tgt_offset + time * joints[p] + b
            for row, value in zip(rows, (src, src - joints[i], tgt, tgt - joints[p],
                                         torch.full(time.shape, heights[i]),
                                         torch.full(time.shape, heights[p]))):
                row.append(value)
        tgt_offset += frames[i] * joints[p]
    if not rows[0]:
        empty = torch.zeros(0, dtype=torch.long)
        return [empty] * 4 + [empty.float()] * 2
    return [torch.cat(row) for row in rows]


class PartnerCollate:
    r"""A ``collate_fn`` that batches clips (:func:`collate_clips`) and
    pairs them with partners (:func:`partner_batch`) in the same step, so
    that the training step finds them ready (``batch.pairing``, ``None``
    when every clip shares one skeleton) and, with DataLoader workers, they
    are built off the training process.

    The pairing is drawn from a generator seeded by :obj:`seed` and the
    clips themselves (their files and first frames), so a batch gets the
    same partners whatever worker or epoch collates it.

    Args:
        seed (int): Seed of the pairing.
    """

    def __init__(self, seed: int = 0) -> None:
        self.seed = int(seed)

    def __call__(self, clips: List[MotionClip]) -> FrameBatch:
        batch = collate_clips(clips)
        key = "|".join(f"{c.meta.get('path', c.meta.get('skeleton'))}@{c.meta.get('start')}"
                       for c in clips)
        seed = int(hashlib.sha1(f"{self.seed}|{key}".encode()).hexdigest()[:15], 16)
        batch.pairing = partner_batch(batch, torch.Generator().manual_seed(seed))
        return batch


def pairing_to(pairing: Pairing, device: torch.device) -> Pairing:
    """:obj:`pairing` with every tensor and the target batch on :obj:`device`."""
    return Pairing(*[value.to(device) for value in pairing])
