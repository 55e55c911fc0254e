"""The module registry: a decorator, a duplicate check, builders that take
their own sections, a data module and data schema per module."""
from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from typing import Any, List

import pytest
import torch

from satagraph.experiment.config import load_config
from tests.conftest import save_module_checkpoint
from satagraph.experiment.registry import (ModuleSections, module_class, module_entry,
                                           register_module, registered_names,
                                           unregister_module)


@pytest.fixture
def names():
    """Names registered by a test, forgotten after it."""
    taken: List[str] = []
    yield taken
    for name in taken:
        unregister_module(name)


def test_builtins_are_registered():
    from satagraph.lightning import (PaddedRVQModule, SAMEModule, SATARVQModule,
                                     SATAVAEModule)
    assert {"vae", "rvq", "same", "padded_rvq"} <= set(registered_names())
    assert module_class("vae") is SATAVAEModule and module_class("rvq") is SATARVQModule
    assert module_class("same") is SAMEModule
    assert module_class("padded_rvq") is PaddedRVQModule


def test_decorated_class_builds_from_a_config(names):
    from satagraph.experiment.train import build_module
    from satagraph.lightning import SATAVAEModule

    @register_module("test_vae")
    class TestVAE(SATAVAEModule):
        pass

    names.append("test_vae")
    module = build_module(load_config("tiny", ["module=test_vae"]))
    assert type(module) is TestVAE and module.meta["module"] == "test_vae"


def test_builder_function_takes_its_own_sections(names, tmp_path):
    """A module with another constructor (e.g. text-to-motion) builds itself
    from its sections; its data section has a schema of its own."""
    from satagraph.experiment.train import build_datamodule, build_module
    seen = {}

    @dataclass
    class CaptionData:
        sources: Any = None
        window: int = 96
        mirror: float = 0.5

    class CaptionModule(torch.nn.Module):
        def __init__(self, width: int, **kwargs: Any) -> None:
            super().__init__()
            self.layer = torch.nn.Linear(width, width)

    @register_module("test_t2m", datamodule=lambda **data: data, data=CaptionData)
    def build(sections: ModuleSections) -> CaptionModule:
        seen.update(sections.kwargs())
        return CaptionModule(**sections.model)

    names.append("test_t2m")
    path = tmp_path / "t2m.yaml"
    path.write_text("module: test_t2m\nmodel: {width: 4}\noptim: {weight_decay: 1}\n"
                    "data: {sources: [z], mirror: 0.0}\n")
    cfg = load_config(str(path))
    assert cfg["data"] == {"sources": ["z"], "window": 96, "mirror": 0.0}
    module = build_module(cfg)
    assert isinstance(module, CaptionModule)
    assert seen["model"] == {"width": 4} and seen["optim"]["weight_decay"] == 1
    assert seen["meta"]["window"] == 96 and seen["fps"] == 30.0
    assert build_datamodule(cfg) == {"sources": ["z"], "window": 96, "mirror": 0.0}
    with pytest.raises(ValueError, match="not a class"):
        module_class("test_t2m")
    with pytest.raises(ValueError, match=r"unknown config key 'data\.stride'"):
        load_config("tiny", ["module=test_t2m"])  # tiny's data is not a caption data set


def test_a_name_registers_once(names):
    register_module("test_once", lambda sections: None)
    names.append("test_once")
    with pytest.raises(ValueError, match="'test_once' is registered already"):
        register_module("test_once", lambda sections: None)
    with pytest.raises(ValueError, match="'vae' is registered already"):
        module_entry("vae")  # imports the built-ins
        register_module("vae")(type("Other", (), {}))


def test_unknown_module_names_the_closest():
    with pytest.raises(ValueError, match=r"unknown module 'samee' \(did you mean 'same'\?\)"):
        module_entry("samee")


def test_t2m_data_schema_is_its_data_module_signature():
    """``module: t2m`` checks ``data`` against CaptionDataModule's arguments,
    whose defaults stay in its signature (``seed``: the run's)."""
    import inspect
    from satagraph.data.caption_datamodule import CaptionDataModule
    from satagraph.experiment.schema import defaults
    entry = module_entry("t2m")
    assert entry.datamodule is CaptionDataModule
    signature = inspect.signature(CaptionDataModule).parameters
    schema = defaults(entry.data)
    assert set(schema) == set(signature) and schema["seed"] is None
    assert all(schema[k] == p.default for k, p in signature.items()
               if k not in ("seed", "sources"))
    with pytest.raises(ValueError, match=r"'data.min_frame' \(did you mean 'min_frames'\?\)"):
        load_config("t2m_tiny", ["data.min_frame=8"])


def test_a_built_in_name_is_taken_before_its_module_is_imported(tmp_path, monkeypatch, names):
    """A name of :data:`PLUGINS` whose module nothing has imported yet (``vae``
    in a fresh process) was taken silently, and ``load_module("builtin")``
    then built the user's class: its module registers it first."""
    import sys
    from satagraph.experiment import registry
    (tmp_path / "fake_builtin_plugin.py").write_text(
        "from satagraph.experiment.registry import register_module\n"
        "register_module('test_builtin', lambda sections: 'built-in')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(registry.PLUGINS, "test_builtin", "fake_builtin_plugin")
    monkeypatch.delitem(sys.modules, "fake_builtin_plugin", raising=False)
    names.append("test_builtin")
    with pytest.raises(ValueError, match="'test_builtin' is registered already"):
        register_module("test_builtin", lambda sections: "mine")
    assert module_entry("test_builtin").build(None) == "built-in"


def _check(name: str, overrides: List[str]) -> None:
    from satagraph.experiment.train import check_config
    check_config(load_config("tiny", [f"module={name}", "data.sources=[zoo]"] + overrides))


def test_a_subclass_has_its_keys_checked_as_its_base_class(names):
    """Registered as the README shows, a subclass took any ``optim`` key
    (a typo trained with the default) and failed on a ``model`` typo with
    a traceback once the data had loaded."""
    from satagraph.lightning import MotionAutoencoderModule, SATAVAEModule
    from satagraph.nn import SATA

    class Plain(MotionAutoencoderModule):
        def build_model(self, **kwargs):
            return SATA(**dict(kwargs, bottleneck="vae"))

    class Widened(SATAVAEModule):
        def build_model(self, width: int = 2, **kwargs):
            return super().build_model(**kwargs)

    class OwnOptimiser(SATAVAEModule):
        def configure_optimizers(self):
            return torch.optim.SGD(self.parameters(), lr=float(self.optim["lr"]))

    for name, cls in (("plain", Plain), ("widened", Widened), ("own_optim", OwnOptimiser)):
        register_module(name, cls)
        names.append(name)
    for name in ("plain", "widened"):
        with pytest.raises(ValueError, match=r"optim.lrr' \(did you mean 'lr'\?\)"):
            _check(name, ["optim.lrr=0.5"])
    with pytest.raises(ValueError, match=r"unknown config key 'model.hiden_channels': Plain's"):
        _check("plain", ["model.hiden_channels=16"])
    with pytest.raises(ValueError, match=r"model.hiden_channels' \(did you mean"):
        _check("widened", ["model.hiden_channels=16"])
    _check("widened", ["model.width=3"])
    _check("own_optim", ["optim.momentum=0.9"])  # its optimiser reads what it likes


def test_a_subclass_without_a_network_is_one_line(names):
    """A subclass of the base module that does not override
    ``build_model`` (the README lists it among the hooks) was a bare
    ``NotImplementedError`` and a 20-line traceback from ``satagraph
    train``; the check before any data is read now says what to do."""
    from satagraph.lightning import MotionAutoencoderModule

    class NoNetwork(MotionAutoencoderModule):
        pass

    register_module("no_network", NoNetwork)
    names.append("no_network")
    with pytest.raises(ValueError, match=r"module 'no_network': NoNetwork builds no network: "
                       r".*override build_model.*SATAVAEModule"):
        _check("no_network", [])


def test_the_command_line_finds_modules_named_in_the_plugin_variable(
        names, tmp_path, monkeypatch):
    from satagraph.experiment import registry
    plugin = tmp_path / "my_models.py"
    plugin.write_text("from satagraph.experiment.registry import register_module\n"
                      "from satagraph.lightning import SATAVAEModule\n"
                      "register_module('from_plugin', type('P', (SATAVAEModule,), {}))\n")
    with pytest.raises(ValueError, match="SATAGRAPH_PLUGINS"):
        module_entry("from_plugin")
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    monkeypatch.setenv("SATAGRAPH_PLUGINS", f" {plugin} ")
    names.append("from_plugin")
    assert module_entry("from_plugin").cls.__name__ == "P"
    monkeypatch.setenv("SATAGRAPH_PLUGINS", "no_such_module_here")
    with pytest.raises(ValueError, match="SATAGRAPH_PLUGINS: cannot import 'no_such_module_here'"):
        module_entry("another_unknown")


def test_a_plugin_whose_own_code_fails_is_one_line_naming_it(tmp_path, monkeypatch, capsys):
    """A plugin file with a syntax error or a raise at import was a Python
    traceback (18 lines from ``satagraph generate``, exit code 1); it is the
    one line of a plugin that does not import, with what failed."""
    from satagraph.cli import main
    from satagraph.experiment import registry
    broken, raising = tmp_path / "broken.py", tmp_path / "raising.py"
    broken.write_text("def broken(:\n")
    raising.write_text("raise RuntimeError('needs a GPU')\n")
    for plugin, why in ((broken, r"SyntaxError: invalid syntax"),
                        (raising, r"RuntimeError: needs a GPU")):
        monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
        monkeypatch.setenv("SATAGRAPH_PLUGINS", str(plugin))
        with pytest.raises(ValueError, match=rf"^SATAGRAPH_PLUGINS: cannot import "
                           rf"'{re.escape(str(plugin))}' \({why}"):
            registry.import_user_plugins()
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    assert main(["inspect", str(tmp_path)]) == 2  # the plugins come first
    err = capsys.readouterr().err
    assert err == f"satagraph: error: SATAGRAPH_PLUGINS: cannot import '{raising}' " \
                  "(RuntimeError: needs a GPU)\n"


@pytest.mark.parametrize("code, why", [
    ("raise SystemExit('no GPU here')", "SystemExit: no GPU here"),
    ("import sys\nsys.exit(3)", "SystemExit: 3"),
    ("raise RuntimeError('needs a GPU\\nsee the README')", "RuntimeError: needs a GPU"),
    ("raise RuntimeError()", "RuntimeError")])
def test_a_plugin_s_exit_or_long_error_is_one_line(tmp_path, monkeypatch, capsys, code, why):
    """A plugin calling ``sys.exit()`` ended the command with its code and
    no line naming it (``no GPU here``, exit code 1); an error of several
    lines was printed whole."""
    from satagraph.cli import main
    from satagraph.experiment import registry
    plugin = tmp_path / "mine.py"
    plugin.write_text(code + "\n")
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    monkeypatch.setenv("SATAGRAPH_PLUGINS", str(plugin))
    assert main(["inspect", str(tmp_path)]) == 2
    assert capsys.readouterr().err == (f"satagraph: error: SATAGRAPH_PLUGINS: cannot import "
                                       f"'{plugin}' ({why})\n")


def test_a_plugin_that_failed_is_imported_once_fixed(tmp_path, monkeypatch):
    """A plugin that failed to import was marked imported all the same: a
    notebook that fixed it and called again went on without it (its modules
    then ``unknown``, said to be named in ``SATAGRAPH_PLUGINS``, which they are)."""
    from satagraph.experiment import registry
    plugin, marker = tmp_path / "mine.py", tmp_path / "imported"
    plugin.write_text("def broken(:\n")
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    monkeypatch.setenv("SATAGRAPH_PLUGINS", str(plugin))
    with pytest.raises(ValueError, match="SyntaxError"):
        registry.import_user_plugins()
    plugin.write_text(f"open({str(marker)!r}, 'w').close()\n")  # fixed
    registry.import_user_plugins()
    assert marker.is_file()


def test_load_module_keeps_a_subclass_s_own_hyperparameters(names, tmp_path):
    """A subclass with a constructor argument of its own came back from
    ``load_module`` (what ``eval``, ``reconstruct``, ``retarget`` and
    ``sweep`` read) with its default, silently: only the five sections were
    passed on."""
    from satagraph.experiment.train import build_module, load_module
    from satagraph.lightning import SATAVAEModule

    @register_module("test_extra")
    class Weighted(SATAVAEModule):
        def __init__(self, model, loss=None, optim=None, fps=30.0, meta=None,
                     z_weight: float = 0.1, taps: tuple = (1,)) -> None:
            super().__init__(model, loss, optim, fps, meta)
            self.z_weight, self.taps = z_weight, taps

    names.append("test_extra")
    built = build_module(load_config("tiny", ["module=test_extra", "model.semantic_channels=0"]))
    module = Weighted(**{k: built.hparams[k] for k in ("model", "loss", "optim", "fps",
                                                       "meta")}, z_weight=0.7, taps=(2, 3))
    module.normalizer.fitted.fill_(True)
    path = tmp_path / "weighted.ckpt"
    save_module_checkpoint(module, path)
    loaded = load_module(str(path))
    assert type(loaded) is Weighted
    assert loaded.z_weight == 0.7 and loaded.hparams["z_weight"] == 0.7
    # a weights file keeps them too: ``export-weights`` wrote only the five
    # sections, and the file loaded back with z_weight 0.1, silently
    from satagraph.io.weights import read_weights_metadata, save_weights
    save_weights(module, tmp_path / "weighted.safetensors")
    assert read_weights_metadata(tmp_path / "weighted.safetensors")[
        "hyper_parameters"]["z_weight"] == 0.7
    from_file = load_module(str(tmp_path / "weighted.safetensors"))
    # JSON has no tuples: the file's [2, 3] is the tuple the constructor defaults to again
    assert from_file.z_weight == 0.7 and from_file.taps == (2, 3)
    assert load_module(str(path)).taps == (2, 3)
    module.hparams["fn"] = print  # no weights file holds it: said, left out
    with pytest.warns(UserWarning, match=r"^hyper_parameters.fn: builtin_function_or_method "
                      "is not a plain value: left out"):
        save_weights(module, tmp_path / "fn.safetensors")


def test_a_checkpoint_of_an_unregistered_module_says_the_plugin_variable_whole(
        tmp_path, monkeypatch):
    """The line for a checkpoint whose module nothing here registered was
    cut at 160 characters of the registry's message, in the middle of its
    hint: '... in SATAGRAPH_PLUGINS, e.g. SATAGRAPH_PL)'."""
    from satagraph.experiment import registry
    from satagraph.experiment.train import load_module
    from satagraph.io.checkpoint import CheckpointError
    from satagraph.lightning import SATAVAEModule
    module = SATAVAEModule(dict(hidden_channels=16, heads=2, ff_channels=16, num_blocks=1,
                                latent_channels=8, semantic_channels=0),
                           meta={"window": 32, "module": "never_registered_t"})
    module.normalizer.fitted.fill_(True)
    path = save_module_checkpoint(module, tmp_path / "theirs.ckpt")
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    monkeypatch.delenv("SATAGRAPH_PLUGINS", raising=False)
    with pytest.raises(CheckpointError) as err:
        load_module(str(path))
    assert str(err.value).startswith(f"{path}: a 'never_registered_t' model, which is not "
                                     "registered here")
    assert str(err.value).endswith("e.g. SATAGRAPH_PLUGINS=my_models))")
    assert "\n" not in str(err.value)


def test_registered_name_is_the_class_s_one_name_or_none(names):
    """The name a class is registered under: not its parent's (a subclass
    registered under none), none for a class registered under two names
    or only built by a builder function; exported with the registry."""
    from satagraph.experiment import registry
    from satagraph.lightning import SATARVQModule, SATAVAEModule

    class Own(SATAVAEModule):
        pass

    assert "registered_name" in registry.__all__
    assert registry.registered_name(SATAVAEModule) == "vae"
    assert registry.registered_name(Own) is None
    register_module("test_own_once", Own)
    names.append("test_own_once")
    assert registry.registered_name(Own) == "test_own_once"
    register_module("test_own_twice", Own)
    names.append("test_own_twice")
    assert registry.registered_name(Own) is None
    register_module("test_rvq_builder", lambda sections: SATARVQModule(**sections.kwargs()))
    names.append("test_rvq_builder")
    assert registry.registered_name(SATARVQModule) == "rvq"


def test_load_module_says_a_checkpoint_names_no_module(names, tmp_path):
    """A module of one's own built without ``meta.module`` (by its
    constructor, trained with one's own Trainer) was read as the built-in
    'vae': refused as 'weights do not fit the 'vae' model its
    hyperparameters describe (Error(s) in loading state_dict for
    SATAVAEModule:)', though they describe none, or, where its weights fit,
    loaded as a SATAVAEModule without a word. A class registered under one
    name now records it when built by hand, and loads as itself."""
    from satagraph.experiment.train import load_module
    from satagraph.io.checkpoint import CheckpointError
    from satagraph.lightning import MotionAutoencoderModule, SATAVAEModule
    from satagraph.nn import SATA

    class OwnRVQ(MotionAutoencoderModule):
        def build_model(self, **kwargs):
            return SATA(**dict(kwargs, bottleneck="rvq"))

    model = dict(hidden_channels=16, heads=2, ff_channels=16, num_blocks=1, latent_channels=8,
                 semantic_channels=0, codebook_size=8, num_quantizers=2)
    path = tmp_path / "own.ckpt"
    module = OwnRVQ(model, meta={"window": 32})  # registered under no name
    assert "module" not in module.hparams["meta"]
    module.normalizer.fitted.fill_(True)
    save_module_checkpoint(module, path)
    with pytest.raises(CheckpointError, match=r"name no module \(meta.module\).*Missing key"):
        load_module(str(path))
    register_module("test_own_rvq", OwnRVQ)
    names.append("test_own_rvq")
    module = OwnRVQ(model, meta={"window": 32})
    assert module.hparams["meta"] == {"window": 32, "module": "test_own_rvq"}
    module.normalizer.fitted.fill_(True)
    save_module_checkpoint(module, path)
    assert type(load_module(str(path))) is OwnRVQ
    # a VAE of an unregistered class fits the built-in 'vae': it loads as one, said
    vae = dict(hidden_channels=16, heads=2, ff_channels=16, num_blocks=1, latent_channels=8,
               semantic_channels=0)
    module = type("OwnVAE", (SATAVAEModule,), {})(vae, meta={"window": 32})
    module.normalizer.fitted.fill_(True)
    save_module_checkpoint(module, path)
    with pytest.warns(UserWarning, match="name no module .*read as the built-in 'vae'"):
        assert type(load_module(str(path))) is SATAVAEModule
    # the built-in class built by hand names itself: no warning
    module = SATAVAEModule(vae, meta={"window": 32})
    assert module.hparams["meta"]["module"] == "vae"
    module.normalizer.fitted.fill_(True)
    save_module_checkpoint(module, path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert type(load_module(str(path))) is SATAVAEModule


def test_a_subclass_s_own_argument_is_a_config_setting(names, tmp_path):
    """A subclass's own constructor argument (a loss weight) could be set
    by a builder function only: ``z_weight=0.5`` and ``model.z_weight=0.5``
    were unknown keys, and a ``train`` or ``sweep`` of it trained with the
    default. ``module_args`` sets it, from YAML and dotted overrides, into
    the checkpoint that ``load_module`` reads."""
    from satagraph.experiment.sweep import check_runs, config_differences, sweep_configs
    from satagraph.experiment.train import build_module, check_config, load_module
    from satagraph.lightning import SATAVAEModule

    @register_module("test_args")
    class Weighted(SATAVAEModule):
        def __init__(self, model, loss=None, optim=None, fps=30.0, meta=None,
                     z_weight: float = 0.1) -> None:
            super().__init__(model, loss, optim, fps, meta)
            self.z_weight = z_weight

    names.append("test_args")
    path = tmp_path / "weighted.yaml"
    path.write_text("defaults: [tiny]\nmodule: test_args\nmodule_args: {z_weight: 0.25}\n")
    assert build_module(load_config(str(path), ["model.semantic_channels=0"])).z_weight == 0.25
    module = build_module(load_config(str(path), ["module_args.z_weight=0.7",
                                                  "model.semantic_channels=0"]))
    assert module.z_weight == 0.7 and module.hparams["z_weight"] == 0.7
    module.normalizer.fitted.fill_(True)
    ckpt = tmp_path / "weighted.ckpt"
    save_module_checkpoint(module, ckpt)
    assert load_module(str(ckpt)).z_weight == 0.7
    from satagraph.experiment.train import check_resumable
    check_resumable(ckpt, check_config(load_config(str(path), ["module_args.z_weight=0.7"])))
    with pytest.raises(ValueError, match=r"module_args.z_weight=0.7 \(here 0.25\)"):
        check_resumable(ckpt, check_config(load_config(str(path))))
    with pytest.raises(ValueError, match=r"module_args.z_weigth' \(did you mean 'z_weight'"):
        check_config(load_config(str(path), ["module_args.z_weigth=0.7"]))
    with pytest.raises(ValueError, match="module_args.z_weight: SATAVAEModule takes no"):
        check_config(load_config("tiny", ["module_args.z_weight=0.7"]))
    runs = sweep_configs(["tiny", str(path)], output=str(tmp_path / "sweep"))
    check_runs(runs)
    assert config_differences(runs)["module_args.z_weight"] == [None, 0.25]


def test_load_module_names_the_file_whose_local_conv_is_not_registered(tmp_path, monkeypatch):
    """A checkpoint trained with a layer of one's own
    (``register_local_conv``), loaded where nothing registered it, was the
    registry's bare 'unknown local conv' line, naming no file; the plugin
    variable that registers it is now read first, as for a module."""
    from torch_geometric.nn import GraphConv
    from satagraph.experiment import registry
    from satagraph.experiment.train import load_module
    from satagraph.io.checkpoint import CheckpointError
    from satagraph.lightning import SATAVAEModule
    from satagraph.nn import register_local_conv
    from satagraph.nn.layers import local_conv
    builtin = dict(local_conv._BUILDERS)
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(builtin))
    register_local_conv("graph_ckpt_t", lambda channels, heads, edge_dim, act:
                        GraphConv(channels, channels))
    torch.manual_seed(0)
    module = SATAVAEModule(dict(hidden_channels=16, heads=2, ff_channels=16, num_blocks=1,
                                latent_channels=8, semantic_channels=0,
                                local_conv="graph_ckpt_t"), meta={"window": 32, "module": "vae"})
    module.normalizer.fitted.fill_(True)
    path = tmp_path / "own_conv.ckpt"
    save_module_checkpoint(module, path)
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(builtin))  # a fresh process
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    monkeypatch.delenv("SATAGRAPH_PLUGINS", raising=False)
    with pytest.raises(CheckpointError, match=rf"{path.name}: its model.local_conv "
                       r"'graph_ckpt_t' is not registered here.*SATAGRAPH_PLUGINS"):
        load_module(str(path))
    plugin = tmp_path / "my_layers.py"
    plugin.write_text("from torch_geometric.nn import GraphConv\n"
                      "from satagraph.nn import register_local_conv\n"
                      "register_local_conv('graph_ckpt_t', lambda channels, heads, edge_dim, "
                      "act: GraphConv(channels, channels))\n")
    monkeypatch.setenv("SATAGRAPH_PLUGINS", str(plugin))
    loaded = load_module(str(path))
    assert any(isinstance(m, GraphConv) for m in loaded.modules())
