"""Consecutive frames of batched clips pooled into groups and back."""
from __future__ import annotations

from types import SimpleNamespace

import pytest
import torch

from satagraph.ops.frame_pool import frame_groups, pool_frames


def batch_of(*num_frames: int) -> SimpleNamespace:
    """The per-frame indices a frame batch of clips this long carries."""
    counts = torch.tensor(num_frames)
    clip = torch.arange(len(num_frames)).repeat_interleave(counts)
    time = torch.cat([torch.arange(n) for n in num_frames])
    return SimpleNamespace(clip_num_frames=counts, frame_clip=clip, frame_time=time)


def test_groups_run_within_each_clip_the_last_one_shorter():
    group = frame_groups(batch_of(5, 2, 3), 2)
    assert group.tolist() == [0, 0, 1, 1, 2, 3, 3, 4, 4, 5]
    assert torch.equal(frame_groups(batch_of(4, 1), 1), torch.arange(5))
    with pytest.raises(ValueError, match="size must be at least 1"):
        frame_groups(batch_of(3), 0)


def test_pool_is_the_group_mean_and_indexing_spreads_it_back():
    x = torch.arange(10.0).unsqueeze(-1).repeat(1, 2)
    group = frame_groups(batch_of(5, 2, 3), 2)
    pooled = pool_frames(x, group)
    assert pooled[:, 0].tolist() == [0.5, 2.5, 4.0, 5.5, 7.5, 9.0]
    spread = pooled[group]
    assert spread.shape == x.shape and torch.equal(spread[0], spread[1])
    # a frame-wise constant signal is unchanged by pooling and spreading
    const = torch.randn(3, 4, generator=torch.Generator().manual_seed(0))
    frames = const[torch.tensor([0, 0, 0, 0, 0, 1, 1, 2, 2, 2])]
    torch.testing.assert_close(pool_frames(frames, group)[group], frames)
