"""Weights files (safetensors): export, offline loading, ``builtin``, refusals."""
from __future__ import annotations

import json
import pickle
from pathlib import Path
from typing import Callable, List

import lightning as L
import numpy as np
import pytest
import torch
from safetensors.torch import save_file

import satagraph.io.weights as weights
from satagraph.cli import main
from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.pipelines.inference import reconstruct_motion
from satagraph.io import write_bvh
from satagraph.io.checkpoint import CheckpointError
from satagraph.io.weights import (NO_BUILTIN, WeightsSizeError, load_weights,
                                  read_weights_metadata, save_weights)
from satagraph.motion import Motion
from satagraph.experiment.train import load_module


@pytest.fixture(scope="module")
def zoo_clip() -> Motion:
    """A short quadruped walk of the procedural zoo."""
    rig = zoo_rigs(["quadruped"], seed=3)[0]
    return generate_clip(rig, "walk", frames=40, seed=1)


def _reconstruct(module: L.LightningModule, motion: Motion, embed: Callable) -> np.ndarray:
    return reconstruct_motion(module, motion, embed, window=16, overlap=4).rotations


def _no_pickle(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make any unpickling (torch.load included) fail."""
    def refuse(*args, **kwargs):
        raise AssertionError("unpickling while loading a weights file")
    monkeypatch.setattr(torch, "load", refuse)
    monkeypatch.setattr(pickle, "loads", refuse)
    monkeypatch.setattr(pickle, "load", refuse)


def test_export_and_reload_reconstruct_the_same(build_tiny_module: Callable, embed: Callable,
                                                zoo_clip: Motion, tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    module = build_tiny_module()
    expected = _reconstruct(module, zoo_clip, embed)
    full, half = tmp_path / "full.safetensors", tmp_path / "half.safetensors"
    size = save_weights(module, full, training_data="tiny test data",
                        provenance={"command": "pytest", "minutes": 0.1})
    assert size == full.stat().st_size
    assert save_weights(module, half, half=True) < size

    meta = read_weights_metadata(full)
    assert meta["provenance"] == {"command": "pytest", "minutes": 0.1}
    assert meta["training_data"] == "tiny test data"
    assert meta["semantic_encoder"] == "offline" and meta["window"] == module.meta["window"]
    assert meta["fps"] == module.fps and meta["dtype"] == "float32"

    _no_pickle(monkeypatch)  # the file carries no code: nothing is unpickled
    loaded = load_module(str(full))
    assert type(loaded) is type(module)
    np.testing.assert_array_equal(_reconstruct(loaded, zoo_clip, embed), expected)
    for key, value in module.normalizer.state_dict().items():
        torch.testing.assert_close(loaded.normalizer.state_dict()[key], value,
                                   rtol=0, atol=0)

    halved = load_weights(half)
    assert halved["weights_metadata"]["dtype"] == "float16"
    assert all(v.dtype != torch.float16 for v in halved["state_dict"].values())
    loaded = load_module(str(half))
    np.testing.assert_allclose(_reconstruct(loaded, zoo_clip, embed), expected, atol=0.05)


def _one_line_error(path: Path) -> str:
    with pytest.raises(CheckpointError) as info:
        load_module(str(path))
    text = str(info.value)
    assert "\n" not in text and str(path) in text
    return text


def test_foreign_or_damaged_files_give_one_line(build_tiny_module: Callable,
                                                tmp_path: Path) -> None:
    foreign = tmp_path / "other.safetensors"
    save_file({"weight": torch.ones(3)}, str(foreign), metadata={"format": "pt"})
    assert "not satagraph weights" in _one_line_error(foreign)

    good = tmp_path / "good.safetensors"
    save_weights(build_tiny_module(), good)
    data = good.read_bytes()
    cut = tmp_path / "cut.safetensors"
    cut.write_bytes(data[: len(data) // 2])
    assert "truncated" in _one_line_error(cut)
    head = tmp_path / "head.safetensors"
    head.write_bytes(data[:20])
    assert "truncated" in _one_line_error(head)

    # Metadata is JSON strings only, and the format is checked.
    meta = read_weights_metadata(good)
    assert json.loads(json.dumps(meta)) == meta
    with pytest.raises(CheckpointError, match="init-from|not satagraph"):
        from satagraph.experiment.train import init_weights
        init_weights(build_tiny_module(), str(foreign))


def test_size_limit(build_tiny_module: Callable, tmp_path: Path) -> None:
    path = tmp_path / "big.safetensors"
    with pytest.raises(WeightsSizeError, match=r"MB, over the .* --force"):
        save_weights(build_tiny_module(), path, max_bytes=1000)
    assert not path.exists()
    assert save_weights(build_tiny_module(), path, max_bytes=1000, force=True) > 1000


def test_the_same_weights_are_the_same_bytes(build_tiny_module: Callable,
                                             tmp_path: Path) -> None:
    """``safetensors.torch.save`` wrote the metadata in a hash map's order,
    new at every call: two exports of one checkpoint differed in their
    bytes (not their content), so a release could not be checked against a
    rebuild. Five saves of one module are one file, which reads back."""
    torch.manual_seed(0)
    module = build_tiny_module()
    paths = [tmp_path / f"w{i}.safetensors" for i in range(5)]
    for path in paths:
        save_weights(module, path, training_data="zoo", provenance={"command": "c", "é": 1})
    assert len({path.read_bytes() for path in paths}) == 1
    assert read_weights_metadata(paths[0])["training_data"] == "zoo"
    state = load_weights(paths[0])["state_dict"]
    assert all(torch.equal(state[k], v) for k, v in module.state_dict().items() if k in state)


def test_builtin_resolves_to_package_data(build_tiny_module: Callable, zoo_clip: Motion,
                                          tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture) -> None:
    clip = tmp_path / "walk.bvh"
    write_bvh(zoo_clip, clip)
    out = tmp_path / "out.bvh"
    monkeypatch.setattr(weights, "builtin_path",
                        lambda kind="autoencoder", name="builtin": tmp_path / "none.safetensors")
    assert main(["reconstruct", str(clip), str(out)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"satagraph: error: {NO_BUILTIN}"
    assert "Traceback" not in err and not out.exists()

    shipped = tmp_path / "builtin.safetensors"
    save_weights(build_tiny_module(), shipped,
                 provenance={"command": "satagraph train tiny", "minutes": 3.0,
                             "note": "a test model: limbs in step on zoo rigs only"})
    assert main(["reconstruct", "--ckpt", "builtin-wide", str(clip), str(out)]) == 2
    assert capsys.readouterr().err.strip() == (
        "satagraph: error: no builtin-wide weights are shipped in this version: train one "
        "with `satagraph train pretrain_zoo_wide` or pass another --ckpt")
    monkeypatch.setattr(weights, "builtin_path",
                        lambda kind="autoencoder", name="builtin": shipped)
    capsys.readouterr()
    assert main(["reconstruct", str(clip), str(out)]) == 0
    # the fallback says which model it used and what it can do, in one line
    err = capsys.readouterr().err.strip()
    assert err == ("satagraph: --ckpt auto (humans and animals of four limbs or fewer): "
                   "using the built-in model (satagraph train tiny, 3 min): "
                   "a test model: limbs in step on zoo rigs only")
    assert main(["reconstruct", "--ckpt", "builtin", str(clip), str(out)]) == 0
    assert out.is_file() and "using the built-in model" in capsys.readouterr().err
    assert main(["reconstruct", "--ckpt", str(shipped), str(clip), str(out)]) == 0
    assert "built-in" not in capsys.readouterr().err
    assert main(["reconstruct", "--ckpt", "builtin-wide", str(clip), str(out)]) == 0
    assert "using the built-in model builtin-wide (satagraph train tiny" in capsys.readouterr().err


def test_builtin_names() -> None:
    """``builtin`` names each kind's shipped weights; ``builtin-wide`` the
    other autoencoder only; any other name is a path."""
    assert weights.builtin_names() == ["builtin", "builtin-wide"]
    assert weights.builtin_names("text-to-motion") == ["builtin"]
    assert weights.is_builtin("builtin-wide") and not weights.is_builtin("builtin-wide", "text-to-motion")
    assert weights.builtin_path(name="builtin-wide").name == "builtin_wide.safetensors"
    assert weights.resolve_weights("runs/x.ckpt") == "runs/x.ckpt"
    with pytest.raises(ValueError, match="named"):
        weights.builtin_path("text-to-motion", "builtin-wide")
    with pytest.raises(CheckpointError, match="auto picks a built-in model by the rigs"):
        weights.resolve_weights("auto")


def test_builtin_path_is_package_data() -> None:
    path = weights.builtin_path()
    assert path.name == "builtin.safetensors" and path.parent.name == "weights"
    assert (path.parent / "__init__.py").is_file()
    setup = (Path(__file__).parents[2] / "setup.cfg").read_text()
    assert "satagraph.weights = *.safetensors" in setup


def _train_args(config_overrides: List[str], run: Path, *extra: str) -> List[str]:
    return ["--traceback", "train", "tiny", *config_overrides, f"output_dir={run}",
            "data.max_files=2", "trainer.max_epochs=1", "trainer.limit_train_batches=1",
            "trainer.limit_val_batches=0", *extra]


@pytest.fixture(scope="module")
def trained_run(config_overrides: List[str], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run folder of :func:`_train_args` trained by ``satagraph train``,
    once a module, for the tests that only read it."""
    run = tmp_path_factory.mktemp("trained") / "run"
    assert main(_train_args(config_overrides, run)) == 0
    return run


def test_export_weights_command_and_init_from(config_overrides: List[str], trained_run: Path,
                                              zoo_clip: Motion, tmp_path: Path,
                                              capsys: pytest.CaptureFixture) -> None:
    run = trained_run
    out = tmp_path / "w.safetensors"
    assert main(["--traceback", "export-weights", str(run), str(out), "--half",
                 "--minutes", "0.5", "--machine", "2-core CPU", "--command", "pytest"]) == 0
    assert "MB (float16 weights of" in capsys.readouterr().out
    meta = read_weights_metadata(out)
    assert meta["provenance"]["machine"] == "2-core CPU"
    assert meta["provenance"]["source"].endswith("last.ckpt")
    assert meta["training_data"] == meta["hyper_parameters"]["meta"]["data"]["sources"]

    clip = tmp_path / "walk.bvh"
    write_bvh(zoo_clip, clip)
    assert main(["--traceback", "reconstruct", "--ckpt", str(out), str(clip),
                 str(tmp_path / "o.bvh")]) == 0

    # --init-from a weights file: with lr = 0 the network stays as loaded.
    tuned = tmp_path / "tuned"
    assert main(_train_args(config_overrides, tuned, "optim.lr=0.0",
                            "--init-from", str(out))) == 0
    state = torch.load(tuned / "checkpoints" / "last.ckpt", weights_only=True)["state_dict"]
    source = load_weights(out)["state_dict"]
    for key, value in source.items():
        if key.startswith("model."):
            torch.testing.assert_close(state[key], value, rtol=0, atol=0, msg=key)

    assert main(["export-weights", str(tmp_path / "nothing"), str(tmp_path / "x.safetensors")]) == 2


def test_builtin_notice_stays_one_short_line(build_tiny_module: Callable, tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """A built-in model whose provenance tells its whole history gets a
    notice with the command's first clause and a pointer to the long note,
    not the history (the shipped ones were 1,000-1,400 characters)."""
    shipped = tmp_path / "builtin.safetensors"
    history = "satagraph train pretrain_zoo (stage 1: " + "resumed with optim.lr=1e-4; " * 20 + ")"
    save_weights(build_tiny_module(), shipped,
                 provenance={"command": history, "minutes": 723.0,
                             "machine": "a 2-core VM, one thread, beside other jobs",
                             "note": "in step on zoo rigs; " * 30})
    monkeypatch.setattr(weights, "builtin_path",
                        lambda kind="autoencoder", name="builtin": shipped)
    notice = weights.builtin_notice()
    assert notice == ("using the built-in model (satagraph train pretrain_zoo, 723 min, "
                      "a 2-core VM, one thread, beside other jobs): what it can and cannot "
                      "do: the provenance notes of satagraph.io.weights."
                      "read_weights_metadata(builtin_path())")
    assert "\n" not in notice and len(notice) < 300


@pytest.mark.parametrize("kind,name,call", [
    ("autoencoder", "builtin", "builtin_path()"),
    ("autoencoder", "builtin-wide", "builtin_path('autoencoder', 'builtin-wide')"),
    ("text-to-motion", "builtin", "builtin_path('text-to-motion')")])
def test_builtin_notice_points_to_what_an_installed_package_has(kind: str, name: str,
                                                                call: str) -> None:
    """The shipped models' notes are long: the notice names the call that
    reads them whole (a wheel has no README)."""
    notice = weights.builtin_notice(kind, name)
    assert "README" not in notice
    assert notice.endswith(f"satagraph.io.weights.read_weights_metadata({call})")
    assert len(notice) < 300


def test_init_normalizer_keeps_the_checkpoints_or_refits(config_overrides: List[str],
                                                         trained_run: Path, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture) -> None:
    """``--init-normalizer checkpoint`` starts from the checkpoint's feature
    statistics (here made unlike the data's), the default refits them on
    the config's data; without ``--init-from`` the flag is refused."""
    module = load_module(str(trained_run / "checkpoints" / "last.ckpt"))
    fitted = {k: v.clone() for k, v in module.state_dict().items() if k.startswith("normalizer.")}
    with torch.no_grad():
        module.normalizer.static_std.mul_(2.0)
        module.normalizer.root_mean.add_(0.5)
    odd = tmp_path / "odd.safetensors"
    weights.save_weights(module, odd)
    for choice, want in (("checkpoint", load_weights(odd)["state_dict"]), ("data", fitted)):
        tuned = tmp_path / choice
        assert main(_train_args(config_overrides, tuned, "optim.lr=0.0", "--init-from",
                                str(odd), "--init-normalizer", choice)) == 0
        state = torch.load(tuned / "checkpoints" / "last.ckpt", weights_only=True)["state_dict"]
        for key in ("normalizer.static_std", "normalizer.root_mean"):
            torch.testing.assert_close(state[key], want[key], msg=f"{choice} {key}")
    assert main(_train_args(config_overrides, tmp_path / "x", "--init-normalizer",
                            "checkpoint")[1:]) == 2  # without --traceback
    assert "--init-normalizer goes with --init-from CKPT" in capsys.readouterr().err


def test_builtin_notice_tells_the_first_training_of_a_re_exported_file(
        build_tiny_module: Callable, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A file re-exported with a part swapped in (its first training kept
    as ``previous``) is announced by its first training's command and
    machine and the minutes of both steps, not by the swap's."""
    shipped = tmp_path / "builtin.safetensors"
    first = {"command": "satagraph train pretrain_zoo", "minutes": 400.0,
             "machine": "a 2-core VM", "note": "short"}
    save_weights(build_tiny_module(), shipped,
                 provenance={"command": "satagraph train t2m_builtin --init-from it",
                             "minutes": 12.0, "machine": "the same VM", "note": "short",
                             "previous": first})
    monkeypatch.setattr(weights, "builtin_path",
                        lambda kind="autoencoder", name="builtin": shipped)
    assert weights.builtin_notice() == ("using the built-in model (satagraph train "
                                        "pretrain_zoo, 412 min, a 2-core VM): short")


def test_builtin_notice_tells_the_first_training_of_a_blend(
        build_tiny_module: Callable, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A blend (``export-weights --blend``: its base's provenance under
    ``blend.previous``) is announced by the base's first training and the
    minutes of every step: the fine-tune's, the base's and the base's own
    earlier file's."""
    shipped = tmp_path / "builtin.safetensors"
    first = {"command": "satagraph train pretrain_zoo", "minutes": 400.0,
             "machine": "a 2-core VM", "note": "short"}
    base = {"command": "satagraph train t2m_builtin --init-from it", "minutes": 12.0,
            "previous": first}
    save_weights(build_tiny_module(), shipped,
                 provenance={"command": "satagraph code-bank ...; satagraph train ...",
                             "minutes": 39.0, "machine": "the same VM", "note": "a blend",
                             "blend": {"base": "old.safetensors", "alpha": 0.5,
                                       "previous": base}})
    monkeypatch.setattr(weights, "builtin_path",
                        lambda kind="autoencoder", name="builtin": shipped)
    assert [p.get("minutes") for p in weights.provenance_chain(
        weights.read_weights_metadata(shipped)["provenance"])] == [39.0, 12.0, 400.0]
    assert weights.builtin_notice() == ("using the built-in model (satagraph train "
                                        "pretrain_zoo, 451 min, a 2-core VM): short")


def test_init_from_another_architecture_is_refused(config_overrides: List[str],
                                                   tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    """``--init-from builtin`` on a config of another size would fill 3 of
    102 weights and train from scratch under a fine-tune's name: refused in
    one line naming the settings to use, and no run folder is left."""
    run = tmp_path / "run"
    args = _train_args(config_overrides, run, "data.preprocessing.facing_smooth=0.25",
                       "--init-from", "builtin")[1:]  # without --traceback
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "another architecture" in err[-1] and "model.hidden_channels=64" in err[-1]
    assert "satagraph train finetune_builtin" in err[-1]
    assert not run.exists()


def test_the_fine_tune_config_is_the_builtin_models_architecture() -> None:
    """``finetune_builtin`` (README) builds what ``builtin`` holds: its model,
    losses, window and facing smoothing."""
    from satagraph.data.dataset import data_facing_smooth
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import load_weights_or_checkpoint
    cfg = load_config("finetune_builtin", ["data.sources=[mine]"])
    hp = load_weights_or_checkpoint("builtin")["hyper_parameters"]
    assert {k: v for k, v in hp["model"].items() if k != "semantic_channels"} == {
        k: cfg["model"][k] for k in hp["model"] if k != "semantic_channels"}
    assert hp["loss"] == {k: cfg["loss"][k] for k in hp["loss"]}
    assert cfg["data"]["window"] == hp["meta"]["window"]
    assert data_facing_smooth(cfg["data"]) == data_facing_smooth(hp["meta"]["data"])


def test_a_run_folder_names_its_last_checkpoint(tmp_path):
    """``--ckpt`` and ``--init-from`` take the folder ``satagraph train``
    wrote, as ``export-weights`` did (``generate`` refused it)."""
    from satagraph.io.checkpoint import CheckpointError
    from satagraph.io.weights import resolve_weights
    (tmp_path / "run" / "checkpoints").mkdir(parents=True)
    with pytest.raises(CheckpointError, match="a folder without checkpoints/last.ckpt"):
        resolve_weights(tmp_path / "run")
    (tmp_path / "run" / "checkpoints" / "last.ckpt").write_bytes(b"")
    assert resolve_weights(tmp_path / "run") == str(tmp_path / "run" / "checkpoints" /
                                                    "last.ckpt")
    assert resolve_weights(tmp_path / "x.ckpt") == str(tmp_path / "x.ckpt")
