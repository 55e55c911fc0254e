"""A second device without a GPU: :class:`HostTracker` follows which tensors
would stay on the host (CPU) were the model and batch on an accelerator, and
records every operation that would mix them with device tensors there
(``Expected all tensors to be on the same device``) or read a device tensor
into NumPy (``can't convert cuda tensor to numpy``).

Every tensor that exists when the tracker starts (parameters, buffers, the
batch) counts as on the device; a factory without ``device=`` (``torch.zeros``,
``torch.arange``, ``torch.tensor``, ``torch.from_numpy``, ...) and
``Tensor.cpu`` make host tensors; other operations give a host tensor only
where all their tensor inputs are host tensors.
"""
from __future__ import annotations

import traceback
from typing import Any, Dict, List, Optional

import torch
from torch.overrides import TorchFunctionMode
from torch.utils._pytree import tree_flatten
from torch.utils.weak import WeakIdKeyDictionary

_FACTORIES = {torch.zeros, torch.ones, torch.empty, torch.full, torch.arange, torch.tensor,
              torch.as_tensor, torch.from_numpy, torch.rand, torch.randn, torch.randint,
              torch.randperm, torch.eye, torch.linspace, torch.logspace}
#: Tensor methods, by name (torch passes them as ``TensorBase`` methods).
_TO_HOST = {"cpu"}
_TO_NUMPY = {"numpy", "__array__"}
#: Indexing an accelerator tensor with host indices (and copying across
#: devices) is allowed by torch.
_INDEXING = {"__getitem__", "__setitem__", "copy_"}


def _tensors(args: Any, kwargs: Optional[Dict[str, Any]]) -> List[torch.Tensor]:
    leaves, _ = tree_flatten((args, kwargs or {}))
    return [t for t in leaves if isinstance(t, torch.Tensor)]


class HostTracker(TorchFunctionMode):
    r"""Records (in :attr:`mixes`) each operation that would mix host and
    device tensors, with the line of ``satagraph`` that ran it.

    Args:
        module (torch.nn.Module, optional): Where given, only its parameters
            and buffers start on the device (an inference pipeline: files
            and caches are read on the host); else every existing tensor.
    """

    def __init__(self, module: Optional[torch.nn.Module] = None) -> None:
        super().__init__()
        self.on_host = WeakIdKeyDictionary()
        self.default_host = module is not None
        if module is not None:
            for t in list(module.parameters()) + list(module.buffers()):
                self.on_host[t] = False
        self.mixes: List[str] = []

    def _is_host(self, t: torch.Tensor) -> bool:
        return self.on_host.get(t, self.default_host)

    def _record(self, func: Any, why: str) -> None:
        frames = [f for f in traceback.extract_stack()
                  if "/satagraph/" in f.filename and "/tests/" not in f.filename]
        where = f"{frames[-1].filename}:{frames[-1].lineno}" if frames else "?"
        self.mixes.append(f"{where}: {getattr(func, '__name__', func)}: {why}")

    def _made_on_host(self, func: Any, name: str, args: tuple, kwargs: Dict[str, Any],
                      host: List[torch.Tensor], device: List[torch.Tensor]) -> bool:
        """Whether :obj:`func`'s output would be on the host (recording a mix)."""
        if func in _FACTORIES:
            return kwargs.get("device") is None
        if name in _TO_HOST:
            return True
        targets = list(args[1:]) + [kwargs.get("device")]
        if name == "to" and any(isinstance(a, (str, torch.device)) for a in targets):
            # torch.device(...) is the model's here (x.device), a "cpu" string the host
            return any(isinstance(a, str) and a.startswith("cpu") for a in targets)
        if device and any(t.dim() > 0 for t in host) and name not in _INDEXING:
            self._record(func, "host and device tensors mixed")
        return bool(host) and not device

    def __torch_function__(self, func, types, args=(), kwargs=None):
        kwargs = kwargs or {}
        out = func(*args, **kwargs)
        name = getattr(func, "__name__", "")
        if name in ("cpu", "to") and out is args[0]:  # a copy on a real second device
            out = out.view_as(out)
        inputs = _tensors(args, kwargs)
        host = [t for t in inputs if self._is_host(t)]
        device = [t for t in inputs if not self._is_host(t)]
        if name in _TO_NUMPY and device:
            self._record(func, "a device tensor read into NumPy")
        made_on_host = self._made_on_host(func, name, args, kwargs, host, device)
        for t in _tensors(out, None):
            self.on_host[t] = made_on_host
        return out
