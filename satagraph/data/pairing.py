r"""Cross-skeleton partners within a batch, for unpaired retargeting losses.

Every clip of a :class:`~satagraph.data.FrameBatch` is paired with another
clip of the batch on a different skeleton (another dataset, species or
augmented rig); :func:`partner_batch` builds the frame graphs of the
partners' skeletons with the clips' own lengths, so that a model can decode
each clip's latents onto its partner's rig, and the node indices of the
limb ends (see :mod:`satagraph.data.semantics.limbs`) that such a
retargeted motion should move like the source's.
"""
from __future__ import annotations

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


def _skeleton_keys(batch: FrameBatch, parents: List[List[int]]) -> List[tuple]:
    return [(str(m.get("skeleton")), tuple(p)) for m, p in zip(batch.meta, parents)]


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


def skeleton_clip(batch: FrameBatch, clip: int, num_frames: int,
                  parents: List[int]) -> MotionClip:
    """A motionless clip of :obj:`num_frames` frames on the skeleton of the
    batch's clip :obj:`clip` (static and semantic features, bones, meta)."""
    streams = (batch.stream_clip == clip).nonzero().view(-1).cpu()
    num = len(parents)
    frames = batch.clip_num_frames.cpu()
    joints = batch.clip_num_joints.cpu()
    edge_start = int(((joints - 1) * 2 * frames)[:clip].sum())
    return MotionClip(
        dynamic=torch.zeros(num_frames, num, DYNAMIC_CHANNELS),
        root=torch.zeros(num_frames, ROOT_CHANNELS),
        static=batch.joint_static[streams].detach().cpu().float(),
        semantic=batch.joint_semantic[streams].detach().cpu().float(),
        parents=torch.tensor(parents),
        edge_attr=batch.edge_attr[edge_start:edge_start + 2 * (num - 1)].detach().cpu().float(),
        meta=dict(batch.meta[clip]))


def partner_batch(batch: FrameBatch,
                  generator: Optional[torch.Generator] = None) -> Optional[Pairing]:
    r"""Pairs every clip with a clip of another skeleton in :obj:`batch` and
    builds the partners' frame graphs with the clips' lengths.

    Limb ends come from each clip's ``meta["limb_ends"]`` (set by
    :class:`~satagraph.data.MotionDataset`); limbs missing on either side are
    left out.

    Args:
        batch (FrameBatch): The source batch.
        generator (torch.Generator, optional): Random source of the pairing.

    Returns:
        Pairing or None: ``None`` when all clips share one skeleton.
    """
    parents = _local_parents(batch)
    partners = choose_partners(_skeleton_keys(batch, parents), generator)
    clips = [i for i, p in enumerate(partners) if p >= 0]
    if not clips:
        return None
    frames = batch.clip_num_frames.tolist()
    target = collate_clips([skeleton_clip(batch, partners[i], frames[i], parents[partners[i]])
                            for i in clips]).to(batch.x.device)
    index = _limb_nodes(batch, target, clips, [partners[i] for i in clips])
    device = batch.x.device
    frame_mask = torch.isin(batch.frame_clip, torch.tensor(clips, device=device))
    return Pairing(target, torch.tensor(clips, device=device),
                   torch.tensor([partners[i] for i in clips], device=device),
                   frame_mask.nonzero().view(-1), *[t.to(device) for t in index])


def _local_parents(batch: FrameBatch) -> List[List[int]]:
    """Each clip's parent list (local joint indices)."""
    joints = batch.clip_num_joints.tolist()
    parent = batch.stream_parent.cpu()
    out, start = [], 0
    for num in joints:
        local = parent[start:start + num]
        out.append(torch.where(local < 0, -1, local - start).tolist())
        start += num
    return out


def _limb_nodes(batch: FrameBatch, target: FrameBatch, clips: List[int],
                partners: List[int]) -> List[Tensor]:
    """Node indices (frames ``t >= 1``) and heights of the paired limb ends."""
    frames, joints = batch.clip_num_frames.tolist(), batch.clip_num_joints.tolist()
    src_offset = [0]
    for t, j in zip(frames, joints):
        src_offset.append(src_offset[-1] + t * j)
    rows: List[List[Tensor]] = [[] for _ in range(6)]
    tgt_offset = 0
    for i, p in zip(clips, partners):
        time = torch.arange(1, frames[i])
        ends_i, ends_p = batch.meta[i].get("limb_ends", ()), batch.meta[p].get("limb_ends", ())
        for a, b in zip(ends_i, ends_p):
            if a < 0 or b < 0:
                continue
            src = src_offset[i] + time * joints[i] + a
            tgt = tgt_offset + time * joints[p] + b
            for row, value in zip(rows, (src, src - joints[i], tgt, tgt - joints[p],
                                         _full(time, batch.meta[i]),
                                         _full(time, batch.meta[p]))):
                row.append(value)
        tgt_offset += frames[i] * joints[p]
    if not rows[0]:
        empty = torch.zeros(0, dtype=torch.long)
        return [empty] * 4 + [empty.float()] * 2
    return [torch.cat(row) for row in rows]


def _full(time: Tensor, meta: dict) -> Tensor:
    return torch.full(time.shape, float(meta.get("height", 1.0)))
