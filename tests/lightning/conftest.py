"""Fixtures of the Lightning tests: a small manifest of short real files, a
tiny config, a set-up data module and tiny modules."""
from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List

import lightning as L
import pytest

from satagraph.experiment.config import load_config
from satagraph.data.collate import FrameBatch
from satagraph.data.datamodule import MotionDataModule, semantic_embedder
from satagraph.experiment.train import build_datamodule, build_module

#: Datasets of the test manifest, in the order the splits list them, so
#: that ``max_files=2`` keeps one file of each dataset per split.
DATASETS = ("bandai", "dog")
WINDOW = 16


def _shortest(rows: List[Dict[str, str]], dataset: str, split: str,
              count: int) -> List[Dict[str, str]]:
    """The :obj:`count` shortest files (in seconds) of a dataset split."""
    chosen = [r for r in rows if r["dataset"] == dataset and r["split"] == split]
    chosen.sort(key=lambda r: (int(r["frames"]) / float(r["fps"]), r["path"]))
    return chosen[:count]


@pytest.fixture(scope="session", autouse=True)
def _private_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Feature and embedding caches in a temporary folder, never in ``~``."""
    path = tmp_path_factory.mktemp("satagraph_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SATAGRAPH_CACHE", str(path))
        yield path


@pytest.fixture(scope="session")
def small_manifest(shared_data: Path, manifest: List[Dict[str, str]],
                   tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A manifest of the shortest bandai and dog files: two training files
    and one validation and one test file per dataset, interleaved."""
    rows = []
    for split, count in (("train", 2), ("val", 1), ("test", 1)):
        per = [_shortest(manifest, d, split, count) for d in DATASETS]
        rows += [r for group in zip(*per) for r in group]
    path = tmp_path_factory.mktemp("manifest") / "manifest.tsv"
    lines = ["path\tdataset\tskeleton\tsplit"]
    lines += [f"{shared_data / r['path']}\t{r['dataset']}\t{r['skeleton']}\t{r['split']}"
              for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="session")
def config_overrides(small_manifest: Path, _private_cache: Path) -> List[str]:
    """Dotted overrides of ``experiments/tiny.yaml`` for fast CPU runs."""
    return [f"data.sources=[{small_manifest}]", f"data.cache_dir={_private_cache}",
            f"data.window={WINDOW}", f"data.stride={WINDOW}", "data.batch_size=4",
            "data.max_files=null", "logger.name=csv", "trainer.progress=false",
            "trainer.enable_model_summary=false", "trainer.log_every_n_steps=1",
            "trainer.limit_train_batches=2", "trainer.limit_val_batches=1"]


@pytest.fixture(scope="session")
def _base_config(config_overrides: List[str]) -> Dict[str, Any]:
    return load_config("tiny", config_overrides)


@pytest.fixture
def tiny_config(_base_config: Dict[str, Any], tmp_path: Path) -> Dict[str, Any]:
    """The tiny config (plain dict, a fresh copy) writing under ``tmp_path``."""
    cfg = copy.deepcopy(_base_config)
    cfg["output_dir"] = str(tmp_path / "run")
    return cfg


@pytest.fixture(scope="session")
def datamodule(_base_config: Dict[str, Any]) -> MotionDataModule:
    """The set-up data module of the tiny config (shared: do not modify)."""
    dm = build_datamodule(_base_config)
    dm.setup("fit")
    return dm


@pytest.fixture
def build_tiny_module(tiny_config: Dict[str, Any],
                      datamodule: MotionDataModule) -> Callable[..., L.LightningModule]:
    """Factory ``build_tiny_module(name="vae", **model)``: a seeded tiny
    module with the data module's normaliser (``model``: config overrides)."""
    def build(name: str = "vae", **model: Any) -> L.LightningModule:
        L.seed_everything(0, verbose=False)
        cfg = dict(tiny_config, module=name)
        if name == "rvq":
            cfg["model"] = dict(cfg["model"], codebook_size=16, num_quantizers=2)
        cfg["model"] = dict(cfg["model"], **model)
        return build_module(cfg, datamodule)
    return build


@pytest.fixture
def train_batch(datamodule: MotionDataModule) -> FrameBatch:
    """The first (unshuffled) batch of training windows: 4 clips."""
    return next(iter(datamodule._loader("train", False)))


@pytest.fixture(scope="session")
def embed() -> Callable:
    """The offline semantic embedder used in training."""
    return semantic_embedder("offline")
