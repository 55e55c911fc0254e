r"""The module registry: what a config's ``module:`` names.

A module registers under a name with :func:`register_module`, as a
decorator or a call, on a LightningModule class with the autoencoder
constructor ``(model, loss, optim, fps, meta)`` or on a builder function
that takes the module's own sections (:class:`ModuleSections`) and returns
the module. A name is registered once (a second registration raises).

Example::

    from satagraph.experiment.registry import register_module

    @register_module("my_vae")
    class MyModule(MotionAutoencoderModule):
        ...

    @register_module("t2m", datamodule=CaptionDataModule, data=CaptionDataConfig)
    def build_t2m(sections: ModuleSections) -> TextToMotionModule:
        return TextToMotionModule(**sections.kwargs())

The built-in modules (``vae``, ``rvq``, ``same``, ``padded_rvq``) register
when :mod:`satagraph.experiment.modules` is imported, on first look-up
(``t2m`` when :mod:`satagraph.experiment.t2m` is);
:data:`PLUGINS` names such modules, so that this registry imports no torch.
"""
from __future__ import annotations

import importlib
import sys
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterable, Optional

from satagraph.experiment.schema import (TRAINER_OPTIM, DataConfig, check_keys,
                                         unknown_key_error)


@dataclass(frozen=True)
class ModuleSections:
    r"""What a module builder gets: its own config sections.

    Args:
        model (dict): The ``model`` section.
        loss (dict): The ``loss`` section.
        optim (dict): The ``optim`` section.
        fps (float): Frame rate of the data.
        meta (dict): What inference needs to know about the data
            (``module``, ``semantic_encoder``, ``window``, ``data``).
    """

    model: Dict[str, Any] = field(default_factory=dict)
    loss: Dict[str, Any] = field(default_factory=dict)
    optim: Dict[str, Any] = field(default_factory=dict)
    fps: float = 30.0
    meta: Dict[str, Any] = field(default_factory=dict)

    def kwargs(self) -> Dict[str, Any]:
        """The sections as keyword arguments of the autoencoder constructor."""
        return {"model": dict(self.model), "loss": dict(self.loss),
                "optim": dict(self.optim), "fps": self.fps, "meta": dict(self.meta)}


#: A module builder: its sections -> the LightningModule.
Builder = Callable[[ModuleSections], Any]


@dataclass(frozen=True)
class ModuleEntry:
    r"""One registered module.

    Args:
        name (str): The ``module:`` name.
        build (callable): :class:`ModuleSections` -> LightningModule.
        cls (type, optional): The class registered (``None`` for a
            builder function).
        datamodule (callable, optional): ``data`` section (filled) -> data
            module (``None``: :class:`~satagraph.data.MotionDataModule`).
        data (type): Dataclass schema of the ``data`` section.
        model_keys (callable, optional): The ``model`` keys the builder
            takes (checked before building; ``None``: not checked).
        optim_keys (iterable, optional): The ``optim`` keys it takes
            besides the trainer's (:data:`~satagraph.experiment.schema.TRAINER_OPTIM`;
            ``None``: not checked).
    """

    name: str
    build: Builder
    cls: Optional[type] = None
    datamodule: Optional[Callable[..., Any]] = None
    data: type = DataConfig
    model_keys: Optional[Callable[[], Iterable[str]]] = None
    optim_keys: Optional[Iterable[str]] = None

    def check(self, sections: ModuleSections) -> None:
        """Raise one line for a ``model`` or ``optim`` key the builder does
        not take."""
        if self.model_keys is not None:
            check_keys("model", sections.model, self.model_keys())
        if self.optim_keys is not None:
            check_keys("optim", sections.optim, set(self.optim_keys) | set(TRAINER_OPTIM))


_REGISTRY: Dict[str, ModuleEntry] = {}

#: Names registered by importing a module on first look-up.
PLUGINS: Dict[str, str] = dict({name: "satagraph.experiment.modules"
                                for name in ("vae", "rvq", "same", "padded_rvq")},
                               t2m="satagraph.experiment.t2m")


def class_builder(cls: type) -> Builder:
    """The builder of a class with the autoencoder constructor."""
    def build(sections: ModuleSections):
        return cls(**sections.kwargs())
    build.__name__ = build.__qualname__ = f"build_{cls.__name__}"
    return build


def register_module(name: str, target: Any = None, *, datamodule: Optional[Callable] = None,
                    data: type = DataConfig,
                    model_keys: Optional[Callable[[], Iterable[str]]] = None,
                    optim_keys: Optional[Iterable[str]] = None):
    r"""Make a module selectable as ``module: name``.

    ``register_module(name)`` is a decorator; ``register_module(name,
    target)`` registers at once and returns :obj:`target`.

    Args:
        name (str): The ``module:`` name.
        target: A LightningModule class with the autoencoder constructor
            ``(model, loss, optim, fps, meta)``, or a builder function
            :class:`ModuleSections` -> module.
        datamodule, data, model_keys, optim_keys: See :class:`ModuleEntry`.

    Raises:
        ValueError: :obj:`name` is registered already.
    """
    def register(obj: Any) -> Any:
        owner = PLUGINS.get(name)
        if owner is not None and name not in _REGISTRY and owner not in sys.modules:
            importlib.import_module(owner)  # a built-in name is its own module's first
        if name in _REGISTRY:
            raise ValueError(f"module {name!r} is registered already (by "
                             f"{_REGISTRY[name].build.__qualname__}); pick another name")
        is_class = isinstance(obj, type)
        _REGISTRY[name] = ModuleEntry(name, class_builder(obj) if is_class else obj,
                                      obj if is_class else None, datamodule, data,
                                      model_keys, optim_keys)
        return obj
    return register if target is None else register(target)


def unregister_module(name: str) -> None:
    """Forget a registered module (tests, notebooks)."""
    _REGISTRY.pop(name, None)


def module_entry(name: str) -> ModuleEntry:
    """The entry registered under :obj:`name` (importing its plugin first
    when :data:`PLUGINS` names one)."""
    if name not in _REGISTRY and name in PLUGINS:
        importlib.import_module(PLUGINS[name])
    if name not in _REGISTRY:
        raise unknown_key_error("", name, registered_names(), what="module")
    return _REGISTRY[name]


def registered_names() -> list:
    """Every name a config's ``module:`` may take."""
    return sorted(set(_REGISTRY) | set(PLUGINS))


def module_class(name: str) -> type:
    """The LightningModule class registered under :obj:`name`."""
    entry = module_entry(name)
    if entry.cls is None:
        raise ValueError(f"module {name!r} is registered as a builder function, not a class")
    return entry.cls


def build_registered(name: str, sections: ModuleSections):
    """The module :obj:`name` built from :obj:`sections` (checked first)."""
    entry = module_entry(name)
    entry.check(sections)
    return entry.build(sections)


__all__ = ["ModuleSections", "ModuleEntry", "Builder", "PLUGINS", "register_module",
           "unregister_module", "module_entry", "module_class", "registered_names",
           "build_registered", "class_builder"]
