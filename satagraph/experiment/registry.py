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

A subclass of a built-in module registered without ``model_keys`` /
``optim_keys`` has its config keys checked as its base class's are: the
``model`` keys of its base (with the named arguments of its own
``build_model``, or only those when that takes no ``**kwargs``), and the
``optim`` keys unless it has its own ``configure_optimizers``.

The command line (``train``, ``eval``, ``sweep``, ``reconstruct`` ...) finds
modules and layers of one's own (:func:`~satagraph.nn.register_local_conv`)
through the environment variable :data:`PLUGIN_VARIABLE`: every command
imports the Python modules (or ``.py`` files) it names, comma-separated,
first; from Python, a ``module:`` name not registered imports them too::

    SATAGRAPH_PLUGINS=my_models satagraph train my_config.yaml
"""
from __future__ import annotations

import importlib
import importlib.util
import inspect
import os
import re
import sys
from dataclasses import dataclass, field, fields
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
        extra (dict): A subclass's own constructor arguments beyond these
            five (``z_weight`` of ``__init__(self, model, ..., z_weight=0.1)``):
            a config's ``module_args`` section, or what its checkpoint saved
            (:func:`class_arguments`); a class's builder passes them on, a
            builder function reads them here.
    """

    model: Dict[str, Any] = field(default_factory=dict)
    loss: Dict[str, Any] = field(default_factory=dict)
    optim: Dict[str, Any] = field(default_factory=dict)
    fps: float = 30.0
    meta: Dict[str, Any] = field(default_factory=dict)
    extra: Dict[str, Any] = field(default_factory=dict)

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
        not take (a class whose ``model`` keys are not known is built once to
        find out)."""
        if self.cls is not None:  # before a build, which a bad one fails unsaid
            check_arguments(self.cls, sections.extra)
        if self.model_keys is not None:
            check_keys("model", sections.model, self.model_keys())
        elif self.cls is not None:
            self._try_build(sections)
        if self.optim_keys is not None:
            check_keys("optim", sections.optim, set(self.optim_keys) | set(TRAINER_OPTIM))

    def _try_build(self, sections: ModuleSections) -> None:
        """Build the class once: a ``model`` key its network does not take
        is one line before any data is read, not a traceback after."""
        try:
            self.build(sections)
        except NotImplementedError as err:  # a hook left out: one line, not a traceback
            raise ValueError(f"module {self.name!r}: {err}") from None
        except TypeError as err:
            bad = re.search(r"unexpected keyword argument '(\w+)'", str(err))
            if bad is None or bad.group(1) not in sections.model:
                raise
            raise ValueError(f"unknown config key 'model.{bad.group(1)}': "
                             f"{self.cls.__name__}'s network does not take it ({err})") from None


_REGISTRY: Dict[str, ModuleEntry] = {}

#: Names registered by importing a module on first look-up.
PLUGINS: Dict[str, str] = dict({name: "satagraph.experiment.modules"
                                for name in ("vae", "rvq", "same", "padded_rvq")},
                               t2m="satagraph.experiment.t2m")


#: Environment variable naming the user's plugin modules (see the module).
PLUGIN_VARIABLE = "SATAGRAPH_PLUGINS"
_IMPORTED_PLUGINS: set = set()


def import_user_plugins() -> None:
    """Import each module or ``.py`` file that :data:`PLUGIN_VARIABLE`
    names (once per process; one that failed is tried again on the next
    call, as a notebook calls after fixing it).

    Raises:
        ValueError: One line naming a plugin that does not import (not
            found, or its own code fails: a syntax error, an exception,
            ``sys.exit()``) and the first line of its error.
    """
    for spec in (s.strip() for s in os.environ.get(PLUGIN_VARIABLE, "").split(",")):
        if not spec or spec in _IMPORTED_PLUGINS:
            continue
        _IMPORTED_PLUGINS.add(spec)
        try:
            if spec.endswith(".py"):
                name = f"satagraph_plugin_{len(_IMPORTED_PLUGINS)}"
                loader = importlib.util.spec_from_file_location(name, spec)
                if loader is None or not os.path.isfile(spec):
                    raise ImportError("no such file")
                module = importlib.util.module_from_spec(loader)
                sys.modules[name] = module
                loader.loader.exec_module(module)
            else:
                importlib.import_module(spec)
        except (Exception, SystemExit) as err:  # not found, or its own code failed
            _IMPORTED_PLUGINS.discard(spec)  # (--traceback: where)
            missing = isinstance(err, ImportError)
            first = next(iter(str(err).splitlines()), "")  # one line, also of sys.exit()
            said = first if missing else ": ".join(filter(None, (type(err).__name__, first)))
            raise ValueError(f"{PLUGIN_VARIABLE}: cannot import {spec!r} ({said})") \
                from (None if missing else err)


def _inherited_keys(cls: type) -> tuple:
    """``(model_keys, optim_keys)`` a class inherits from the nearest
    registered class it derives from, or from
    :class:`~satagraph.lightning.MotionAutoencoderModule` (its ``optim``
    keys; see the module)."""
    from satagraph.lightning.autoencoder import DEFAULT_OPTIM, MotionAutoencoderModule
    _load_builtins()
    bases = [(e.cls, e.model_keys, e.optim_keys)
             for c in cls.__mro__[1:] for e in _REGISTRY.values() if e.cls is c]
    if not bases and not issubclass(cls, MotionAutoencoderModule):
        return None, None
    base, model_keys, optim_keys = bases[0] if bases else (
        MotionAutoencoderModule, None, DEFAULT_OPTIM)
    build = getattr(cls, "build_model", None)
    if build is not getattr(base, "build_model", None) and model_keys is not None:
        params = list(inspect.signature(build).parameters.values())[1:]
        named = {p.name for p in params if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
        inherited = model_keys
        model_keys = ((lambda: set(inherited()) | named)
                      if any(p.kind == p.VAR_KEYWORD for p in params) else (lambda: named))
    own_optimizer = getattr(cls, "configure_optimizers", None) is not getattr(
        base, "configure_optimizers", None)
    return model_keys, None if own_optimizer else optim_keys


#: The sections every module takes (``model``, ``loss``, ``optim``, ``fps``,
#: ``meta``): a constructor's own arguments are the others.
SECTION_NAMES = frozenset(f.name for f in fields(ModuleSections)) - {"extra"}


def own_arguments(cls: type) -> tuple:
    """``(names, takes_any)``: the constructor arguments of :obj:`cls`
    beyond the five sections, and whether it takes ``**kwargs``."""
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    named = {p.name for p in params if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
    return named - SECTION_NAMES, any(p.kind == p.VAR_KEYWORD for p in params)


def check_arguments(cls: type, extra: Dict[str, Any]) -> None:
    """Raise one line for a ``module_args`` key :obj:`cls`'s constructor
    does not take (any, where it takes ``**kwargs``)."""
    named, takes_any = own_arguments(cls)
    if takes_any or not extra:
        return
    if not named:
        raise ValueError(f"module_args.{next(iter(extra))}: {cls.__name__} takes no "
                         "arguments beyond its model, loss, optim, fps and meta sections")
    check_keys("module_args", extra, named)


def class_arguments(cls: Optional[type], hparams: Dict[str, Any]) -> Dict[str, Any]:
    """The hyperparameters beyond the five sections that :obj:`cls`'s
    constructor takes (all of them when it takes ``**kwargs``; none for a
    builder function, :obj:`cls` ``None``), as Lightning's
    ``load_from_checkpoint`` passes them; a list where the constructor's
    default is a tuple is a tuple again (:func:`_tuple_defaults`)."""
    if cls is None:
        return {}
    named, takes_any = own_arguments(cls)
    tuples = _tuple_defaults(cls)
    return {k: tuple(v) if k in tuples and isinstance(v, list) else v
            for k, v in hparams.items() if k not in SECTION_NAMES and (takes_any or k in named)}


def _tuple_defaults(cls: type) -> set:
    """The constructor arguments of :obj:`cls` whose default is a tuple: a
    weights file keeps hyperparameters as JSON, whose lists they are read
    back as (:func:`class_arguments` makes them tuples again)."""
    params = inspect.signature(cls.__init__).parameters.values()
    return {p.name for p in params if isinstance(p.default, tuple)}


def class_builder(cls: type) -> Builder:
    """The builder of a class with the autoencoder constructor (and the
    subclass's own arguments, :attr:`ModuleSections.extra`)."""
    def build(sections: ModuleSections):
        return cls(**sections.kwargs(), **sections.extra)
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
        keys = (model_keys, optim_keys)
        if is_class and keys == (None, None):
            keys = _inherited_keys(obj)
        _REGISTRY[name] = ModuleEntry(name, class_builder(obj) if is_class else obj,
                                      obj if is_class else None, datamodule, data, *keys)
        return obj
    return register if target is None else register(target)


def _load_builtins() -> None:
    """Register the built-in autoencoder modules (their keys are inherited)."""
    owner = PLUGINS["vae"]
    if owner not in sys.modules:
        importlib.import_module(owner)


def unregister_module(name: str) -> None:
    """Forget a registered module (tests, notebooks)."""
    _REGISTRY.pop(name, None)


def module_entry(name: str) -> ModuleEntry:
    """The entry registered under :obj:`name` (importing its plugin first
    when :data:`PLUGINS` names one)."""
    if name not in _REGISTRY and name in PLUGINS:
        importlib.import_module(PLUGINS[name])
    if name not in _REGISTRY:
        import_user_plugins()
    if name not in _REGISTRY:
        err = unknown_key_error("", name, registered_names(), what="module")
        raise ValueError(f"{err} (a module of your own: name the code that registers it "
                         f"in {PLUGIN_VARIABLE}, e.g. {PLUGIN_VARIABLE}=my_models)")
    return _REGISTRY[name]


def registered_name(cls: type) -> Optional[str]:
    """The one name :obj:`cls` is registered under (the built-in modules
    registered first), or ``None`` where it is registered under none or
    several: what a module built by hand records as its ``meta.module``."""
    _load_builtins()
    names = [name for name, entry in _REGISTRY.items() if entry.cls is cls]
    return names[0] if len(names) == 1 else None


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


__all__ = ["ModuleSections", "ModuleEntry", "Builder", "PLUGINS", "PLUGIN_VARIABLE",
           "import_user_plugins", "register_module", "registered_name",
           "unregister_module", "module_entry", "module_class", "registered_names",
           "build_registered", "class_arguments", "class_builder", "own_arguments",
           "check_arguments"]
