"""How decoded windows are joined into a take."""
import numpy as np
import torch

from satagraph.data.features import motion_to_features
from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.pipelines.inference import cross_fade, transfer, window_plan
from satagraph.transforms.canonical import canonicalize


class WindowNumber(torch.nn.Module):
    """Decodes every frame of the k-th window it is shown as k: what a
    decoder that reads each window a little differently does, at its
    largest."""

    def __init__(self) -> None:
        super().__init__()
        self.anchor = torch.nn.Parameter(torch.zeros(1))  # a device to be on
        self.seen = 0

    def forward(self, src, tgt) -> dict:
        frames = src.clip_num_frames.tolist()
        joints = int(tgt.clip_num_joints[0])
        number = torch.cat([torch.full((n,), float(self.seen + k)) for k, n in enumerate(frames)])
        self.seen += len(frames)
        return {"q": number[:, None, None].expand(-1, joints, 6).reshape(-1, 6),
                "r": number[:, None].expand(-1, 4).clone(),
                "c": torch.zeros(len(number) * joints)}


def test_windows_are_cross_faded_where_they_overlap_not_cut() -> None:
    """A take read window by window has no jump at a seam: each frame two
    windows share moves from the earlier window's reading to the later's
    (cut at the seam, each frame of a biped walk jumped by a whole window's
    difference)."""
    walk = canonicalize(generate_clip(zoo_rigs(["biped"])[0], "walk", frames=100, seed=0))
    feats = motion_to_features(walk)
    q, r, _ = transfer(WindowNumber(), feats, feats, window=32, overlap=8, batch_size=3)
    plan = window_plan(feats.num_frames, 32, 8)
    assert len(plan) == 4  # three seams, one of them between two batches
    step = np.abs(np.diff(r[:, 0]))
    assert step.max() <= 1 / 9 + 1e-9  # eight shared frames: ninths, never a whole 1
    assert np.all(np.diff(r[:, 0]) >= 0)
    assert r[0, 0] == 0 and r[-1, 0] == len(plan) - 1
    np.testing.assert_allclose(q[..., 0], np.broadcast_to(r[:, :1], q.shape[:2]))


def test_cross_fade_keeps_a_window_whole_where_it_shares_no_frame() -> None:
    whole = np.full((10, 2), 7.0)
    cross_fade(whole, np.ones((6, 2)), 0, 0)
    cross_fade(whole, np.full((6, 2), 3.0), 4, 6)
    np.testing.assert_allclose(whole[:, 0], [1, 1, 1, 1, 5 / 3, 7 / 3, 3, 3, 3, 3])
