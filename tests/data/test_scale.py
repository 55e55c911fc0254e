"""Data pipeline over many files: what grows with the number of files."""
import tracemalloc

import numpy as np
import pytest

from satagraph.data import motion_to_features
from satagraph.data.normalizer import FeatureNormalizer
from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.transforms import canonicalize


@pytest.fixture(scope="module")
def walk_features():
    rig = zoo_rigs(["biped"])[0]
    return motion_to_features(canonicalize(generate_clip(rig, "walk", frames=60, seed=3)))


def test_normalizer_fit_holds_one_file_at_a_time(walk_features):
    """Fitting on many files pools their statistics one file at a time: the
    memory it takes beside the features does not grow with their number
    (the split was copied to float64 and concatenated: `train tiny` on
    1 029 files peaked at 4.6 GB, 1.9 GB without the copy), and the
    statistics are those of all rows together."""
    files = 40
    one = walk_features.dynamic.reshape(-1, 22).astype(np.float64).nbytes
    tracemalloc.start()
    try:
        norm = FeatureNormalizer().fit([walk_features] * files)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 6 * one < files * one
    rows = norm._relative(walk_features.dynamic.reshape(-1, 22), "dynamic",
                          walk_features.height)
    mean, std = rows.mean(0), rows.std(0)
    c = slice(21, 22)  # contacts stay raw
    np.testing.assert_allclose(norm.dynamic_mean[:21].numpy(), mean[:21], rtol=1e-5,
                               atol=1e-6)
    np.testing.assert_allclose(norm.dynamic_std[:21].numpy(),
                               np.maximum(std[:21], 1e-4), rtol=1e-4, atol=1e-6)
    assert norm.dynamic_mean[c].item() == 0.0 and norm.dynamic_std[c].item() == 1.0


def test_normalizer_moments_pool_blocks_of_unlike_lengths():
    """Blocks of different lengths weigh by their rows, as one concatenation."""
    from satagraph.data.normalizer import _Moments
    rng = np.random.default_rng(0)
    parts = [rng.normal(loc, scale, size=(n, 4)) for loc, scale, n in
             ((0.0, 1.0, 10), (5.0, 2.0, 300), (-3.0, 0.5, 1))]
    moments = _Moments()
    for p in parts:
        moments.add(p)
    moments.add(np.zeros((0, 4)))
    whole = np.concatenate(parts)
    np.testing.assert_allclose(moments.stats()[0], whole.mean(0), rtol=1e-12)
    np.testing.assert_allclose(moments.stats()[1], whole.std(0), rtol=1e-12)


def test_feature_cache_is_keyed_by_content_not_place(tmp_path, monkeypatch):
    """One file's bytes in three places (a link, a moved copy) are
    processed once and cached once; an edit to one of them is processed
    again, alone (each place had its own entry: a folder linked in three
    times took three times the cache, and a moved folder was read anew)."""
    import shutil

    from satagraph.data import dataset
    from satagraph.data.dataset import load_features
    from satagraph.datasets.sources import MotionFile
    from satagraph.io import write_bvh
    rig = zoo_rigs(["biped"])[0]
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    write_bvh(generate_clip(rig, "walk", frames=40, seed=1), tmp_path / "a" / "walk.bvh")
    (tmp_path / "b" / "walk.bvh").symlink_to(tmp_path / "a" / "walk.bvh")
    shutil.copytree(tmp_path / "a", tmp_path / "moved")
    paths = [tmp_path / d / "walk.bvh" for d in ("a", "b", "moved")]
    calls = []
    real = dataset.preprocess_file
    monkeypatch.setattr(dataset, "preprocess_file",
                        lambda path, config: calls.append(path) or real(path, config))
    files = [MotionFile(str(p), "d", "d", "train", scale=1.0) for p in paths]
    cache = tmp_path / "cache"
    feats = load_features(files, cache_dir=str(cache))
    assert len(calls) == 1 and len(list((cache / "processed").glob("*.npz"))) == 1
    np.testing.assert_array_equal(feats[0].x, feats[2].x)
    write_bvh(generate_clip(rig, "walk", frames=40, seed=2), paths[2])
    load_features(files, cache_dir=str(cache))
    assert calls[1:] == [str(paths[2])]
    assert len(list((cache / "processed").glob("*.npz"))) == 2


def test_a_folder_of_linked_folders_is_read(tmp_path):
    """A training folder assembled from links to dataset folders kept
    elsewhere is read through them (it was 'no .bvh files found'), and a
    link back to a folder above it is not followed round."""
    from satagraph.datasets.sources import bvh_files, scan_folder
    from satagraph.io import write_bvh
    store, mine = tmp_path / "store", tmp_path / "mine"
    (store / "deep").mkdir(parents=True)
    mine.mkdir()
    rig = zoo_rigs(["biped"])[0]
    for i, name in enumerate(("walk.bvh", "deep/run.bvh")):
        write_bvh(generate_clip(rig, "walk", frames=20, seed=i), store / name)
    (mine / "first").symlink_to(store, target_is_directory=True)
    (mine / "second").symlink_to(store / "deep", target_is_directory=True)
    (store / "deep" / "up").symlink_to(store, target_is_directory=True)  # a loop
    names = [p.relative_to(mine).as_posix() for p in bvh_files(mine)]
    assert names == ["first/deep/run.bvh", "first/walk.bvh", "second/run.bvh"]
    assert len(scan_folder(mine)) == 3
    # a loop across two folders (each links to the other) ends too
    (tmp_path / "a").mkdir(), (tmp_path / "b").mkdir()
    write_bvh(generate_clip(rig, "walk", frames=20, seed=3), tmp_path / "a" / "x.bvh")
    (tmp_path / "a" / "to_b").symlink_to(tmp_path / "b", target_is_directory=True)
    (tmp_path / "b" / "to_a").symlink_to(tmp_path / "a", target_is_directory=True)
    names = [p.relative_to(tmp_path).as_posix() for p in bvh_files(tmp_path / "a")]
    assert names == ["a/x.bvh"]


def test_rig_warnings_of_many_files_are_capped(tmp_path):
    """Files whose units no rig tells warn a line each for the first few,
    then one line counts the rest (a folder of 1 029 files printed 197
    warning lines)."""
    import warnings

    from satagraph.data.dataset import RIG_WARNINGS_SHOWN, try_load_features
    from satagraph.datasets.sources import MotionFile
    from satagraph.io import write_bvh
    from satagraph.transforms.rig_reading import UnitsWarning
    rig = zoo_rigs(["spider"])[0]  # an arthropod: no size tells its units
    files = []
    for i in range(RIG_WARNINGS_SHOWN + 4):
        path = tmp_path / f"spider_{i}.bvh"
        write_bvh(generate_clip(rig, "walk", frames=20, seed=i), path)
        files.append(MotionFile(str(path), "d", "d", "train", up_axis="+Y"))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        kept, _, errors = try_load_features(files, cache_dir=str(tmp_path / "cache"))
    units = [str(w.message) for w in said if issubclass(w.category, UnitsWarning)]
    assert len(kept) == len(files) and not errors
    assert len(units) == RIG_WARNINGS_SHOWN + 1
    assert all(files[i].path in units[i] for i in range(RIG_WARNINGS_SHOWN))
    assert units[-1].startswith("4 more units warnings")
