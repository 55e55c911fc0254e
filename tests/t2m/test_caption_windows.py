"""Captioned windows: zoo clips captioned from their facts, file windows
with the captions that overlap them, mirroring of motion and captions
together, and the data module's splits."""
from __future__ import annotations

import numpy as np
import torch
import pytest

from satagraph.transforms.canonical import canonicalize
from satagraph.data.examples import example_motion
from satagraph.data.features import motion_to_features
from satagraph.datasets.sources import MotionFile
from satagraph.datasets import Caption, captions_for, mirror_text
from satagraph.data.caption_datamodule import CaptionDataModule
from satagraph.data.captioned import (FileCaptionWindows, batch_censored, batch_seconds,
                                      batch_texts)
from tests.conftest import data_dir
from tests.t2m.conftest import zoo_batch, zoo_windows


def test_zoo_windows_carry_their_captions_and_lengths():
    ds = zoo_windows(6)
    for i in range(6):
        clip = ds[(0, i)]
        assert 16 <= clip.num_frames <= 40
        assert clip.meta["text"] in clip.meta["captions"]
        assert clip.meta["seconds"] == pytest.approx(clip.num_frames / 30.0)
        assert clip.meta["censored"]  # a drawn length: the motion could go on
        assert clip.semantic.shape == (clip.num_joints, 256)


def test_zoo_windows_are_deterministic_per_key():
    a, b = zoo_windows(4), zoo_windows(4)
    first, again = a[(2, 1)], b[(2, 1)]
    assert first.meta["text"] == again.meta["text"]
    assert np.array_equal(first.dynamic.numpy(), again.dynamic.numpy())
    assert a[(3, 1)].meta["path"] != first.meta["path"]  # a new clip every epoch
    assert a[1].meta["path"] == b[1].meta["path"]  # evaluation: fixed


def test_evaluation_items_take_the_first_caption_unmirrored():
    ds = zoo_windows(4, mirror=1.0)
    clip = ds[0]
    assert not clip.meta["mirrored"]
    assert clip.meta["text"] == clip.meta["captions"][0]


def _turn_keys(plain, mirrored):
    """A training key of a turning clip that could be mirrored."""
    for i in range(len(plain)):
        clip = plain[(0, i)]
        if clip.meta["kind"] == "turn" and any(w in clip.meta["text"]
                                               for w in ("left", "right")):
            flipped = mirrored[(0, i)]
            if flipped.meta["mirrored"]:
                return clip, flipped
    pytest.skip("no mirrorable turning clip drawn")


def test_mirroring_swaps_motion_and_caption_sides_together():
    clip, flipped = _turn_keys(zoo_windows(64, mirror=0.0), zoo_windows(64, mirror=1.0))
    assert flipped.meta["text"] == mirror_text(clip.meta["text"])
    assert flipped.meta["captions"] == [mirror_text(t) for t in clip.meta["captions"]]
    # the root turns the other way: yaw velocities change sign
    yaw, yaw_m = clip.root[:, 0].sum().item(), flipped.root[:, 0].sum().item()
    assert abs(yaw) > 0.05 and np.sign(yaw) == -np.sign(yaw_m)
    assert yaw_m == pytest.approx(-yaw, rel=0.05, abs=1e-3)
    side = "left" if yaw > 0 else "right"
    other = "right" if side == "left" else "left"
    assert side in clip.meta["text"] and other in flipped.meta["text"]


def test_file_windows_keep_the_captions_overlapping_them():
    motion = canonicalize(example_motion(90, fps=30.0), fps=30.0)
    feats = motion_to_features(motion)
    captions = [Caption("a person waves the left hand", 0.0, 1.0),
                Caption("a person kicks with the right foot", 2.0, None)]
    f = MotionFile("clip.bvh", "user", "example", "train")
    ds = FileCaptionWindows([f], [feats], window=30, stride=30, captions=[captions])
    texts = [ds[i].meta["captions"] for i in range(len(ds))]
    assert texts == [[captions[0].text], [captions[1].text]]  # 1 s - 2 s: no caption
    assert all(ds[i].num_frames == 30 for i in range(len(ds)))
    # each window's duration is its caption's time range: 0-1 s, then 2 s to the end
    assert [ds[i].meta["seconds"] for i in range(len(ds))] == pytest.approx([1.0, 1.0])
    assert not any(ds[i].meta["censored"] for i in range(len(ds)))


def test_a_caption_touching_a_window_by_a_frame_is_not_its_caption():
    """A window of a standing stretch (0-2 s) was trained as "walks
    backward", the next stretch's caption, for the frame they share."""
    from satagraph.data.captioned import overlapping
    still, back = Caption("a person stands still", 0.0, 2.0), Caption("a person walks "
                                                                     "backward", 2.0, 6.9)
    assert overlapping([still, back], 30.0, 207, 0, 64) == [still]  # shares 4 frames of back
    assert overlapping([still, back], 30.0, 207, 40, 104) == [back]  # 20 of 64 still's
    assert overlapping([still, back], 30.0, 207, 30, 90) == [still, back]  # half and half
    whole = Caption("a person walks")
    assert overlapping([whole], 30.0, 207, 100, 164) == [whole]


def test_file_windows_learn_their_whole_clips_duration():
    """A window cut from a longer captioned clip carries the clip's duration
    (the caption describes all of it), mirrored or not."""
    motion = canonicalize(example_motion(150, fps=30.0), fps=30.0)
    feats = motion_to_features(motion)
    f = MotionFile("clip.bvh", "user", "example", "train")
    caption = [Caption("a person walks forward and turns left", 0.0, None)]
    for mirror in (0.0, 1.0):
        ds = FileCaptionWindows([f], [feats], window=60, stride=60, captions=[caption],
                                mirror=mirror)
        for key in ((0, 0), 1, (3, 2)):
            clip = ds[key]
            assert clip.num_frames == 60
            assert clip.meta["seconds"] == pytest.approx(feats.num_frames / 30.0)
            assert not clip.meta["censored"]


def test_file_windows_mirror_their_captions():
    motion = canonicalize(example_motion(40, fps=30.0), fps=30.0)
    feats = motion_to_features(motion)
    f = MotionFile("clip.bvh", "user", "example", "train")
    caption = [Caption("a person turns left", 0.0, None)]
    ds = FileCaptionWindows([f], [feats], window=40, captions=[caption], mirror=1.0)
    clip = ds[(0, 0)]
    assert clip.meta["mirrored"] and clip.meta["text"] == "a person turns right"
    assert clip.num_frames == 40


def test_batch_helpers():
    batch = zoo_batch(3)
    assert len(batch_texts(batch)) == 3
    assert batch_seconds(batch).tolist() == pytest.approx(
        (batch.clip_num_frames.float() / 30.0).tolist())
    assert batch_censored(batch).tolist() == [True] * 3


@pytest.mark.skipif(data_dir() is None, reason="../shared/data not found: the real "
                    "captioned files are needed")
def test_real_captioned_windows_in_manifest_splits(tmp_path):
    root = data_dir()
    rows = [line.split("\t") for line in (root / "manifest.tsv").read_text().splitlines()]
    keep = [r for r in rows[1:] if r[1] in ("ccbase", "bandai")]
    picked = [r for r in keep if r[1] == "ccbase"][:2] + \
        [r for r in keep if r[1] == "bandai" and r[4] == "test"][:1]
    manifest = tmp_path / "manifest.tsv"
    manifest.write_text("\t".join(rows[0]) + "\n" + "\n".join(
        "\t".join([str(root / r[0])] + r[1:]) for r in picked) + "\n")
    data = CaptionDataModule([str(manifest)], window=64, mirror=0.0,
                             cache_dir=str(tmp_path / "cache"))
    data.setup()
    for split in ("train", "val", "test"):
        ds = data.datasets[split]
        for i in range(len(ds)):
            clip = ds[i]
            expected = [c.text for c in captions_for(clip.meta["path"])]
            assert clip.meta["text"] in expected
    test = data.datasets["test"]
    assert len(test) and all(test[i].meta["dataset"] == "bandai" for i in range(len(test)))


def test_bone_scaling_changes_the_skeleton_not_the_caption_or_the_length():
    plain, scaled = zoo_windows(4, scale=0.0), zoo_windows(4, scale=1.0)
    for i in range(4):
        a, b = plain[(1, i)], scaled[(1, i)]
        assert b.meta["scaled"] and not a.meta["scaled"]
        assert a.meta["captions"] == b.meta["captions"] and a.num_frames == b.num_frames
        assert torch.isfinite(b.dynamic).all() and torch.isfinite(b.root).all()
        lengths_a = a.static[:, :3].norm(dim=-1)
        lengths_b = b.static[:, :3].norm(dim=-1)
        ratio = lengths_b[lengths_a > 1e-6] / lengths_a[lengths_a > 1e-6]
        assert ratio.std() > 0.01  # bones scaled unevenly
        assert ((ratio > 0.5) & (ratio < 1.6)).all()
    # evaluation windows are never scaled
    assert not scaled[0].meta["scaled"]


def test_file_windows_play_walks_backwards_with_their_captions():
    motion = canonicalize(example_motion(90, fps=30.0), fps=30.0)
    feats = motion_to_features(motion)
    f = MotionFile("clip.bvh", "user", "example", "train")
    walk = [Caption("a person walks forward", 0.0, None), Caption("a person takes a walk")]
    plain = FileCaptionWindows([f], [feats], window=40, stride=20, captions=[walk])
    back = FileCaptionWindows([f], [feats], window=40, stride=20, captions=[walk], reverse=1.0)
    for key in ((0, 0), (2, 1), (1, 2)):
        a, b = plain[key], back[key]
        assert b.meta["reversed"] and not a.meta["reversed"]
        assert b.meta["captions"] == ["a person walks backward"]  # the other has no reversal
        assert b.num_frames == a.num_frames == 40
        assert b.meta["seconds"] == pytest.approx(a.meta["seconds"])
        # the root travels the other way at the same speed, and the pose plays backwards
        assert b.root[:, 2].mean().item() == pytest.approx(-a.root[:, 2].mean().item(), rel=0.05)
        assert a.root[:, 2].mean().item() > 0.5
        assert torch.allclose(b.dynamic.flip(0)[..., :3], a.dynamic[..., :3], atol=1e-4)
    assert not back[0].meta["reversed"]  # evaluation windows are never reversed


def test_windows_without_a_known_reversal_stay_as_they_are():
    motion = canonicalize(example_motion(60, fps=30.0), fps=30.0)
    feats = motion_to_features(motion)
    f = MotionFile("clip.bvh", "user", "example", "train")
    jump = [Caption("a person jumps forward")]
    ds = FileCaptionWindows([f], [feats], window=60, captions=[jump], reverse=1.0)
    clip = ds[(0, 0)]
    assert not clip.meta["reversed"] and clip.meta["captions"] == ["a person jumps forward"]
    assert clip.root[:, 2].mean().item() > 0.5
    with pytest.raises(ValueError, match="reverse must be in"):
        FileCaptionWindows([f], [feats], window=60, captions=[jump], reverse=1.5)


def test_files_without_captions_are_said_when_left_out(tmp_path):
    """An uncaptioned take (or one whose caption lies past its end) was left
    out of training without a word."""
    from satagraph.io import write_bvh
    folder = tmp_path / "mine"
    folder.mkdir()
    for name in ("walk", "other", "third", "fourth", "fifth"):
        write_bvh(example_motion(num_frames=40), folder / f"{name}.bvh")
    for name in ("walk", "third", "fourth", "fifth"):
        (folder / f"{name}.txt").write_text("a person walks forward#a/DET#0.0#0.0\n")
    files = [MotionFile(str(folder / f"{n}.bvh"), "mine", "example", "train")
             for n in ("walk", "other")]
    feats = [motion_to_features(canonicalize(f.read(), fps=30.0)) for f in files]
    windows = FileCaptionWindows(files, feats, window=16, stride=16)
    assert windows.uncaptioned == [files[1].path] and len(windows.files) == 1
    dm = CaptionDataModule([str(folder)], window=16, stride=16, batch_size=2,
                           semantic_encoder=None, cache_dir=str(tmp_path / "cache"))
    said = r"(train|val|test): 1 of \d files have no captions .*other\.bvh"
    with pytest.warns(UserWarning, match=said):
        dm.setup("fit")


def test_captions_past_a_clips_end_are_said_when_left_out(tmp_path):
    """A sidecar line whose range starts past its clip's end (a 1.3-s take
    captioned at 5-9 s) described no frame and was dropped without a word."""
    from satagraph.io import write_bvh
    folder = tmp_path / "mine"
    folder.mkdir()
    for name in ("walk", "third", "fourth", "fifth"):
        write_bvh(example_motion(num_frames=40), folder / f"{name}.bvh")
        (folder / f"{name}.txt").write_text("a person walks forward#a/DET#0.0#0.0\n"
                                           "a person stands still#a/DET#5.0#9.0\n")
    f = MotionFile(str(folder / "walk.bvh"), "mine", "example", "train")
    feats = motion_to_features(canonicalize(f.read(), fps=30.0))
    windows = FileCaptionWindows([f], [feats], window=16, stride=16)
    assert len(windows.outside) == 1 and "'a person stands still' at 5-9 s" in windows.outside[0]
    assert all(windows.window_captions(0, s) for _, s in windows.index)
    dm = CaptionDataModule([str(folder)], window=16, stride=16, batch_size=2,
                           semantic_encoder=None, cache_dir=str(tmp_path / "cache"))
    said = r"train: 4 captions lie past their clip's end and are left out .*stands"
    with pytest.warns(UserWarning, match=said):
        dm.setup("fit")


def test_a_file_limit_of_captioned_files_is_said(tmp_path):
    """``data.max_files`` spread a caption data module's files as the
    motion data module's, but said nothing of what it left out."""
    from satagraph.io import write_bvh
    folder = tmp_path / "mine"
    folder.mkdir()
    for name in ("walk", "jog", "turn", "wave", "hop"):
        write_bvh(example_motion(num_frames=40), folder / f"{name}.bvh")
        (folder / f"{name}.txt").write_text("a person walks forward#a/DET#0.0#0.0\n")
    dm = CaptionDataModule([str(folder)], window=16, stride=16, batch_size=2, max_files=2,
                           semantic_encoder=None, cache_dir=str(tmp_path / "cache"))
    with pytest.warns(UserWarning, match=r"data.max_files=2 reads train 2 of \d \(mine 2 of"):
        dm.setup("fit")
    assert len(dm.datasets["train"].parts[0].files) == 2
