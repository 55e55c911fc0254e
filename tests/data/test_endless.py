"""The endless zoo: samples deterministic in (seed, epoch, index), held-out
body plans and seeds, windows in the data module, mixing with files, and
exact resume of a run trained on it."""
from __future__ import annotations

from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest
import torch

from satagraph.experiment.config import load_config
from satagraph.data.collate import collate_clips
from satagraph.data.datamodule import MotionDataModule, semantic_embedder
from satagraph.data.endless import EndlessZooDataset, MixedDataset, zoo_entry
from satagraph.datasets.sources import resolve_sources
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.lightning.reliability import read_loss_log
from satagraph.experiment.train import train

HOLDOUT = "quadruped/abbrev"


def _entry(**extra) -> Dict:
    return dict({"zoo": "endless", "species": ["biped", "quadruped"],
                 "holdout_species": [HOLDOUT], "windows_per_epoch": 8,
                 "val_windows": 2, "test_windows": 2, "fit_windows": 4}, **extra)


def test_samples_are_a_function_of_the_key() -> None:
    zoo = EndlessZoo(["biped", "quadruped", "crab"], seed=5)
    a, b = zoo.sample(2, 7, 20), zoo.sample(2, 7, 20)
    assert a.motion.skeleton.names == b.motion.skeleton.names
    np.testing.assert_array_equal(a.motion.rotations, b.motion.rotations)
    np.testing.assert_array_equal(a.motion.skeleton.offsets, b.motion.skeleton.offsets)
    # another epoch, index, seed stream or seed: another rig (proportions)
    for other in (zoo.sample(3, 7, 20), zoo.sample(2, 7, 20, stream="val"),
                  EndlessZoo(["biped", "quadruped", "crab"], seed=6).sample(2, 7, 20)):
        assert other.species == a.species  # plans are visited in turn
        assert other.motion.skeleton.offsets.shape != a.motion.skeleton.offsets.shape \
            or not np.allclose(other.motion.skeleton.offsets, a.motion.skeleton.offsets)


def test_holdout_plans_are_never_drawn_in_training() -> None:
    zoo = EndlessZoo(["biped", "quadruped"], holdout=[HOLDOUT, "crab"])
    assert HOLDOUT not in zoo.plans() and "quadruped/mixamo" in zoo.plans()
    assert zoo.plans(holdout=True) == [HOLDOUT, "crab/plain", "crab/abdomen"]
    drawn = {zoo.sample(e, i, 8).plan for e in range(2) for i in range(12)}
    assert drawn == set(zoo.plans())
    held = {zoo.sample(0, i, 8, "val", holdout=True).plan for i in range(3)}
    assert held == set(zoo.plans(holdout=True))
    with pytest.raises(ValueError, match="unknown variant"):
        EndlessZoo(holdout=["quadruped/nope"])
    with pytest.raises(ValueError, match="every body plan is held out"):
        EndlessZoo(["crab"], holdout=["crab"])


def test_endless_windows_in_the_rest_inference_shows(tmp_path: Path) -> None:
    """With ``data.preprocessing.rest: auto`` a zoo window drawn with a
    line (axis) or captured rest is shown re-rested, as inference shows
    such a rig; with the default (``file``) as drawn. The motion is the
    same either way."""
    from satagraph.data.features import features_to_motion
    from satagraph.transforms.rest import is_line_rest, needs_rest
    plain = EndlessZooDataset(EndlessZoo(["biped"]), windows=8, window=16)
    shown = EndlessZooDataset(EndlessZoo(["biped"]), windows=8, window=16,
                              preprocessing={"rest": "auto"})
    drawn = [plain.features(0, i) for i in range(40)]
    posed = [i for i, (f, s) in enumerate(drawn) if needs_rest(f.skeleton)]
    assert posed and len(posed) < len(drawn)
    for i in posed[:3] + [next(i for i in range(40) if i not in posed)]:
        a, b = drawn[i][0], shown.features(0, i)[0]
        assert not is_line_rest(b.skeleton)
        np.testing.assert_allclose(features_to_motion(a).global_positions(),
                                   features_to_motion(b).global_positions(), atol=1e-6)
        assert np.allclose(a.static, b.static) is (i not in posed)


def test_window_clips_and_entry_checks(tmp_path: Path) -> None:
    ds = EndlessZooDataset(EndlessZoo(["bird"]), windows=4, window=16,
                           semantic=semantic_embedder("offline", str(tmp_path)))
    clip = ds[(1, 2)]
    assert tuple(clip.dynamic.shape[:2]) == (16, clip.parents.shape[0])
    assert clip.semantic.shape[0] == clip.parents.shape[0]
    assert clip.meta["dataset"] == "zoo-endless" and clip.meta["species"] == "bird"
    again = ds[(1, 2)]
    torch.testing.assert_close(again.dynamic, clip.dynamic, rtol=0, atol=0)
    assert ds[2].meta["path"] != clip.meta["path"]  # a plain index is epoch 0
    with pytest.raises(ValueError, match="unknown keys"):
        zoo_entry({"zoo": "endless", "specie": ["biped"]})


def test_datamodule_with_an_endless_zoo(tmp_path: Path) -> None:
    dm = MotionDataModule([_entry()], window=16, batch_size=4, cache_dir=str(tmp_path))
    dm.setup("fit")
    train_ds = dm.datasets["train"]
    assert isinstance(train_ds, MixedDataset) and len(train_ds) == 8 and train_ds.keyed
    assert bool(dm.normalizer.fitted)
    loader = dm.train_dataloader()
    keys = list(loader.sampler)
    assert all(isinstance(k, tuple) for k in keys)
    batch = next(iter(loader))
    assert torch.isfinite(batch.x).all()
    val = dm.datasets["val"]
    assert sorted({val[i].meta["dataset"] for i in range(len(val))}) == \
        ["zoo-endless", "zoo-endless-holdout"]
    assert {val[i].meta["skeleton"] for i in range(2, 4)} <= {HOLDOUT}
    assert dm.semantic_channels > 0


def test_include_keeps_cmu_clips_by_name(shared_data: Path) -> None:
    files = resolve_sources([{"path": str(shared_data / "manifest.tsv"), "dataset": "cmu",
                              "include": ["[0-9][0-9]_[0-9][0-9].bvh"]}])
    assert [Path(f.path).name for f in files] == ["01_01.bvh"]


def _overrides(root: Path) -> List[str]:
    entry = ("{zoo: endless, species: [biped, quadruped], holdout_species: "
             f"['{HOLDOUT}'], windows_per_epoch: 16, val_windows: 2, test_windows: 2, "
             "fit_windows: 4}")
    return [f"data.sources=[{entry}]", f"data.cache_dir={root / 'cache'}",
            "data.window=16", "data.batch_size=4", "data.max_files=null",
            "logger.name=none", "trainer.progress=false",
            "trainer.enable_model_summary=false", "trainer.max_epochs=2",
            "trainer.limit_train_batches=null", "trainer.limit_val_batches=1",
            "trainer.num_sanity_val_steps=0", "trainer.deterministic=true", "threads=1",
            "checkpoint.every_n_steps=3", "loss_log=true"]


@pytest.mark.slow
def test_resume_on_the_endless_zoo_gives_the_same_losses(tmp_path: Path) -> None:
    """Stopped after 4 steps (checkpoint at step 3), resumed: the same
    windows, the same losses as an uninterrupted run."""
    overrides = _overrides(tmp_path)
    train(load_config("tiny", overrides + [f"output_dir={tmp_path / 'a'}"]))
    full = read_loss_log(tmp_path / "a" / "losses.tsv")
    assert len(full) == 8
    cfg = load_config("tiny", overrides + [f"output_dir={tmp_path / 'b'}"])
    train(cfg, max_steps=4)
    train(cfg, resume=True)
    assert read_loss_log(tmp_path / "b" / "losses.tsv") == full


def test_augmenting_a_zoo_alone_is_said_to_change_nothing(tmp_path: Path) -> None:
    """``data.augment`` on zoo sources alone trained bit for bit as without
    it (the zoo's windows are drawn on new rigs already), unsaid."""
    dm = MotionDataModule([_entry()], window=16, batch_size=4, cache_dir=str(tmp_path),
                          augment=True)
    with pytest.warns(UserWarning, match="data.augment changes no window here"):
        dm.setup("fit")
