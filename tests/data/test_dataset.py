"""Sources, processed-feature cache, windows and the normaliser."""
import os
from pathlib import Path

import numpy as np
import pytest
import torch

from satagraph.data.cache import load_cached, store_cached
from satagraph.data.dataset import (MotionDatasetError, load_features,
                                    preprocess_file, window_starts,
                                    DEFAULT_PREPROCESSING)
from satagraph.data.normalizer import FeatureNormalizer
from satagraph.datasets.sources import resolve_sources, scan_folder, select


def test_window_starts_cover_clip():
    assert window_starts(10, 64, 32) == [0]
    assert window_starts(64, 64, 32) == [0]
    starts = window_starts(150, 64, 32)
    assert starts[0] == 0 and starts[-1] + 64 == 150
    assert all(b - a <= 32 for a, b in zip(starts, starts[1:]))


def test_manifest_sources_and_splits(shared_data):
    files = resolve_sources(str(shared_data / "manifest.tsv"))
    assert len(files) == 244  # parser_test fixtures are left out
    assert {f.dataset for f in files} == {"bandai", "cmu", "ccbase", "dog"}
    dog = scan_folder(shared_data / "dog")
    assert len(dog) == 34 and len(select(dog, "test")) == 10
    only_dog = resolve_sources({"path": str(shared_data / "manifest.tsv"),
                                "dataset": "dog"})
    assert len(only_dog) == 34
    with pytest.raises(FileNotFoundError, match="not found"):
        resolve_sources("/nonexistent/folder")


def test_cache_round_trip_and_corruption(shared_data, tmp_path):
    path = str(shared_data / "bandai" / "dataset-1_bow_active_001.bvh")
    feats = preprocess_file(path, DEFAULT_PREPROCESSING)
    store_cached(tmp_path, "k", feats)
    back = load_cached(tmp_path, "k")
    assert back.skeleton.names == feats.skeleton.names
    assert back.skeleton.channels == feats.skeleton.channels
    np.testing.assert_array_equal(back.q, feats.q)
    assert back.transform.removed_root["name"] == "joint_Root"
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".tmp")]
    (tmp_path / "k.npz").write_bytes(b"garbage")
    with pytest.warns(UserWarning, match="unreadable cache"):
        assert load_cached(tmp_path, "k") is None
    assert not (tmp_path / "k.npz").exists()


def test_bad_files_reported_together_and_not_cached(shared_data, tmp_path):
    good = resolve_sources(str(shared_data / "cmu"))[:1]
    bad_dir = tmp_path / "bad"
    bad_dir.mkdir()
    (bad_dir / "a.bvh").write_text("HIERARCHY\nROOT x\n{\n")
    (bad_dir / "b.bvh").write_text("")
    bad = resolve_sources(str(bad_dir))
    cache = tmp_path / "cache"
    with pytest.raises(MotionDatasetError) as err:
        load_features(good + bad, cache_dir=str(cache))
    msg = str(err.value)
    assert "2 of 3" in msg and "a.bvh" in msg and "b.bvh" in msg
    assert len(list((cache / "processed").glob("*.npz"))) == 1  # the good one


def test_cache_keyed_by_config(shared_data, tmp_path):
    files = resolve_sources(str(shared_data / "cmu"))[:1]
    a = load_features(files, {"fps": 30.0}, cache_dir=str(tmp_path))[0]
    b = load_features(files, {"fps": 15.0}, cache_dir=str(tmp_path))[0]
    assert a.fps == 30 and b.fps == 15
    assert len(list((tmp_path / "processed").glob("*.npz"))) == 2


def test_normalizer_fit_and_inverse(shared_data, tmp_path):
    files = resolve_sources(str(shared_data / "cmu"))[:2]
    feats = load_features(files, cache_dir=str(tmp_path))
    norm = FeatureNormalizer().fit(feats)
    x = torch.from_numpy(np.concatenate([f.dynamic.reshape(-1, 22) for f in feats])).float()
    height = torch.cat([torch.full((f.dynamic[..., 0].size,), f.height) for f in feats])
    z = norm.normalize(x, "dynamic", height)
    assert z[:, :21].mean(0).abs().max() < 1e-3
    torch.testing.assert_close(z[:, 21], x[:, 21])  # contacts stay raw
    torch.testing.assert_close(norm.denormalize(z, "dynamic", height=height), x,
                               atol=1e-4, rtol=1e-4)
    state = norm.state_dict()
    other = FeatureNormalizer(body_relative=False)
    other.load_state_dict(state)
    assert bool(other.fitted) and bool(other.body_relative)


def test_body_relative_normaliser_sees_a_scaled_body_alike(shared_data, tmp_path):
    """The same motion on a body ten times smaller has the same normalised
    features (lengths in heights); rotations are untouched."""
    from satagraph.data import features_to_motion, motion_to_features
    from satagraph.transforms import canonicalize
    files = resolve_sources(str(shared_data / "cmu"))[:1]
    feats = load_features(files, cache_dir=str(tmp_path))[0]
    norm = FeatureNormalizer().fit([feats])
    motion = features_to_motion(feats)
    small = motion.with_(translations=motion.translations * 0.1,
                         skeleton=motion.skeleton.replace(offsets=motion.skeleton.offsets * 0.1))
    tiny = motion_to_features(canonicalize(small))
    assert tiny.height == pytest.approx(0.1 * feats.height, rel=1e-6)
    # canonical ground placement differs by 0.1% of the height: root height
    # (a channel of small spread) agrees to 0.1 of its standard deviation
    for name, a, b, tol in (("root", feats.r, tiny.r, 0.1),
                            ("static", feats.static, tiny.static, 1e-3)):
        za = norm.normalize(torch.from_numpy(a).float(), name,
                            torch.full((len(a),), feats.height))
        zb = norm.normalize(torch.from_numpy(b).float(), name,
                            torch.full((len(b),), tiny.height))
        torch.testing.assert_close(za, zb, atol=tol, rtol=1e-3)


def test_normaliser_of_an_old_checkpoint_stays_in_metres():
    """Statistics saved before body_relative existed load as metres."""
    norm = FeatureNormalizer()
    state = {k: v for k, v in norm.state_dict().items() if k != "body_relative"}
    norm.load_state_dict(state)
    assert not bool(norm.body_relative)
    x = torch.ones(3, 4)
    torch.testing.assert_close(norm.normalize(x, "root", torch.full((3,), 2.0)), x)


def test_augmentation_never_makes_an_implausible_root(read_real) -> None:
    """Bone scaling of ccbase/007_01 (a moving RL_BoneRoot above the hips)
    gave root speeds of 1e5 (a 1e9 training loss) while that root was read
    as the body's; folded into the hips (canonical.fold_root) it scales
    like any rig, and the guard that used such windows as they were has
    nothing left to catch there."""
    from satagraph.data import motion_to_features
    from satagraph.transforms import canonicalize
    from satagraph.data.dataset import WindowAugment
    feats = motion_to_features(canonicalize(read_real("ccbase/007_01.bvh")))
    aug = WindowAugment.from_config({"scale": 1.0, "mirror": 0.0})
    bound = 4 * max(np.abs(feats.r[:, :3]).max(), 0.5)
    for i, start in enumerate(range(0, 44, 4)):
        out, _ = aug(feats, start, start + 32, 0, i)
        assert np.abs(out.r[:, :3]).max() <= bound
    assert aug.rejected == 0


def test_the_augmentation_guard_refuses_a_root_four_times_faster(read_real) -> None:
    """What the guard reads: an augmented window whose root moves more than
    four times as fast as its source's (or is not finite) is implausible."""
    from dataclasses import replace
    from satagraph.data import motion_to_features
    from satagraph.data.dataset import _plausible_root
    from satagraph.transforms import canonicalize
    feats = motion_to_features(canonicalize(read_real("ccbase/007_02.bvh")))
    assert _plausible_root(feats, feats)
    assert not _plausible_root(replace(feats, r=feats.r * 5.0), feats)
    assert not _plausible_root(replace(feats, r=feats.r * np.nan), feats)


def test_facing_smooth_is_a_preprocessing_option_end_to_end(shared_data):
    """``data.preprocessing.facing_smooth`` reaches the features of a file,
    of augmented windows and of a zoo clip, is part of the cache key, and
    inference reads it back from a module's config (0 where none is set)."""
    from satagraph.data.cache import cache_key
    from satagraph.data.dataset import (DEFAULT_PREPROCESSING, WindowAugment, feature_options,
                                        preprocess_file)
    from satagraph.data.endless import EndlessZooDataset
    from satagraph.datasets.zoo.endless import EndlessZoo
    from satagraph.pipelines.inference import facing_smooth_of
    path = str(shared_data / "dog" / "D1_009_KAN01_001.bvh")
    config = dict(DEFAULT_PREPROCESSING, scale="cm")
    smooth = dict(config, facing_smooth=0.25)
    swing = [np.abs(preprocess_file(path, c).r[1:, 0]).mean() for c in (config, smooth)]
    assert swing[1] < 0.25 * swing[0]
    assert cache_key(path, config) != cache_key(path, smooth)
    assert feature_options(smooth)["facing_smooth"] == 0.25
    assert WindowAugment.from_config(True, 0, smooth).options["facing_smooth"] == 0.25
    zoo = [EndlessZooDataset(EndlessZoo(["quadruped"]), windows=1, window=90,
                             preprocessing={"facing_smooth": s}) for s in (0.0, 0.25)]
    clips = [d[0] for d in zoo]
    assert not torch.allclose(clips[0].root[:, 0], clips[1].root[:, 0])

    class Trained:
        meta = {"data": {"preprocessing": {"facing_smooth": 0.25}}}

    assert facing_smooth_of(Trained()) == 0.25 and facing_smooth_of(object()) == 0.0


def test_cache_sees_an_edit_that_keeps_size_and_time(tmp_path):
    """A file replaced by one of the same size and modification time (``cp
    -p``, ``rsync -t``) is read again, not served from the cache."""
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "zoo", species=["biped"], clips=1, frames=8)
    files = scan_folder(tmp_path / "zoo")[:1]
    path = files[0].path
    before = load_features(files, cache_dir=str(tmp_path / "cache"))[0]
    text = open(path).read()
    head, motion = text.split("MOTION\n")
    lines = motion.splitlines()
    frames = [" ".join(v if i != 4 else ("7" if v[0] != "7" else "1") + v[1:]
                       for i, v in enumerate(line.split())) for line in lines[2:]]
    edited = head + "MOTION\n" + "\n".join(lines[:2] + frames) + "\n"
    assert len(edited) == len(text) and edited != text
    stat = os.stat(path)
    with open(path, "w") as handle:
        handle.write(edited)
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    after = load_features(files, cache_dir=str(tmp_path / "cache"))[0]
    fresh = load_features(files, cache_dir=str(tmp_path / "fresh"))[0]
    assert not np.allclose(after.q, before.q)
    np.testing.assert_array_equal(after.q, fresh.q)


def test_a_cache_that_cannot_be_written_is_said_once_and_blames_no_file(tmp_path):
    """A cache folder that is a file (or full, or read-only): one warning
    naming it, and every data file still read; before, each file was
    reported as bad (and left out with ``on_error=skip``)."""
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "zoo", species=["biped"], clips=1, frames=8)
    files = scan_folder(tmp_path / "zoo")[:2]
    blocked = tmp_path / "cache"
    blocked.write_text("a file where the cache folder should be")
    with pytest.warns(UserWarning, match=f"feature cache {blocked}/processed cannot be used") \
            as caught:
        feats = load_features(files, cache_dir=str(blocked))
    assert len(feats) == 2 and len([w for w in caught if "feature cache" in str(w.message)]) == 1
    fresh = load_features(files[:1], cache_dir=str(tmp_path / "fresh"))
    np.testing.assert_array_equal(feats[0].q, fresh[0].q)


def test_a_manifest_row_of_an_unknown_split_is_said(tmp_path):
    """A misspelt split (``trian``) was left out unsaid."""
    (tmp_path / "manifest.tsv").write_text("path\tsplit\na.bvh\ttrain\nb.bvh\ttrian\n"
                                           "c.bvh\ttrian\nd.bvh\tparser_test\n")
    with pytest.warns(UserWarning, match=r"not used: 'trian' \(2\)"):
        files = resolve_sources(str(tmp_path / "manifest.tsv"))
    assert [f.split for f in files] == ["train", "trian", "trian"]


def test_a_folder_of_links_reads_its_own_manifest(tmp_path):
    """A folder of symbolic links to files kept elsewhere, with a
    ``manifest.tsv`` of its own: its rows were checked with the links
    resolved, so none was the folder's, and the manifest was dropped unsaid
    (splits by file name, test files trained on, no units, up axis or
    skeleton)."""
    store, mine = tmp_path / "store", tmp_path / "mine"
    store.mkdir(), mine.mkdir()
    for name in ("a.bvh", "b.bvh"):
        (store / name).write_text("HIERARCHY\n")
        (mine / name).symlink_to(store / name)
    (mine / "manifest.tsv").write_text("path\tsplit\tskeleton\tup_axis\tscale\n"
                                       "a.bvh\ttest\tdog21\t+Z\tcm\n"
                                       "b.bvh\tval\tdog21\t+Z\tcm\n")
    files = scan_folder(mine)
    assert [(Path(f.path).name, f.split, f.skeleton, f.up_axis, f.scale) for f in files] \
        == [("a.bvh", "test", "dog21", "+Z", 0.01), ("b.bvh", "val", "dog21", "+Z", 0.01)]


def test_a_zoo_folder_of_files_reads_the_manifest_two_folders_up(tmp_path):
    """``--data zoo/biped/Zup-in``, the folder ``satagraph zoo`` wrote the
    +Z-up inch files to: its manifest (two folders up) was not looked for,
    so the files were split by name (held-out rigs trained on), read in
    inches as metres and named ``Zup-in``."""
    from satagraph.datasets.zoo import write_zoo
    from satagraph.datasets.zoo.dialects import Dialect
    write_zoo(tmp_path / "zoo", species=["biped"], clips=1, frames=8,
              dialects=[Dialect(up_axis="+Z", unit="in")])
    (folder,) = {p.parent for p in (tmp_path / "zoo").rglob("*.bvh")}
    assert folder.parent.parent == tmp_path / "zoo"
    files = scan_folder(folder)
    truth = {Path(f.path).name: f for f in resolve_sources(str(tmp_path / "zoo"))}
    assert len(files) == len(truth) and {f.dataset for f in files} == {"zoo"}
    assert all((f.split, f.skeleton, f.up_axis, f.scale)
               == (truth[Path(f.path).name].split, truth[Path(f.path).name].skeleton,
                   "+Z", 0.0254) for f in files)


def test_special_files_among_sources_are_refused_not_read(tmp_path):
    """The cache key reads a file's content: a FIFO would block it and
    ``/dev/zero`` never end; each is one error line instead."""
    from satagraph.data.dataset import try_load_features
    from satagraph.datasets.sources import MotionFile
    fifo = tmp_path / "pipe.bvh"
    os.mkfifo(fifo)
    files = [MotionFile(str(fifo), "x", "x", "train"), MotionFile("/dev/zero", "x", "x", "train")]
    kept, _, errors = try_load_features(files, cache_dir=str(tmp_path / "cache"))
    assert not kept
    assert errors == [f"{fifo}: is a FIFO (named pipe), not a BVH file",
                      "/dev/zero: is a character device, not a BVH file"]


def test_a_file_limit_keeps_every_source_and_rig_it_has_room_for():
    """``data.max_files`` took the first files in order: with a CMU folder
    and a zoo, the CMU files only; of a zoo folder, one rig's."""
    from satagraph.datasets.sources import MotionFile, limit_note, spread_files
    files = ([MotionFile(f"cmu/{i}.bvh", "cmu", "cmu", "train") for i in range(6)]
             + [MotionFile(f"zoo/{k}{i}.bvh", "zoo", k, "train")
                for k in ("biped", "quadruped") for i in range(6)])
    kept = spread_files(files, 4)
    assert [f.path for f in kept] == ["cmu/0.bvh", "cmu/1.bvh", "zoo/biped0.bvh",
                                      "zoo/quadruped0.bvh"]
    assert spread_files(files, None) == files and spread_files(files, 100) == files
    assert limit_note("train", kept, files) == "train 4 of 18 (cmu 2 of 6, zoo 2 of 12)"


def test_a_file_limit_is_said(tmp_path):
    from satagraph.data.datamodule import MotionDataModule
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "zoo", species=["biped", "quadruped"], clips=1, seed=0)
    dm = MotionDataModule([str(tmp_path / "zoo")], window=8, stride=8, max_files=2,
                          semantic_encoder=None, cache_dir=str(tmp_path / "cache"))
    with pytest.warns(UserWarning, match=r"data.max_files=2 reads train 2 of \d+"):
        dm.setup("fit")
    skeletons = {f.skeleton for f in dm.datasets["train"].files}
    assert len(skeletons) == 2


def test_a_folder_of_two_rigs_is_sampled_per_rig(tmp_path, tiny_motion) -> None:
    """A folder without a manifest named every file's skeleton after the
    folder: two rigs in it were one balanced-sampling group, drawn as
    often as their windows are (65 of 69 Bandai windows to 4 CMU ones)."""
    from satagraph.data.dataset import MotionDataset
    from satagraph.data.examples import example_motion
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.sources import MotionFile
    from satagraph.io import write_bvh
    from satagraph.transforms import canonicalize
    write_bvh(example_motion(), tmp_path / "walk.bvh")
    write_bvh(tiny_motion, tmp_path / "tiny.bvh")
    files = scan_folder(tmp_path)
    feats = [motion_to_features(canonicalize(f.read(), unit_scale=1.0)) for f in files]
    ds = MotionDataset(files, feats, window=4, stride=4)
    groups = {ds.group(i) for i in range(len(ds))}
    assert len(groups) == 2 and all(g.startswith(f"{tmp_path.name}/") for g in groups)
    assert {ds[i].meta["skeleton"] for i in range(len(ds))} == {g.split("/")[1] for g in groups}
    # a skeleton id a manifest names is kept as it is
    from satagraph.data.dataset import skeleton_id
    named = MotionFile("a.bvh", "d", "crab", "train")
    assert skeleton_id(named, feats[0].skeleton) == "crab"


def test_two_folders_of_one_name_are_refused_not_merged(tmp_path):
    """``--data a/mocap --data b/mocap`` named both datasets ``mocap``: their
    per-dataset figures, balanced groups and skeleton ids merged unsaid."""
    for parent in ("a", "b"):
        (tmp_path / parent / "mocap").mkdir(parents=True)
        (tmp_path / parent / "mocap" / f"{parent}.bvh").write_text("")
    a, b = str(tmp_path / "a" / "mocap"), str(tmp_path / "b" / "mocap")
    with pytest.raises(ValueError, match=f"{a} and {b} are both dataset 'mocap'"):
        resolve_sources([a, b])
    with pytest.raises(ValueError, match="both dataset 'mocap'"):
        resolve_sources([{"path": a, "dataset": "mocap"}, b])
    # named by the user: merged as asked, or told apart; one folder twice is one dataset
    merged = resolve_sources([{"path": a, "dataset": "m"}, {"path": b, "dataset": "m"}])
    assert {f.dataset for f in merged} == {"m"}
    apart = resolve_sources([a, {"path": b, "dataset": "mocap_b"}])
    assert [f.dataset for f in apart] == ["mocap", "mocap_b"]
    assert len(resolve_sources([a, str(tmp_path / "a" / ".." / "a" / "mocap")])) == 2
    # --data NAME=PATH names it as the refusal says (only a data.sources dict could)
    with pytest.raises(ValueError, match=f"--data mocap_2={b}"):
        resolve_sources([a, b])
    named = resolve_sources([a, f"mocap_b={b}"])
    assert [f.dataset for f in named] == ["mocap", "mocap_b"]
    odd = tmp_path / "x=y"  # a folder whose own name looks like one stays a path
    (odd / "mocap").mkdir(parents=True)
    (odd / "mocap" / "c.bvh").write_text("")
    assert [f.dataset for f in resolve_sources([str(odd / "mocap")])] == ["mocap"]
    assert [f.dataset for f in resolve_sources([str(odd)])] == ["x=y"]


def test_manifests_below_a_folder_and_files_a_manifest_lacks_are_said(tmp_path):
    """A folder of two zoo folders is split by name: the zoos' manifests
    (their splits, units and up axes) were left unread without a word; a
    file added beside a manifest that does not list it was left out unsaid."""
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "top" / "a", species=["biped"], clips=1, frames=8)
    write_zoo(tmp_path / "top" / "b", species=["quadruped"], clips=1, frames=8)
    with pytest.warns(UserWarning, match=r"top: its files are split by name, and the 2 "
                      r"manifest\(s\) below it are not read: .*a/manifest.tsv, .*b/manifest"):
        assert len(scan_folder(tmp_path / "top")) == 8
    listed = scan_folder(tmp_path / "top" / "a")
    extra = tmp_path / "top" / "a" / "extra.bvh"
    extra.write_bytes(Path(listed[0].path).read_bytes())
    with pytest.warns(UserWarning, match=r"a/manifest.tsv: 1 .bvh file\(s\) below it are not "
                      r"in it and are not read: .*extra.bvh"):
        assert [f.path for f in scan_folder(tmp_path / "top" / "a")] == \
            [f.path for f in listed]


def test_a_folder_a_manifest_above_does_not_list_is_said(tmp_path):
    """A folder of new files under a folder whose manifest lists none of
    them was split by name without a word."""
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "top", species=["biped"], clips=1, frames=8)
    new = tmp_path / "top" / "new"
    new.mkdir()
    source = scan_folder(tmp_path / "top")[0].path
    (new / "a.bvh").write_bytes(Path(source).read_bytes())
    with pytest.warns(UserWarning, match=r"new: .*top/manifest.tsv above it lists none of its "
                      r"1 .bvh file\(s\): they are split by name"):
        assert len(scan_folder(new)) == 1

