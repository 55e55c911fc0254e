"""Weight-space blends of a fine-tune with its starting point
(:mod:`satagraph.experiment.blend`, ``export-weights --blend``)."""
from __future__ import annotations

from pathlib import Path
from typing import Dict

import numpy as np
import pytest
import torch
from torch import Tensor

from satagraph.cli import main
from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.experiment.blend import blend_state
from satagraph.experiment.train import load_module
from satagraph.io.weights import (load_weights, read_weights_metadata, resolve_weights,
                                   save_weights)
from satagraph.pipelines.inference import reconstruct_motion


@pytest.fixture(scope="module")
def base() -> Dict[str, Tensor]:
    return load_module("builtin").state_dict()


@pytest.fixture(scope="module")
def tuned_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``builtin`` with every weight moved, as a fine-tune that kept its
    normaliser would move them (its own file)."""
    module = load_module("builtin")
    gen = torch.Generator().manual_seed(0)
    with torch.no_grad():
        for key, tensor in module.state_dict().items():
            if tensor.is_floating_point() and not key.startswith("normalizer."):
                tensor.add_(0.05 * torch.randn(tensor.shape, generator=gen))
    path = tmp_path_factory.mktemp("blend") / "tuned.safetensors"
    save_weights(module, path)
    return path


def test_blend_interpolates_every_float_tensor(base: Dict[str, Tensor],
                                               tuned_file: Path) -> None:
    tuned = load_weights(tuned_file)["state_dict"]
    assert blend_state(base, tuned, 0.0).keys() == tuned.keys()
    for alpha in (0.0, 0.3, 1.0):
        out = blend_state(base, tuned, alpha)
        for key in [k for k in tuned if k.endswith(".weight")][:5]:
            want = (1 - alpha) * base[key] + alpha * tuned[key]
            torch.testing.assert_close(out[key], want, rtol=0, atol=1e-6)
        for key in ("normalizer.fitted", "normalizer.root_std"):
            assert torch.equal(out[key], tuned[key])
    key = next(k for k in tuned if k.endswith(".weight"))
    assert not torch.equal(blend_state(base, tuned, 0.5)[key], base[key])


@pytest.mark.parametrize("change, message", [
    (lambda s: s.pop("normalizer.root_std"), "1 weights only in one, e.g. "
                                             "'normalizer.root_std' in base"),
    (lambda s: s.update({"normalizer.root_std": torch.ones(7)}), "'normalizer.root_std' is (7,)"),
    (lambda s: s.update({"normalizer.body_relative": ~s["normalizer.body_relative"]}),
     "'normalizer.body_relative' differs and is not a weight"),
    (lambda s: s.update({"normalizer.static_std": 1.03 * s["normalizer.static_std"]}),
     "'normalizer.static_std' differs and is not a weight (the two read their features "
     "otherwise: fine-tune with --init-normalizer checkpoint to blend)"),
])
def test_blend_refuses_another_network(base: Dict[str, Tensor], change, message: str) -> None:
    tuned = dict(base)
    change(tuned)
    with pytest.raises(ValueError, match="cannot blend tuned with base") as err:
        blend_state(base, tuned, 0.5)
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("alpha", [-0.1, 1.5])
def test_blend_refuses_alpha_outside_unit_interval(base: Dict[str, Tensor], alpha: float) -> None:
    with pytest.raises(ValueError, match=r"--alpha must be in \[0, 1\]"):
        blend_state(base, base, alpha)


def test_export_weights_blend_writes_the_blend(base: Dict[str, Tensor], tuned_file: Path,
                                               tmp_path: Path) -> None:
    out = tmp_path / "blend.safetensors"
    assert main(["export-weights", str(tuned_file), str(out), "--blend", "builtin",
                 "--alpha", "0.25"]) == 0
    written = load_weights(out)
    tuned = load_weights(tuned_file)["state_dict"]
    for key, value in written["state_dict"].items():
        if value.is_floating_point():
            torch.testing.assert_close(value, 0.75 * base[key] + 0.25 * tuned[key],
                                       rtol=0, atol=1e-6, msg=key)
    blend = written["weights_metadata"]["provenance"]["blend"]
    assert (blend["base"], blend["alpha"]) == ("builtin", 0.25)
    # how builtin was made stays with it
    assert blend["previous"] == read_weights_metadata(resolve_weights("builtin"))["provenance"]
    # alpha 0 is builtin itself: the same reconstruction of a zoo clip
    zero = tmp_path / "zero.safetensors"
    assert main(["export-weights", str(tuned_file), str(zero), "--blend", "builtin",
                 "--alpha", "0"]) == 0
    clip = generate_clip(zoo_rigs(["quadruped"], seed=3)[0], "walk", frames=40, seed=1)
    got = [reconstruct_motion(load_module(p), clip).rotations for p in ("builtin", str(zero))]
    np.testing.assert_allclose(got[1], got[0], atol=1e-4)


def test_export_weights_blend_refusals(tuned_file: Path, tmp_path: Path,
                                       capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "x.safetensors"
    assert main(["export-weights", str(tuned_file), str(out), "--blend", "builtin"]) == 2
    assert "--blend BASE and --alpha A go together" in capsys.readouterr().err
    assert main(["export-weights", "builtin-wide", str(out), "--blend", "builtin",
                 "--alpha", "0.5"]) == 2
    assert "facing_smooth 0.0 in one and 0.25 in the other" in capsys.readouterr().err
    assert not out.exists()


def test_export_weights_refuses_an_output_that_is_no_weights_file(
        tuned_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """``export-weights w.safetensors last.ckpt`` (the arguments swapped)
    wrote the weights over the checkpoint; a name not ending in
    .safetensors is refused before anything is read."""
    ckpt = tmp_path / "last.ckpt"
    ckpt.write_bytes(b"a checkpoint")
    for target in (ckpt, tmp_path / "w.bvh"):
        assert main(["export-weights", str(tuned_file), str(target)]) == 2
        assert "must end in .safetensors" in capsys.readouterr().err
    assert ckpt.read_bytes() == b"a checkpoint" and not (tmp_path / "w.bvh").exists()
