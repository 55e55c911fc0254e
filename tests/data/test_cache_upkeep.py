"""Upkeep of the processed-feature cache: reads mark entries used,
``satagraph cache`` shows, prunes and clears them, and touches nothing else."""
from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from satagraph.cli import main
from satagraph.data.cache import cache_usage, feature_cache_dir, prune_cache
from satagraph.data.dataset import load_features
from satagraph.datasets.sources import scan_folder

DAY = 86400.0


@pytest.fixture
def cached(tmp_path: Path):
    """Two zoo files read once into a cache of their own; their entries."""
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "zoo", species=["biped"], clips=2, frames=8)
    files = scan_folder(tmp_path / "zoo")[:2]
    root = tmp_path / "cache"
    load_features(files, cache_dir=str(root))
    entries = sorted(feature_cache_dir(str(root)).glob("*.npz"))
    assert len(entries) == 2
    return files, root, entries


def _age(path: Path, days: float) -> None:
    then = time.time() - days * DAY
    os.utime(path, (then, then))


def test_a_read_marks_the_entry_used(cached) -> None:
    files, root, entries = cached
    for path in entries:
        _age(path, 40)
    load_features(files[:1], cache_dir=str(root))  # served from the cache
    ages = sorted((time.time() - p.stat().st_mtime) / DAY for p in entries)
    assert ages[0] < 1 and ages[1] > 39


def test_prune_removes_the_unread_entries_only(cached) -> None:
    _, root, entries = cached
    folder = feature_cache_dir(str(root))
    _age(entries[0], 40)
    other = folder / "notes.txt"  # not the cache's: never removed
    other.write_text("mine")
    _age(other, 400)
    size = entries[0].stat().st_size
    assert prune_cache(folder, unused_days=30) == (1, size)
    assert not entries[0].exists() and entries[1].exists() and other.exists()
    assert cache_usage(folder).entries == 1
    size = entries[1].stat().st_size
    assert prune_cache(folder) == (1, size)
    assert cache_usage(folder).entries == 0 and other.read_text() == "mine"
    with pytest.raises(ValueError, match="days unused must be 0 or more"):
        prune_cache(folder, unused_days=-1)


def test_the_cache_command_shows_prunes_and_clears(cached, capsys) -> None:
    _, root, entries = cached
    folder = feature_cache_dir(str(root))
    _age(entries[0], 40)
    assert main(["cache", "--dir", str(root)]) == 0
    shown = capsys.readouterr().out
    assert f"{folder}: 2 feature entries" in shown and "least recently 40 days ago" in shown
    assert main(["cache", "--dir", str(root), "--prune", "30"]) == 0
    shown = capsys.readouterr().out
    assert "removed 1 entry" in shown and f"{folder}: 1 feature entry," in shown
    assert main(["cache", "--dir", str(root), "--clear"]) == 0
    assert f"{folder}: no feature entries" in capsys.readouterr().out
    assert main(["cache", "--dir", str(tmp := root / "none")]) == 0
    assert f"{tmp / 'processed'}: no feature entries" in capsys.readouterr().out


def test_the_cache_command_refuses_the_feature_folder_as_its_root(cached, capsys) -> None:
    """``--dir`` given the folder the command prints (``ROOT/processed``)
    looked in ``ROOT/processed/processed``: 'no feature entries', and
    ``--clear`` removed nothing, without a word."""
    _, root, entries = cached
    folder = feature_cache_dir(str(root))
    assert main(["cache", "--dir", str(folder), "--clear"]) == 2
    assert capsys.readouterr().err.strip() == (
        f"satagraph: error: cache --dir {folder}: the feature folder itself; --dir takes "
        f"the cache root that holds it: --dir {root}")
    assert all(p.exists() for p in entries)


def test_a_run_served_from_the_cache_says_the_rig_warnings_again(tmp_path: Path) -> None:
    """A quadruped in centimetres that no manifest or file tells: the first
    run warned that its units are unknown, a second run from the cache said
    nothing."""
    from satagraph.datasets.zoo import Dialect, write_zoo
    from satagraph.transforms.rig_reading import UnitsWarning
    write_zoo(tmp_path / "zoo", species=["quadruped"], clips=1, frames=8,
              dialects=[Dialect(unit="cm")])
    (tmp_path / "zoo" / "manifest.tsv").unlink()
    files = scan_folder(tmp_path / "zoo")[:1]
    said = []
    for _ in range(2):
        with pytest.warns(UnitsWarning) as caught:
            load_features(files, cache_dir=str(tmp_path / "cache"))
        said.append([str(w.message) for w in caught if w.category is UnitsWarning])
    assert len(said[0]) == 1 and f"{files[0].path}: units unknown" in said[0][0]
    assert said[1] == said[0]


def test_a_data_module_caps_its_rig_warnings_over_all_splits(tmp_path: Path) -> None:
    """Each split capped its own: a folder of quadrupeds whose units no file
    tells said three warnings and a count per split ("1 more units warnings
    like those above", then six more)."""
    from satagraph.data.datamodule import MotionDataModule
    from satagraph.datasets.zoo import Dialect, write_zoo
    from satagraph.transforms.rig_reading import UnitsWarning
    write_zoo(tmp_path / "zoo", species=["quadruped"], clips=3, frames=20,
              dialects=[Dialect(unit="cm")])
    (tmp_path / "zoo" / "manifest.tsv").unlink()
    files = scan_folder(tmp_path / "zoo")
    splits = {f.split for f in files}
    assert len(files) > 4 and len(splits) >= 2
    dm = MotionDataModule(str(tmp_path / "zoo"), window=8, stride=8, batch_size=2,
                          cache_dir=str(tmp_path / "cache"))
    with pytest.warns(UnitsWarning) as caught:
        dm._read_splits()
    said = [str(w.message) for w in caught if w.category is UnitsWarning]
    assert len(said) == 4 and said[-1].startswith(f"{len(files) - 3} more units warnings")


def test_a_clear_while_a_run_reads_is_a_miss_said_nothing_of(cached, monkeypatch) -> None:
    """``satagraph cache --clear`` between a run's look for an entry and its
    read of it: the run warned of an "unreadable cache entry" (No such
    file or directory); it computes the features again, silently."""
    import warnings
    from satagraph.data import cache as cache_mod
    files, root, entries = cached
    before = load_features(files, cache_dir=str(root))
    load = cache_mod.np.load

    def cleared_meanwhile(path, **kwargs):
        prune_cache(feature_cache_dir(str(root)))  # the other process's --clear
        return load(path, **kwargs)
    monkeypatch.setattr(cache_mod.np, "load", cleared_meanwhile)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = load_features(files, cache_dir=str(root))
    assert [f.x_local.tobytes() for f in again] == [f.x_local.tobytes() for f in before]
