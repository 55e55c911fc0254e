"""Equal-budget sweeps: ``satagraph sweep`` end to end on two tiny configs."""
from __future__ import annotations

import io
import json
import math
import os
from pathlib import Path

import pytest
import yaml

from satagraph.cli import main
from satagraph.experiment.config import load_config
from satagraph.experiment import sweep as sweep_mod
from satagraph.experiment.sweep import (SweepRow, budget_config, config_differences,
                                        format_sweep, split_arguments, sweep_configs)
from tests.conftest import data_dir

needs_data = pytest.mark.skipif(data_dir() is None, reason="../shared/data not found")


def test_split_arguments():
    configs, overrides = split_arguments(["tiny", "a.b=1", "config=gnn_gin", "c=x"])
    assert configs == ["tiny", "gnn_gin"]
    assert overrides == ["a.b=1", "c=x"]


def test_budget_config_binds_time_only(tmp_path):
    cfg = load_config("tiny", ["trainer.max_steps=5"])
    out = budget_config(cfg, 0.5, tmp_path / "run", data={"sources": ["x"]})
    assert out["trainer"]["max_epochs"] == -1
    assert "max_steps" not in out["trainer"]
    assert out["trainer"]["max_time"] == {"seconds": pytest.approx(30.0)}
    assert not [k for k in out if k.startswith("_")]  # no private keys
    assert out["data"] == {"sources": ["x"]} and out["logger"] == {"name": "csv"}
    assert cfg["trainer"]["max_steps"] == 5  # the input is not modified


def test_sweep_configs_share_data_and_unique_names(tmp_path):
    runs = sweep_configs(["tiny", "tiny"], ["data.max_files=2"],
                         variants=[[], ["data.window=16"]], output=str(tmp_path))
    assert [r.source for r in runs] == ["tiny", "tiny"]
    cfgs = [r.cfg for r in runs]
    assert cfgs[1]["data"] == cfgs[0]["data"]  # the first config's data for all
    assert cfgs[0]["data"]["max_files"] == 2
    assert cfgs[0]["name"] != cfgs[1]["name"]
    assert cfgs[0]["output_dir"] != cfgs[1]["output_dir"]


def test_a_sweep_s_w_and_b_runs_share_a_group_named_after_its_folder(tmp_path):
    """A sweep's W&B runs were named after their configs alone, among every
    other run of the project: nothing told one sweep's rows from another's."""
    from satagraph.experiment.train import build_logger
    runs = sweep_configs(["tiny", "tiny"], variants=[[], ["data.window=16"]],
                         output=str(tmp_path / "gnn"), logger="wandb")
    loggers = [build_logger(r.cfg, Path(r.cfg["output_dir"])) for r in runs]
    assert [lg._wandb_init["group"] for lg in loggers] == ["gnn", "gnn"]
    assert [lg._wandb_init["name"] for lg in loggers] == ["tiny", "tiny+window=16"]
    own = sweep_configs(["tiny"], ["logger.group=mine"], output=str(tmp_path / "gnn"),
                        logger=None)
    assert own[0].cfg["logger"]["group"] == "mine"  # a group set is kept


def test_a_steps_budget_binds_steps_only(tmp_path):
    cfg = load_config("tiny", ["trainer.max_time=00:00:10:00", "trainer.max_epochs=3"])
    trainer = budget_config(cfg, 0.5, tmp_path, steps=40)["trainer"]
    assert trainer["max_steps"] == 40 and trainer["max_epochs"] == -1
    assert "max_time" not in trainer


def test_a_sweep_of_equal_steps_says_so_and_times_each_row(tmp_path, monkeypatch):
    """Equal time is not equal work: a GNN twice as slow trains half the
    steps. ``--steps N`` trains every config N steps, and the table's
    ``train (min)`` column gives each row's time."""
    metrics = {"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}}
    limits = []

    def run_config(run, **kw):
        limits.append(run.cfg["trainer"])
        return SweepRow(run.cfg["name"], run.source, params=5, steps=40, seconds=93.0,
                        train_loss=1.0, metrics=metrics, run_dir=run.cfg["output_dir"])
    monkeypatch.setattr(sweep_mod, "run_config", run_config)
    monkeypatch.setattr(sweep_mod, "check_runs", lambda runs, resume=False: set())
    sweep_mod.run_sweep(["tiny"], 0.01, str(tmp_path), log=lambda *a: None, steps=40)
    assert limits[0]["max_steps"] == 40 and "max_time" not in limits[0]
    text = (tmp_path / "sweep.md").read_text()
    assert text.startswith("# Sweep: 1 configs, 40 steps of training each")
    assert "| config | params (M) | steps | train (min) | train loss |" in text
    assert "| tiny | 5e-06 | 40 | 1.55 | 1.0000 (all 40) |" in text
    payload = json.loads((tmp_path / "sweep.json").read_text())
    assert payload["steps"] == 40 and payload["budget_minutes"] is None
    with pytest.raises(ValueError, match="--steps must be at least 1"):
        sweep_mod.run_sweep(["tiny"], 0.01, str(tmp_path / "x"), steps=0)
    with pytest.raises(SystemExit):
        main(["sweep", "--budget", "1", "--steps", "5", "tiny"])


def test_a_config_s_own_limits_give_way_to_the_budget(tmp_path):
    """A config's trainer.min_steps trained one row 60 steps for 21 s
    beside another's 4."""
    cfg = load_config("tiny", ["trainer.min_steps=60", "trainer.min_epochs=2",
                               "trainer.max_epochs=3"])
    trainer = budget_config(cfg, 0.5, tmp_path)["trainer"]
    assert "min_steps" not in trainer and "min_epochs" not in trainer
    assert trainer["max_epochs"] == -1 and trainer["max_time"] == {"seconds": 30.0}


def test_each_row_s_run_is_closed_with_its_scores():
    """A W&B run stayed open, and every later config of a sweep was logged
    into the first one's; the test scores never reached it."""
    from types import SimpleNamespace
    from satagraph.experiment.sweep import close_logger
    seen = {}
    experiment = SimpleNamespace(finish=lambda: seen.setdefault("finished", True))
    logger = SimpleNamespace(log_metrics=lambda m, step: seen.update(metrics=m, step=step),
                             finalize=lambda status: seen.update(status=status),
                             experiment=experiment)
    close_logger(SimpleNamespace(logger=logger, global_step=7),
                 {"test/JP": 0.5, "test/dog/JP": 0.7, "note": "text"})
    assert seen == {"metrics": {"test/JP": 0.5, "test/dog/JP": 0.7}, "step": 7,
                    "status": "success", "finished": True}
    close_logger(SimpleNamespace(logger=None, global_step=0), {})  # no logger: nothing


def test_a_step_limit_is_refused_not_dropped(tmp_path):
    """trainer.max_steps was dropped for the time budget while the table's
    legend listed it as applied to every config."""
    for overrides, variants in ((["trainer.max_steps=20"], None),
                                ([], [[], ["trainer.max_epochs=2"]])):
        with pytest.raises(ValueError, match="sweep: trainer.max_(steps|epochs)=.*budget"):
            sweep_configs(["tiny", "tiny"], overrides, variants=variants, output=str(tmp_path))


def test_sweep_table_has_internal_and_cross_retarget_columns():
    """As the SATA paper's Table 4: INT. and CROSS retargeting columns, per
    evaluation group; a config without retarget errors shows dashes."""
    metrics = {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}
    rows = [SweepRow("a", "a", params=10, steps=2, metrics={"all": metrics, "dog": metrics},
                     retarget={"internal": {"test": 1.5, "test:dog": 1.0},
                               "cross": {"test": 2.5, "test:dog": 2.0}}),
            SweepRow("b", "b", params=10, steps=2, metrics={"all": metrics})]
    lines = format_sweep(rows).splitlines()
    assert lines[0].endswith("| retarget int. | retarget cross |")
    assert lines[2].endswith("| 1.500 | 2.500 |") and lines[3].endswith("| - | - |")
    assert format_sweep(rows, "dog").splitlines()[2].endswith("| 1.000 | 2.000 |")
    assert "retarget" not in format_sweep(rows[1:])


def test_the_sweep_command_prints_its_utf8_table_on_windows(tmp_path, monkeypatch, capsys):
    """The table (UTF-8) was printed as read in the system's encoding:
    a config ``marché`` showed as ``marchÃ©`` where that is cp1252."""
    def run_sweep(configs, budget, output, *args, **kwargs):
        Path(output).mkdir(parents=True)
        (Path(output) / "sweep.md").write_text("| marché |\n", encoding="utf-8")
        return []
    monkeypatch.setattr(sweep_mod, "run_sweep", run_sweep)
    monkeypatch.setattr(io, "text_encoding",  # pathlib's default, as on Windows
                        lambda encoding, stacklevel=2: encoding or "cp1252")
    assert main(["sweep", "--budget", "1", "--output", str(tmp_path / "s"), "marché"]) == 0
    assert "| marché |" in capsys.readouterr().out


@pytest.mark.slow
@needs_data
def test_sweep_cli_end_to_end(tmp_path):
    gin = load_config("tiny", ["model.local_conv=gin"])
    gin["name"] = "tiny_gin"
    (tmp_path / "tiny_gin.yaml").write_text(yaml.safe_dump(gin))
    out = tmp_path / "sweep"
    code = main(["sweep", "--budget", "0.08", "--output", str(out), "--max-batches", "2",
                 "tiny", str(tmp_path / "tiny_gin.yaml"),
                 f"data.sources=[{data_dir()}]", "data.max_files=3"])
    assert code == 0
    table = (out / "sweep.md").read_text()
    assert "| tiny |" in table and "| tiny_gin |" in table
    assert "`data.max_files=3`" in table and "Retarget:" not in table
    assert "first 2 batch(es)" in table and "| `model.local_conv` | gine | gin |" in table
    payload = json.loads((out / "sweep.json").read_text())
    assert payload["overrides"][-1] == "data.max_files=3"
    assert payload["data"] == [str(data_dir())]
    rows = payload["rows"]
    assert [r["name"] for r in rows] == ["tiny", "tiny_gin"]
    for row in rows:
        assert row["steps"] > 0 and row["params"] > 0
        assert math.isfinite(row["train_loss"])
        assert set(row["metrics"]["all"]) >= {"JR", "RT", "JP", "FS", "GP"}
        assert Path(row["run_dir"]).is_dir()


def test_the_table_lists_every_setting_the_rows_differ_in(tmp_path):
    """`sweep tiny gnn_gin` compared a 32-wide model with a 256-wide one at
    another learning rate under the name "gnn_gin"; the table now says so."""
    runs = sweep_configs(["tiny", "gnn_gin"], output=str(tmp_path))
    differ = config_differences(runs)
    assert differ["model.local_conv"] == ["gine", "gin"]
    assert differ["model.hidden_channels"] == [32, 256] and "optim.lr" in differ
    assert "data.window" not in differ and "seed" not in differ  # the same data and seed
    same = sweep_configs(["tiny", "tiny"], output=str(tmp_path / "same"))
    assert config_differences(same) == {}


def test_every_config_is_checked_before_any_trains(tmp_path, monkeypatch):
    """A config that cannot build stopped the sweep after the others had
    trained, and no table was written."""
    trained = []
    monkeypatch.setattr(sweep_mod, "run_config", lambda run, **kw: trained.append(run))
    with pytest.raises(ValueError,
                       match="sweep: config tiny\\+local_conv=bogus .*unknown local conv"):
        sweep_mod.run_sweep(["tiny", "tiny"], 0.01, str(tmp_path),
                            variants=[[], ["model.local_conv=bogus"]])
    assert trained == [] and not list(tmp_path.iterdir())


def test_a_config_that_fails_while_training_is_a_row_and_the_others_go_on(tmp_path,
                                                                          monkeypatch):
    def run_config(run, **kw):
        if run.cfg["name"] == "tiny":
            raise RuntimeError("out of memory\nmore lines")
        return SweepRow(run.cfg["name"], run.source, params=5, steps=3, train_loss=1.0,
                        metrics={"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}})
    monkeypatch.setattr(sweep_mod, "run_config", run_config)
    monkeypatch.setattr(sweep_mod, "check_runs", lambda runs, resume=False: set())
    rows = sweep_mod.run_sweep(["tiny", "tiny"], 0.01, str(tmp_path), log=lambda *a: None)
    assert [r.error for r in rows] == ["out of memory", ""]
    table = (tmp_path / "sweep.md").read_text()
    assert "| tiny | failed: out of memory |" in table and "| tiny_2 | 5e-06 |" in table


def test_the_table_says_which_train_losses_do_not_compare(tmp_path):
    """A 0.25-minute sweep trained gnn_gin 63 steps and gnn_gat 44: the
    table called both "mean over the last 50 steps", though gnn_gat's was
    the mean from its first step (757 against 724); and a module of one's
    own that adds a loss term was compared by its train loss unsaid."""
    from satagraph.experiment.sweep import write_results
    metrics = {"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}}
    rows = [SweepRow("gnn_gin", "gnn_gin", params=10, steps=63, train_loss=723.5, metrics=metrics),
            SweepRow("gnn_gat", "gnn_gat", params=10, steps=44, train_loss=757.1, metrics=metrics)]
    text = write_results(rows, tmp_path, 0.25, differences={"model.local_conv": ["gin", "gat"]})
    assert "| gnn_gin | 1e-05 | 63 | 0.00 | 723.5000 |" in text
    assert "| gnn_gat | 1e-05 | 44 | 0.00 | 757.1000 (all 44) |" in text
    assert "(all N): the run trained N < 50 steps" in text and "different sums" not in text
    text = write_results(rows[:1], tmp_path, 0.25,
                         differences={"module": ["vae", "mine"], "module_args.w": [None, 1]})
    assert "(all N)" not in text
    # a stopped sweep's one finished row said "The configs differ in no setting but their names"
    alone = write_results(rows[:1], tmp_path, 0.25, differences={}, planned=3)
    assert "1 of 3 configs so far" in alone and "differ in no setting" not in alone
    assert "The rows differ in module, module_args: their train losses are different sums" in text


def test_a_row_resumed_near_its_end_says_its_loss_averages_fewer_steps(tmp_path):
    """A sweep resumed 20 steps before a row's budget ran out averaged those
    20 steps and called them "the last 50"."""
    from satagraph.experiment.sweep import write_results
    metrics = {"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}}
    rows = [SweepRow("a", "a", params=10, steps=320, loss_steps=20, train_loss=2.0,
                     metrics=metrics),
            SweepRow("b", "b", params=10, steps=300, loss_steps=50, train_loss=2.5,
                     metrics=metrics),
            SweepRow("c", "c", params=10, steps=30, train_loss=3.0, metrics=metrics)]
    text = write_results(rows, tmp_path, 0.25)
    assert "| a | 1e-05 | 320 | 0.00 | 2.0000 (last 20) |" in text
    assert "| b | 1e-05 | 300 | 0.00 | 2.5000 |" in text
    assert "| c | 1e-05 | 30 | 0.00 | 3.0000 (all 30) |" in text  # an older row: no count
    assert "(last N): a run resumed" in text and "(all N): the run trained" in text


def test_a_config_s_threads_do_not_run_the_rows_after_it(tmp_path, monkeypatch):
    """A config with ``threads: 2`` (``torch.set_num_threads``) left every
    later row of the sweep on 2 threads, whatever their own setting (the
    table said they set none), and so trained them more or fewer steps."""
    import torch
    before = torch.get_num_threads()

    def train_budgeted(cfg, resume=False):
        torch.set_num_threads(int(cfg["threads"]))
        raise RuntimeError("stopped after setting the threads")
    monkeypatch.setattr(sweep_mod, "train_budgeted", train_budgeted)
    run = sweep_configs(["tiny"], [f"threads={before + 1}"], output=str(tmp_path))[0]
    with pytest.raises(RuntimeError, match="stopped after"):
        sweep_mod.run_config(run)
    assert torch.get_num_threads() == before


def test_split_val_scores_the_rows_for_choosing_and_test_says_so(tmp_path, monkeypatch):
    """``--split val`` scores every row (and its retarget files) on the
    validation split, which the table names; the default test table says to
    choose among rows on --split val (a sweep could only score on the test
    split: choosing an ablation from it left no test result); a stopped
    sweep's rows of another split are scored again, not kept."""
    metrics = {"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}}
    asked = []

    def run_config(run, eval_split="test", retarget_files=None, **kw):
        asked.append((eval_split, retarget_files))
        return SweepRow(run.cfg["name"], run.source, params=5, steps=60, train_loss=1.0,
                        metrics=metrics, split=eval_split, run_dir=run.cfg["output_dir"])
    monkeypatch.setattr(sweep_mod, "run_config", run_config)
    monkeypatch.setattr(sweep_mod, "check_runs", lambda runs, resume=False: set())
    sweep_mod.run_sweep(["tiny"], 0.01, str(tmp_path), log=lambda *a: None, split="val",
                        retarget=True)
    assert asked == [("val", {"val": "split"})]
    text = (tmp_path / "sweep.md").read_text()
    assert "of the val split" in text and "Choose among the rows" not in text
    runs = sweep_configs(["tiny"], output=str(tmp_path))
    assert sweep_mod.finished_rows(runs, tmp_path, "val")
    assert not sweep_mod.finished_rows(runs, tmp_path, "test")
    sweep_mod.run_sweep(["tiny"], 0.01, str(tmp_path / "t"), log=lambda *a: None)
    text = (tmp_path / "t" / "sweep.md").read_text()
    assert asked[-1][0] == "test" and "of the test split" in text
    assert "Choose among the rows on a sweep with --split val" in text
    with pytest.raises(ValueError, match="--split must be one of"):
        sweep_mod.run_sweep(["tiny"], 0.01, str(tmp_path / "x"), split="train")


def test_a_second_sweep_on_one_output_is_refused_before_it_trains(tmp_path, monkeypatch,
                                                                  capsys):
    """Two sweeps on one --output trained by turns, each refused in the
    folder the other held: both tables listed half the rows as failed."""
    from satagraph.lightning.reliability import run_lock
    trained = []
    monkeypatch.setattr(sweep_mod, "run_config", lambda run, **kw: trained.append(run))
    monkeypatch.setattr(sweep_mod, "check_runs", lambda runs, resume=False: set())
    with run_lock(tmp_path):  # the first sweep, still training
        code = main(["sweep", "--steps", "5", "--output", str(tmp_path), "tiny", "tiny"])
    assert code == 1 and trained == []
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"satagraph: error: {tmp_path}: --output is in use by another "
                          f"live run (pid {os.getpid()} on ")
    assert "choose another --output" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "sweep.md").exists()
