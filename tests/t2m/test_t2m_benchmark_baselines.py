"""benchmarks/t2m.py's baselines with a generator: the retrieved training
clip is retargeted onto the test clip's rig through the generator's frozen
SATA-RVQ, cut to the test clip's length."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import t2m  # noqa: E402
from satagraph.pipelines.generate import load_generator  # noqa: E402


def test_retrieval_is_retargeted_onto_each_test_rig(t2m_ckpt: Path) -> None:
    module = load_generator(str(t2m_ckpt))
    train = t2m.zoo_items("train", 6, keep=True)
    test = t2m.zoo_items("test", 3, keep=True)
    retrieved = [train[0], train[1], train[2]]
    out = t2m.retargeted_items(module, retrieved, test)
    assert [o.skeleton for o in out] == [t.skeleton for t in test]
    for got, src, it in zip(out, retrieved, test):
        # the test clip's captions and length (at most), the retrieved clip's motion
        assert got.captions == it.captions and got.label == it.label
        frames = min(src.motion.num_frames, it.motion.num_frames)
        assert abs(got.seconds - frames / t2m.FPS) < 1.5 / t2m.FPS
        assert np.isfinite(got.desc).all() and np.isfinite(got.travel).all()
    # a clip retargeted onto its own rig is its reconstruction
    same = t2m.retargeted_items(module, test[:1], test[:1])[0]
    recon = t2m.reconstructed_items(module, test[:1])[0]
    np.testing.assert_allclose(same.desc, recon.desc, atol=1e-5)


def test_reference_autoencoder_row_reconstructs_each_test_clip() -> None:
    """``--reference builtin``: each test clip through the built-in model on
    its own rig keeps its captions and length and is described closer to
    its own clip than to the others (zoo bipeds and quadrupeds, the body
    plans the built-in model was trained on)."""
    from satagraph.experiment.train import load_module
    test = [it for it in t2m.zoo_items("test", 12, keep=True)
            if it.skeleton in ("biped", "quadruped")][:4]
    assert len(test) >= 3
    out = t2m.autoencoded_items(load_module("builtin").eval(), test)
    for got, it in zip(out, test):
        assert got.captions == it.captions and got.skeleton == it.skeleton
        assert abs(got.seconds - it.seconds) < 1.5 / t2m.FPS
    own = np.array([[np.linalg.norm(a.desc - b.desc) for b in test] for a in out])
    others = np.where(np.eye(len(test), dtype=bool), np.inf, own)
    assert (own.diagonal() < others.min(axis=1)).mean() >= 0.75  # nearest to its own


def test_length_benchmark_reads_the_length_models_distribution(t2m_ckpt: Path) -> None:
    """benchmarks/t2m_length.py: the mean drawn duration per rig is the
    distribution's mean over the probe prompts, within the model's bins."""
    import torch
    import t2m_length
    from satagraph.datasets.zoo.endless import EndlessZoo
    module = load_generator(str(t2m_ckpt)).eval()
    motion = EndlessZoo(["biped"], fps=30.0, seed=0).sample(0, 0, 40, "val").motion
    row = t2m_length.rig_row(module, "a person", motion)
    seconds = module.length.bins_to_seconds(torch.arange(module.length.num_bins)).numpy()
    assert seconds[0] <= row["mean"] <= seconds[-1]
    assert 0.0 <= row["short"] <= 1.0 and row["spread"] >= 0.0
    p = t2m_length.distribution(module, "a person walks forward",
                                t2m_length.skeleton_token(module, motion))
    assert p.shape == seconds.shape and abs(p.sum() - 1.0) < 1e-6
    text = t2m_length.table({"tiny": {"rigs": {"zoo biped": row}, "bandai": None,
                                      "longest": float(seconds[-1])}}, 1.0)
    assert "| tiny | zoo biped |" in text
