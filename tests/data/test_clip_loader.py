"""ClipLoader: clips of mixed skeletons batched as PyG's DataLoader batches graphs."""
from __future__ import annotations

import pytest
import torch
from torch_geometric.loader import DataLoader as PyGDataLoader

from satagraph.data import ClipLoader, FrameBatch, collate_clips
from tests.data.test_collate import make_clips


def test_a_clip_loader_gives_the_batches_collate_clips_gives():
    clips = make_clips()
    batches = list(ClipLoader(clips, batch_size=2))
    assert len(batches) == 3 and all(isinstance(b, FrameBatch) for b in batches)
    for i, batch in enumerate(batches):
        expected = collate_clips(clips[2 * i:2 * i + 2])
        assert batch.meta == expected.meta
        for key in expected.keys():
            if isinstance(expected[key], torch.Tensor):
                assert torch.equal(batch[key], expected[key]), key


def test_a_shuffled_clip_loader_draws_every_clip_once_an_epoch_as_seeded():
    clips = make_clips()
    ids = [c.meta["id"] for c in clips]

    def epoch(seed: int) -> list:
        loader = ClipLoader(clips, batch_size=2, shuffle=True,
                            generator=torch.Generator().manual_seed(seed))
        return [m["id"] for batch in loader for m in batch.meta]

    assert sorted(epoch(0)) == sorted(ids)
    assert epoch(0) == epoch(0) and epoch(0) != ids


def test_pyg_s_loader_refuses_clips_and_ours_refuses_another_collate():
    """PyG's loader cannot batch a clip (why ClipLoader exists); a
    ``collate_fn`` of one's own is refused, not silently dropped."""
    with pytest.raises(TypeError, match="invalid type"):
        next(iter(PyGDataLoader(make_clips(), batch_size=2)))
    with pytest.raises(TypeError, match="^ClipLoader: collate_fn is collate_clips"):
        ClipLoader(make_clips(), collate_fn=list)


def test_without_batch_size_each_item_is_a_list_of_clips():
    """``batch_size=None`` hands each item over as it is: a list of clips
    is one batch; a clip alone is refused in one line, not "'MotionClip'
    object is not iterable"."""
    clips = make_clips()
    lists = [clips[:2], clips[2:]]
    batches = list(ClipLoader(lists, batch_size=None))
    assert [b.meta for b in batches] == [collate_clips(c).meta for c in lists]
    with pytest.raises(TypeError, match=r"^collate_clips: a list of clips, not one MotionClip"):
        next(iter(ClipLoader(clips, batch_size=None)))
