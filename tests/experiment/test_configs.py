"""Every config in experiments/ loads, resolves its defaults, names a
module, a model and data sources, and builds its module; the wandb sweep
names configs of experiments/ and its command parses."""
from __future__ import annotations

from pathlib import Path
from typing import List

import pytest
import yaml

from satagraph.experiment.config import load_config

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments"
#: Configs whose module needs a trained autoencoder: built in tests/t2m.
NEEDS_CHECKPOINT = ("t2m", "t2m_tiny", "t2m_cpu", "t2m_builtin", "t2m_gestures",
                    "t2m_length_bandai")
#: Configs whose data the user names (``data.sources=[...]``).
NEEDS_USER_DATA = ("finetune_builtin",)
CONFIGS = sorted(p.stem for p in EXPERIMENTS.glob("*.yaml") if p.stem not in NEEDS_CHECKPOINT)
WANDB_SWEEP = EXPERIMENTS / "sweeps" / "wandb_sweep.yaml"
#: Widths and depths small enough to build every config in a fraction of a
#: second; the structure (layers, attention, convolution kinds) is kept.
SMALL_MODEL = {"hidden_channels": 32, "ff_channels": 32, "latent_channels": 16,
               "codebook_size": 16, "num_blocks": 1, "num_layers": 1, "heads": 2}


@pytest.mark.parametrize("name", CONFIGS)
def test_config_builds_its_module(name: str):
    from satagraph.experiment.train import build_module, module_class
    cfg = load_config(name)
    assert cfg["module"] and cfg["model"]
    assert bool(cfg["data"]["sources"]) != (name in NEEDS_USER_DATA)
    model = cfg["model"]
    model.update({k: v for k, v in SMALL_MODEL.items() if k in model})
    module = build_module(cfg)  # the real builder, without data
    assert type(module) is module_class(cfg["module"])
    assert sum(p.numel() for p in module.parameters()) > 0


def _sweep_argv(config: str) -> List[str]:
    """The command line a wandb agent runs for one value of ``config``."""
    spec = yaml.safe_load(WANDB_SWEEP.read_text())
    return [{"${args_no_hyphens}": f"config={config}"}.get(a, a)
            for a in spec["command"] if a != "${program}"]


def test_wandb_sweep_runs_configs_of_experiments():
    from satagraph.cli import build_parser, parse_args
    from satagraph.experiment.sweep import split_arguments
    spec = yaml.safe_load(WANDB_SWEEP.read_text())
    assert spec["program"] == "satagraph"
    names = spec["parameters"]["config"]["values"]
    assert names and set(names) <= set(CONFIGS)
    for name in names:
        args = parse_args(build_parser(), _sweep_argv(name))
        assert args.command == "sweep" and args.logger == "wandb"
        assert split_arguments(args.items) == ([name], [])


def test_finetune_stage_inherits_cpu_joint():
    base, stage = load_config("cpu_joint"), load_config("cpu_joint_finetune")
    assert stage["model"] == base["model"]
    assert stage["loss"]["position"] == 0.005 and base["loss"]["position"] == 0.001
    assert stage["data"] == base["data"]


def test_retarget_stage_adds_only_the_cross_skeleton_term():
    base, stage = load_config("cpu_joint_finetune"), load_config("cpu_joint_retarget")
    assert stage["loss"] == dict(base["loss"], retarget=0.01)
    assert stage["model"] == base["model"] and stage["data"] == base["data"]


def test_augment_stage_draws_new_rigs_with_new_rest_poses():
    base, stage = load_config("cpu_joint_retarget"), load_config("cpu_joint_augment")
    assert stage["loss"] == base["loss"] and stage["model"] == base["model"]
    assert stage["data"]["augment"]["rest"] > 0


def test_long_retarget_stage_doubles_the_term_with_a_new_data_order():
    base, stage = load_config("cpu_joint_retarget"), load_config("cpu_joint_retarget_long")
    assert stage["loss"] == dict(base["loss"], retarget=0.02)
    assert stage["model"] == base["model"] and stage["data"] == base["data"]
    assert stage["seed"] != base.get("seed", 0)


def test_named_configs_found_without_a_source_checkout(tmp_path, monkeypatch):
    """A non-editable install has no ``experiments/`` beside the package: the
    named configs come from the data files it ships (``setup.cfg``)."""
    from satagraph.experiment import config
    shipped = tmp_path / "share" / "satagraph" / "experiments"
    shipped.mkdir(parents=True)
    (shipped / "tiny.yaml").write_text((EXPERIMENTS / "tiny.yaml").read_text())
    monkeypatch.setattr(config, "CONFIG_DIRS", (tmp_path / "missing", shipped))
    assert config.experiments_dir() == shipped
    assert config.config_path("tiny") == shipped / "tiny.yaml"
    with pytest.raises(FileNotFoundError, match="one of: tiny"):
        config.config_path("sata_vae")


def test_only_a_checkout_s_experiments_folder_is_read(tmp_path, monkeypatch):
    """Installed, the package's parent is site-packages, whose
    ``experiments`` may be another distribution's package; a ``pip install
    --user`` ships the configs under the user base; with none found, the
    error says where it looked."""
    from satagraph.experiment import config
    (tmp_path / "experiments").mkdir()
    assert tmp_path / "experiments" not in config.config_dirs(tmp_path)
    (tmp_path / "setup.cfg").write_text("[metadata]\n")
    assert config.config_dirs(tmp_path)[0] == tmp_path / "experiments"
    monkeypatch.setattr(config.site, "USER_BASE", str(tmp_path / "user"))
    assert tmp_path / "user" / "share" / "satagraph" / "experiments" in config.config_dirs()
    monkeypatch.setattr(config, "CONFIG_DIRS", (tmp_path / "a", tmp_path / "b"))
    with pytest.raises(FileNotFoundError, match=f"looked in {tmp_path / 'a'}, {tmp_path / 'b'}"):
        config.config_path("tiny")


def test_one_s_own_config_inherits_a_named_one(tmp_path):
    (tmp_path / "mine.yaml").write_text("defaults: [tiny]\nname: mine\n")
    cfg = load_config(str(tmp_path / "mine.yaml"))
    assert cfg["name"] == "mine" and cfg["data"] == load_config("tiny")["data"]


def test_a_defaults_entry_may_be_a_file_name_or_a_relative_path(tmp_path):
    """``defaults: [tiny.yaml]`` or ``[../base.yaml]`` was read as
    ``tiny.yaml.yaml`` ('not a valid YAML config ([Errno 2] No such file
    ...)'); a base found nowhere names the file whose defaults list it."""
    (tmp_path / "base.yaml").write_text("defaults: [tiny.yaml]\nseed: 11\n")
    (tmp_path / "sub").mkdir()
    top = tmp_path / "sub" / "top.yaml"
    top.write_text("defaults: [../base.yaml]\noptim: {lr: 2.0e-3}\n")
    cfg = load_config(str(top))
    assert cfg["seed"] == 11 and cfg["optim"]["lr"] == 2.0e-3
    assert cfg["data"] == load_config("tiny")["data"]
    lost = tmp_path / "sub" / "lost.yaml"
    lost.write_text("defaults: [base]\n")  # base.yaml is a folder up
    with pytest.raises(FileNotFoundError, match=rf"{lost}: defaults: config 'base' not found"):
        load_config(str(lost))


def test_defaults_that_include_themselves_or_are_no_list_are_one_line(tmp_path):
    """A config whose defaults come back to it was 'not a valid YAML config
    (maximum recursion depth exceeded ...)'; ``defaults: tiny`` (no list)
    was read letter by letter ('config 't' not found')."""
    (tmp_path / "a.yaml").write_text("defaults: [b]\n")
    (tmp_path / "b.yaml").write_text("defaults: [a.yaml]\n")
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    with pytest.raises(ValueError, match=rf"^{a}: defaults include themselves: "
                                         rf"{a} -> {b} -> {a}$"):
        load_config(str(a))
    (tmp_path / "bare.yaml").write_text("defaults: tiny\n")
    with pytest.raises(ValueError, match=r"bare.yaml: defaults: a list of configs is "
                                         r"expected, e.g. defaults: \[tiny\] \(got 'tiny'\)$"):
        load_config(str(tmp_path / "bare.yaml"))


def test_a_config_that_is_a_list_is_one_line(tmp_path):
    """A YAML file holding a list, given or named by ``defaults``, was a
    traceback (``TypeError: ListConfig.pop() takes from 1 to 2 positional
    arguments but 3 were given``)."""
    listed = tmp_path / "listed.yaml"
    listed.write_text("- tiny\n- seed: 3\n")
    (tmp_path / "top.yaml").write_text("defaults: [listed]\n")
    for name in ("listed.yaml", "top.yaml"):
        with pytest.raises(ValueError, match=rf"^{listed}: a config is a mapping of "
                                             r"sections \(model:, data:, trainer:, ...\), "
                                             r"not a list$"):
            load_config(str(tmp_path / name))


@pytest.mark.slow
def test_every_config_loads_from_the_shipped_copy(tmp_path, monkeypatch):
    """The data files of ``setup.cfg`` cover every config, and each loads
    (inheritance included) from a copy laid out as a non-editable install
    ships it (``<prefix>/share/satagraph/experiments``)."""
    import configparser
    import shutil
    from satagraph.experiment import config
    setup = configparser.ConfigParser()
    setup.read(EXPERIMENTS.parent / "setup.cfg")
    files = setup["options.data_files"]
    shipped = tmp_path / "share" / "satagraph" / "experiments"
    for folder, pattern in files.items():
        target = tmp_path / folder
        target.mkdir(parents=True, exist_ok=True)
        for path in EXPERIMENTS.parent.glob(pattern.strip()):
            shutil.copy(path, target)
    every = sorted(p.stem for p in EXPERIMENTS.glob("*.yaml"))
    assert sorted(p.stem for p in shipped.glob("*.yaml")) == every
    assert (shipped / "sweeps" / WANDB_SWEEP.name).is_file()
    monkeypatch.setattr(config, "CONFIG_DIRS", (tmp_path / "missing", shipped))
    for name in every:
        assert load_config(name) == load_config(str(EXPERIMENTS / f"{name}.yaml")), name


def test_every_package_has_an_init():
    """``packages = find:`` leaves out folders without ``__init__.py``: a
    non-editable install would lack them."""
    package = EXPERIMENTS.parent / "satagraph"
    missing = [str(d.relative_to(package.parent)) for d in package.rglob("*")
               if d.is_dir() and d.name != "__pycache__" and any(d.glob("*.py"))
               and not (d / "__init__.py").is_file()]
    assert not missing


def test_every_data_file_of_the_package_is_package_data():
    """A file under ``satagraph/`` that is not Python (the built-in weights,
    which ``importlib.resources`` loads) reaches a wheel only through a glob
    of ``setup.cfg``'s ``options.package_data`` for its package."""
    import configparser
    import fnmatch
    setup = configparser.ConfigParser()
    setup.read(EXPERIMENTS.parent / "setup.cfg")
    globs = {package: value.replace(",", " ").split()
             for package, value in setup["options.package_data"].items()}
    package = EXPERIMENTS.parent / "satagraph"
    data = [p for p in package.rglob("*") if p.is_file() and p.suffix not in (".py", ".pyc")
            and "__pycache__" not in p.parts]
    assert data, "the package ships its built-in weights"
    for path in data:
        owner = ".".join(path.parent.relative_to(package.parent).parts)
        patterns = globs.get(owner, []) + globs.get("*", [])
        assert any(fnmatch.fnmatch(path.name, g) for g in patterns), f"{path} is not shipped"


def test_a_config_is_read_again_when_one_of_its_files_changes(tmp_path):
    """Configs are kept once read, as copies: a caller's edit never reaches
    the next load, and an edited file (the config or a default it inherits)
    is read again."""
    base = tmp_path / "base.yaml"
    base.write_text((EXPERIMENTS / "sata_vae.yaml").read_text())
    top = tmp_path / "top.yaml"
    top.write_text("defaults: [base]\ndata: {window: 24}\n")
    first = load_config(str(top))
    assert first["data"]["window"] == 24 and first["name"] == "top"
    first["data"]["window"] = 1
    assert load_config(str(top))["data"]["window"] == 24
    top.write_text("defaults: [base]\ndata: {window: 40}\nseed: 7\n")
    assert load_config(str(top))["data"]["window"] == 40
    base.write_text(base.read_text() + "\nthreads: 3\n")
    assert load_config(str(top))["threads"] == 3


def test_carriage_finetune_adds_only_the_carriage_term_to_builtins_last_stage():
    base = load_config("pretrain_zoo_lie")
    stage = load_config("finetune_builtin_carriage")
    assert stage["loss"] == dict(base["loss"], retarget_carriage=1.5)
    assert stage["model"] == base["model"]
    assert stage["data"]["sources"] == base["data"]["sources"]
    assert stage["data"]["preprocessing"]["facing_smooth"] == 0.25
    assert stage["checkpoint"]["keep_every_epoch"]
