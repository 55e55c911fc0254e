"""to_temporal_streams / from_temporal_streams on mixed skeletons and lengths."""
from __future__ import annotations

from typing import List, Sequence, Tuple

import pytest
import torch

from satagraph.data import collate_clips
from satagraph.data.clip import MotionClip
from satagraph.ops import from_temporal_streams, to_temporal_streams

MIXED = ((5, 3), (12, 7), (5, 4))  # (joints, frames)


def random_clip(num_joints: int, num_frames: int, gen: torch.Generator) -> MotionClip:
    """A clip on a random tree skeleton: parents[j] uniform in [0, j)."""
    par = [-1] + [int(torch.randint(0, j, (1,), generator=gen)) for j in range(1, num_joints)]
    return MotionClip(
        dynamic=torch.randn(num_frames, num_joints, 4, generator=gen),
        root=torch.randn(num_frames, 4, generator=gen),
        static=torch.randn(num_joints, 6, generator=gen),
        semantic=torch.zeros(num_joints, 0),
        parents=torch.tensor(par),
        edge_attr=torch.randn(2 * (num_joints - 1), 2, generator=gen))


def make_batch(specs: Sequence[Tuple[int, int]] = MIXED, seed: int = 0):
    gen = torch.Generator().manual_seed(seed)
    clips: List[MotionClip] = [random_clip(j, t, gen) for j, t in specs]
    return clips, collate_clips(clips)


@pytest.mark.parametrize("specs", [MIXED, ((5, 6), (12, 6)), ((7, 5),)])
def test_round_trip(specs):
    _, batch = make_batch(specs)
    x = torch.randn(batch.num_nodes, 9)
    streams, mask = to_temporal_streams(x, batch)
    assert streams.shape == (batch.num_streams, batch.max_time, 9)
    assert mask.shape == (batch.num_streams, batch.max_time) and mask.dtype == torch.bool
    assert torch.equal(from_temporal_streams(streams, batch), x)
    assert (streams[~mask] == 0).all()
    assert torch.equal(to_temporal_streams(from_temporal_streams(streams, batch), batch)[0],
                       streams)


def test_placement_and_mask():
    clips, batch = make_batch()
    streams, mask = to_temporal_streams(batch.x, batch)
    offset = 0
    for clip in clips:
        num_joints, num_frames = clip.num_joints, clip.num_frames
        block = streams[offset:offset + num_joints]
        assert torch.equal(block[:, :num_frames], clip.dynamic.transpose(0, 1))
        assert (block[:, num_frames:] == 0).all()
        assert mask[offset:offset + num_joints, :num_frames].all()
        assert not mask[offset:offset + num_joints, num_frames:].any()
        offset += num_joints
    assert int(mask.sum()) == batch.num_nodes


def test_uniform_batch_is_a_transpose():
    clips, batch = make_batch(((6, 5), (6, 5), (6, 5)))
    streams, mask = to_temporal_streams(batch.x, batch)
    ref = torch.stack([c.dynamic for c in clips]).transpose(1, 2).reshape(18, 5, -1)
    assert torch.equal(streams, ref) and mask.all()


def test_gradcheck():
    _, batch = make_batch(((3, 2), (4, 3)))
    x = torch.randn(batch.num_nodes, 2, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda v: to_temporal_streams(v, batch)[0], (x,))
    s = torch.randn(batch.num_streams, batch.max_time, 2, dtype=torch.float64,
                    requires_grad=True)
    assert torch.autograd.gradcheck(lambda v: from_temporal_streams(v, batch), (s,))


def test_padding_gets_no_gradient():
    _, batch = make_batch()
    s = torch.randn(batch.num_streams, batch.max_time, 3, requires_grad=True)
    from_temporal_streams(s, batch).sum().backward()
    _, mask = to_temporal_streams(torch.zeros(batch.num_nodes, 1), batch)
    assert torch.equal(s.grad[..., 0] != 0, mask)


def test_perturbing_one_frame_is_local():
    clips, batch = make_batch()
    clip_id, frame = 1, 4
    base, _ = to_temporal_streams(batch.x, batch)
    x = batch.x.clone()
    start = clips[0].num_frames * clips[0].num_joints + frame * clips[1].num_joints
    x[start:start + clips[1].num_joints] += 1.0
    changed = (to_temporal_streams(x, batch)[0] != base).any(-1)
    expected = torch.zeros_like(changed)
    offset = clips[0].num_joints
    expected[offset:offset + clips[clip_id].num_joints, frame] = True
    assert torch.equal(changed, expected)


def test_dtype_is_kept():
    _, batch = make_batch()
    x = torch.randn(batch.num_nodes, 2, dtype=torch.float64)
    streams, _ = to_temporal_streams(x, batch)
    assert streams.dtype == torch.float64
    assert from_temporal_streams(streams, batch).dtype == torch.float64


def test_features_of_another_batch_are_one_line():
    """Node features or streams of the wrong size raise a ValueError naming
    the sizes, not an IndexError from the gather."""
    _, batch = make_batch()
    x = torch.randn(batch.num_nodes, 9)
    streams, _ = to_temporal_streams(x, batch)
    for bad in (x[:-1], x[:, :, None]):
        with pytest.raises(ValueError, match=f"N = {batch.num_nodes} nodes"):
            to_temporal_streams(bad, batch)
    for bad in (streams[:-1], streams[:, :-1], streams[0]):
        with pytest.raises(ValueError, match=f"S = {batch.num_streams} streams"):
            from_temporal_streams(bad, batch)
