"""``satagraph demo`` end to end on a tiny configuration: zoo, a few
training steps, retargeting, rendering."""
import json
from pathlib import Path

import numpy as np
import pytest

from satagraph.cli import main
from satagraph.io import read_bvh

FRAMES = 30
TINY = ["trainer.max_steps=3", "trainer.accelerator=cpu", "trainer.progress=false",
        "trainer.enable_model_summary=false", "data.window=16", "data.stride=16",
        "data.batch_size=4", "model.hidden_channels=16", "model.ff_channels=32",
        "model.num_blocks=1", "model.heads=2", "model.latent_channels=8"]


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """Run the demo once: 3 species, one 30-frame clip per skeleton, 3
    training steps."""
    out = tmp_path_factory.mktemp("demo")
    argv = ["demo", *TINY, "--output", str(out), "--species", "biped", "quadruped",
            "bird", "--clips", "1", "--frames", str(FRAMES), "--minutes", "1"]
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SATAGRAPH_CACHE", str(out / "cache"))
        code = main(argv)
    assert code == 0
    return out, json.loads((out / "summary.json").read_text())


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
    assert gif.n_frames == FRAMES
    assert gif.size[0] == 4 * gif.size[1]  # four square panels side by side
    sheet = Image.open(out / "demo_sheet.png")
    assert sheet.size[0] == gif.size[0] and sheet.size[1] > gif.size[1]


def test_quick_demo_still_available(capsys, tmp_path):
    assert main(["demo", "--quick", "--output", str(tmp_path)]) == 0
    assert "built-in example walk" in capsys.readouterr().out
    assert read_bvh(tmp_path / "example_walk.bvh").num_frames == 60
