"""The README's subclassing example runs as written, and trains."""
from __future__ import annotations

import re
from pathlib import Path

import torch

from satagraph.experiment.registry import register_module, unregister_module

README = Path(__file__).resolve().parents[2] / "README.md"


def _subclass_example() -> str:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    chosen = [b for b in blocks if "MotionAutoencoderModule" in b and "class " in b]
    assert chosen, "README lost its subclassing example"
    return chosen[0]


def test_readme_subclass_example_runs(tiny_config, datamodule, train_batch):
    scope: dict = {}
    exec(compile(_subclass_example(), str(README), "exec"), scope)
    base = scope["MotionAutoencoderModule"]
    (cls,) = [v for v in scope.values()
              if isinstance(v, type) and issubclass(v, base) and v is not base]
    register_module("readme_example", cls)
    try:
        from satagraph.experiment.train import build_module
        module = build_module(dict(tiny_config, module="readme_example"), datamodule)
        assert type(module) is cls
        torch.manual_seed(0)
        out = module(train_batch)
        losses = module.compute_losses(out, train_batch)
        assert torch.isfinite(losses["loss"])
        losses["loss"].backward()
        grads = [p.grad for p in module.parameters() if p.grad is not None]
        assert grads and all(torch.isfinite(g).all() for g in grads)
    finally:
        unregister_module("readme_example")
