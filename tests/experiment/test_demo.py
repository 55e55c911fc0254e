"""``satagraph demo`` end to end on a tiny configuration: zoo, a few
training steps, retargeting, rendering."""
import json
from pathlib import Path
from typing import Optional

import numpy as np
import pytest

from satagraph.cli import main
from satagraph.io import read_bvh

FRAMES = 30
TINY = ["trainer.max_steps=3", "trainer.accelerator=cpu", "trainer.progress=false",
        "trainer.enable_model_summary=false", "data.window=16", "data.stride=16",
        "data.batch_size=4", "model.hidden_channels=16", "model.ff_channels=32",
        "model.num_blocks=1", "model.heads=2", "model.latent_channels=8"]


SMALL = ["--species", "biped", "quadruped", "bird", "--clips", "1", "--frames", str(FRAMES),
         "--minutes", "1"]


def _run_demo(out: Path, argv, builtin: Optional[Path] = None) -> dict:
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SATAGRAPH_CACHE", str(out / "cache"))
        if builtin is not None:
            mp.setattr("satagraph.io.weights.builtin_path",
                       lambda kind="autoencoder", name="builtin": builtin)
        assert main(["demo", *argv, "--output", str(out), *SMALL]) == 0
    return json.loads((out / "summary.json").read_text())


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """Run the demo from scratch once: 3 species, one 30-frame clip per
    skeleton, 3 training steps of a tiny model."""
    out = tmp_path_factory.mktemp("demo")
    return out, _run_demo(out, [*TINY, "--from-scratch"])


@pytest.fixture(scope="module")
def demo_weights(demo, tmp_path_factory):
    """The demo's tiny model exported as a weights file."""
    weights = tmp_path_factory.mktemp("weights") / "builtin.safetensors"
    assert main(["export-weights", str(demo[0] / "run"), str(weights)]) == 0
    return weights


@pytest.fixture(scope="module")
def demo_builtin(demo_weights, tmp_path_factory):
    """The demo with a built-in model (the tiny one above, exported as a
    weights file): retarget and render with it, then fine-tune it."""
    out = tmp_path_factory.mktemp("demo_builtin")
    tiny = [o for o in TINY if not o.startswith("model.")]
    return out, _run_demo(out, tiny, builtin=demo_weights), demo_weights


@pytest.mark.slow
def test_builtin_model_retargets_first_then_fine_tunes(demo_builtin, capsys):
    """With built-in weights the GIF comes from them in seconds; the
    fine-tune starts from them (same architecture) and both models' retargets
    are scored with numbers a user can read."""
    import torch
    from satagraph.io.weights import load_weights

    out, summary, weights = demo_builtin
    names = [s["name"] for s in summary["steps"]]
    assert names == ["zoo", "retarget", "render", "train", "fine-tuned"]
    assert (out / "demo.gif").is_file() and (out / "retarget_finetuned").is_dir()
    for step in (summary["steps"][1], summary["steps"][4]):
        assert set(step["quality"]) == {"quadruped", "bird", "rescaled human"}
        for quality in step["quality"].values():
            assert -1.0 <= quality["steps"] <= 1.0 and quality["travel"] >= 0.0
            assert quality["stride"] > 0.0
            assert quality["lands"] is None or 0.0 <= quality["lands"] <= 1.0
        assert quality["lands"] is not None  # the rescaled human's feet, against its own walk
        assert "steps" in step["note"] and "travel" in step["note"] and "stride" in step["note"]
        assert " down " in step["note"]
    tuned = torch.load(out / "run" / "checkpoints" / "last.ckpt", weights_only=True)
    base = load_weights(weights)
    assert tuned["hyper_parameters"]["model"] == base["hyper_parameters"]["model"]
    assert "3 steps" in summary["steps"][3]["note"]


def test_builtin_fine_tune_refuses_a_new_architecture(demo_weights, tmp_path):
    """model.* overrides would not fit the built-in weights: one clear error."""
    from satagraph.experiment.demo import DemoOptions, demo_config
    from satagraph.io.weights import load_weights

    base = load_weights(demo_weights)["hyper_parameters"]
    with pytest.raises(ValueError, match="--from-scratch"):
        demo_config(DemoOptions(overrides=["model.hidden_channels=8"]), [], tmp_path, base)


def test_steps_and_summary(demo, capsys):
    out, summary = demo
    assert [s["name"] for s in summary["steps"]] == ["zoo", "train", "retarget", "render"]
    assert all(s["seconds"] > 0 for s in summary["steps"])
    for step in summary["steps"]:
        for path in step["written"]:
            assert Path(path).is_file(), path
    assert (out / "zoo" / "manifest.tsv").is_file()
    assert (out / "run" / "checkpoints" / "last.ckpt").is_file()
    assert "3 steps" in summary["steps"][1]["note"]


def test_retargeted_files(demo):
    out, summary = demo
    written = summary["steps"][2]["written"]
    source = read_bvh(next(p for p in written if Path(p).name.startswith("source_")))
    assert source.num_frames == FRAMES
    outputs = {Path(p).name: read_bvh(p) for p in written
               if Path(p).name.startswith("walk_on_")}
    assert len(outputs) == 3
    rows = (out / "zoo" / "manifest.tsv").read_text().splitlines()
    for name, motion in outputs.items():
        assert motion.num_frames == FRAMES and motion.fps == source.fps
        if name.endswith("_rescaled.bvh"):
            truth = read_bvh(out / "retarget" / name.replace("walk_on_", "ground_truth_"))
            assert motion.skeleton.names == truth.skeleton.names
            np.testing.assert_allclose(motion.skeleton.offsets, truth.skeleton.offsets,
                                       atol=1e-4)
            assert not np.allclose(motion.skeleton.offsets, source.skeleton.offsets,
                                   atol=1e-3)
            continue
        species, rig = name[len("walk_on_"):-len(".bvh")].split("-", 1)
        target = next(r.split("\t")[0] for r in rows if f"-{species}-{rig}_" in r)
        skeleton = read_bvh(out / "zoo" / target).skeleton
        assert motion.skeleton.names == skeleton.names
        assert motion.skeleton.parents.tolist() == skeleton.parents.tolist()
        np.testing.assert_allclose(motion.skeleton.offsets, skeleton.offsets, atol=1e-4)


def test_rendering(demo):
    from PIL import Image

    out, _ = demo
    gif = Image.open(out / "demo.gif")
    assert gif.n_frames == 33 and gif.info["duration"] == 30  # 1 s at 30 fps, shown at 33.3
    assert gif.size[0] == 4 * gif.size[1]  # four square panels side by side
    sheet = Image.open(out / "demo_sheet.png")
    assert sheet.size[0] == gif.size[0] and sheet.size[1] > gif.size[1]


def test_quick_demo_still_available(capsys, tmp_path):
    assert main(["demo", "--quick", "--output", str(tmp_path)]) == 0
    assert "built-in example walk" in capsys.readouterr().out
    assert read_bvh(tmp_path / "example_walk.bvh").num_frames == 60


def test_a_second_demo_into_one_folder_is_refused_before_any_step(capsys, tmp_path):
    """A second ``satagraph demo`` in the same folder (the default
    ``demo_output``) removed the first's checkpoints while it trained, then
    failed on its run lock with a traceback."""
    from satagraph.lightning.reliability import run_lock
    kept = tmp_path / "run" / "checkpoints" / "last.ckpt"
    kept.parent.mkdir(parents=True)
    kept.write_bytes(b"the first demo's")
    with run_lock(tmp_path):  # the first demo, still running
        code = main(["demo", "--output", str(tmp_path), *TINY, "--from-scratch", *SMALL])
    err = capsys.readouterr().err.strip()
    assert code == 1 and kept.read_bytes() == b"the first demo's"
    assert err.startswith(f"satagraph: error: {tmp_path}: --output is in use by another live ")
    assert len(err.splitlines()) == 1 and not (tmp_path / "zoo").exists()


def test_a_missing_data_folder_is_refused_before_any_step(capsys, tmp_path):
    """``demo --data MISSING`` wrote the zoo into a new ``--output`` folder,
    then failed on the missing source, leaving the folder behind."""
    out = tmp_path / "new"
    code = main(["demo", "--output", str(out), "--data", str(tmp_path / "missing"), *SMALL])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err == (f"satagraph: error: motion source not found: "
                                 f"{tmp_path / 'missing'}; " + err.split("; ", 1)[1])
    assert len(err.splitlines()) == 1 and not out.exists()


@pytest.mark.parametrize("argv, said", [
    (["nosuch.key=1"], "unknown config key 'nosuch'"),
    (["--config", "nosuch"], "config 'nosuch' not found")])
def test_a_refused_config_is_said_before_any_step(capsys, tmp_path, argv, said):
    """A bad override or config was refused after the zoo, the built-in
    model's retargets and their rendering were written into ``--output``."""
    out = tmp_path / "new"
    assert main(["demo", "--output", str(out), *argv, *SMALL]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"satagraph: error: {said}") and len(err.splitlines()) == 1
    assert not out.exists()


def test_builtin_fine_tune_keeps_the_builtin_facing_features(demo_weights, tmp_path):
    """The fine-tune featurises the zoo as the built-in weights were
    trained (``data.preprocessing.facing_smooth``), so ``--init-from``
    accepts them whatever that value is."""
    import copy

    from satagraph.experiment.demo import DemoOptions, demo_config
    from satagraph.experiment.train import check_init_features
    from satagraph.io.weights import load_weights

    payload = load_weights(demo_weights)
    for smooth in (0.0, 0.25):
        base = copy.deepcopy(payload["hyper_parameters"])
        base["meta"].setdefault("data", {})["preprocessing"] = {"facing_smooth": smooth}
        cfg = demo_config(DemoOptions(), [], tmp_path, base)
        assert cfg["data"]["preprocessing"]["facing_smooth"] == smooth
        check_init_features({"hyper_parameters": base}, cfg, "builtin")
