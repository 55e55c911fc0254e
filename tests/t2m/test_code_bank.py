"""Code banks: a banked batch gives the losses of the frame batch it was
coded from, banks round-trip through their file, belong to one autoencoder
(its decoder aside), refuse damaged files by name, and `satagraph code-bank`
then `satagraph train ... data.code_bank=` train end to end."""
from __future__ import annotations

import copy

import pytest
import torch

from satagraph.cli import main
from satagraph.data.code_bank import (CodeBank, CodeBatch, DrawInterrupted,
                                      autoencoder_fingerprint, concat_banks, draw_code_bank,
                                      swap_skeletons)
from satagraph.experiment.config import load_config
from satagraph.experiment.train import train
from tests.t2m.conftest import build_t2m, tiny_train_overrides, zoo_batch


@pytest.fixture(scope="module")
def banked(autoencoder_ckpt):
    module = build_t2m(autoencoder_ckpt)
    batch = zoo_batch(5, mirror=0.5)
    return module, batch, module.bank_batch(batch)


def test_a_banked_batch_gives_the_losses_of_its_frame_batch(banked):
    module, batch, bank = banked
    coded = bank.collate(range(len(bank)))
    assert isinstance(coded, CodeBatch) and coded.texts == [m["text"] for m in batch.meta]
    module.train()
    live = module.compute_losses(batch, torch.Generator().manual_seed(3))
    fast = module.compute_losses(coded, torch.Generator().manual_seed(3))
    for key in ("masked", "residual", "length", "loss"):
        torch.testing.assert_close(fast[key], live[key])
    fast["loss"].backward()
    assert module.skeleton.lin.weight.grad.abs().sum() > 0


def test_a_bank_round_trips_through_its_file_and_gathers_any_order(banked, tmp_path):
    module, batch, bank = banked
    bank.save(tmp_path / "bank.safetensors")
    back = CodeBank.load(tmp_path / "bank.safetensors")
    assert back.texts == bank.texts and back.fingerprint == bank.fingerprint
    assert torch.equal(back.codes.long(), bank.codes.long())
    torch.testing.assert_close(back.x.float(), bank.x.half().float())
    one, other = bank.collate([3, 0]), back.collate([3, 0])
    assert bank.censored.all()  # zoo clips: their durations are lower bounds
    for key in ("codes", "num_frames", "parent", "node_clip", "texts", "seconds", "censored"):
        assert getattr(one, key) == getattr(other, key) if key == "texts" else \
            torch.equal(getattr(one, key), getattr(other, key)), key
    torch.testing.assert_close(one.x.half().float(), other.x)
    # window 3 first: its codes and skeleton are the frame batch's clip 3
    live, frames = module.batch_codes(batch)
    first = int(frames[3])
    assert torch.equal(one.codes[:first], live[3, :first])
    nodes = batch.stream_clip == 3
    assert one.node_clip.tolist() == [0] * int(nodes.sum()) + [1] * int((batch.stream_clip == 0).sum())
    local = batch.stream_parent[nodes] - int(nodes.nonzero()[0])
    assert torch.equal(one.parent[:int(nodes.sum())], local.clamp(min=-1))
    joined = concat_banks([bank, back])
    assert len(joined) == 2 * len(bank) and joined.collate([len(bank) + 1]).texts == \
        [bank.texts[1]]


def test_a_bank_made_before_censoring_reads_every_duration_as_known(banked, tmp_path):
    from safetensors.torch import load_file, save_file
    from safetensors import safe_open
    _, _, bank = banked
    bank.save(tmp_path / "new.safetensors")
    tensors = load_file(str(tmp_path / "new.safetensors"))
    with safe_open(str(tmp_path / "new.safetensors"), framework="pt") as f:
        meta = f.metadata()
    del tensors["censored"]
    save_file(tensors, str(tmp_path / "old.safetensors"), metadata=meta)
    old = CodeBank.load(tmp_path / "old.safetensors")
    assert not old.censored.any() and old.collate([0, 1]).censored.tolist() == [False] * 2
    assert torch.equal(old.seconds, bank.seconds)


def test_a_bank_belongs_to_its_autoencoder_decoder_aside(banked):
    module, _, bank = banked
    other = copy.deepcopy(module.autoencoder)
    with torch.no_grad():
        next(other.model.decoder.parameters()).add_(1.0)
    assert autoencoder_fingerprint(other) == bank.fingerprint
    bank.check_autoencoder(other)
    with torch.no_grad():
        next(other.model.encoder.parameters()).add_(1.0)
    with pytest.raises(ValueError, match="another autoencoder"):
        bank.check_autoencoder(other, "my.safetensors")


def test_damaged_and_foreign_files_are_named(tmp_path):
    from safetensors.torch import save_file
    bad = tmp_path / "bad.safetensors"
    bad.write_bytes(b"\x00" * 64)
    with pytest.raises(ValueError, match="bad.safetensors"):
        CodeBank.load(bad)
    foreign = tmp_path / "weights.safetensors"
    save_file({"w": torch.zeros(2)}, foreign)
    with pytest.raises(ValueError, match="weights.safetensors: not a satagraph code bank"):
        CodeBank.load(foreign)
    with pytest.raises(ValueError, match="2 frame counts"):
        CodeBank(torch.zeros(3, 2), torch.tensor([1, 2]), torch.zeros(2, 4), torch.tensor([-1]),
                 torch.tensor([1]), torch.tensor([1.0]), ["one"], "x")


def test_satagraph_code_bank_then_train_on_it(autoencoder_ckpt, tmp_path, capsys):
    path = tmp_path / "bank.safetensors"
    overrides = tiny_train_overrides(autoencoder_ckpt, tmp_path / "run", windows=4)
    assert main(["code-bank", "t2m_tiny", str(path), *overrides, "--windows", "6",
                 "--swap-rigs", "1"]) == 0  # nothing to swap on the zoo alone
    bank = CodeBank.load(path)
    # two epochs of 4 zoo windows: the second epoch's rigs are new ones
    assert len(bank) == 8 and len(set(bank.texts)) > 1
    assert int(bank.num_frames.min()) >= 12 and int(bank.num_frames.max()) <= 24
    module, dm, trainer, _ = train(load_config("t2m_tiny", overrides +
                                               [f"data.code_bank={path}"]))
    assert dm.bank is not None and trainer.global_step == 4  # 2 epochs of 2 banked batches
    assert "val_loss" in trainer.callback_metrics
    bank.fingerprint = "of another autoencoder"
    bank.save(path)
    with pytest.raises(ValueError, match="bank.safetensors: its codes are of another"):
        train(load_config("t2m_tiny", overrides + [f"data.code_bank={path}",
                                                   f"output_dir={tmp_path / 'run2'}"]))


@pytest.mark.slow
def test_a_text_to_motion_run_resumes_as_if_never_stopped(autoencoder_ckpt, tmp_path):
    """``--resume`` of a text-to-motion run was always refused (its recorded
    autoencoder is a dict, the config's a path), and a banked run's shuffle
    started over at epoch 0 on resuming: its weights went another way."""
    path = tmp_path / "bank.safetensors"
    overrides = tiny_train_overrides(autoencoder_ckpt, tmp_path / "bank_run", windows=4)
    assert main(["code-bank", "t2m_tiny", str(path), *overrides, "--windows", "8"]) == 0
    banked = [f"data.code_bank={path}"]

    def run(folder: str, steps: int, resume: bool = False):
        cfg = load_config("t2m_tiny", overrides + banked + [
            f"output_dir={tmp_path / folder}", f"trainer.max_steps={steps}",
            "trainer.max_epochs=-1"])
        return train(cfg, resume=resume)[0]

    whole = run("whole", 7)
    run("cut", 3)
    resumed = run("cut", 7, resume=True)
    for name, value in whole.state_dict().items():
        assert torch.equal(value, resumed.state_dict()[name]), name


def test_a_bank_says_when_a_run_names_other_data_than_it_was_drawn_from(banked, tmp_path):
    """A bank drawn from the zoo trained a run on ``--data mydata`` on zoo
    windows, silently, and recorded ``mydata``; so did one of 96-frame
    windows under ``data.window=48``."""
    import warnings
    _, _, coded = banked
    bank = copy.copy(coded)
    bank.check_data(["anything"], 16)  # a bank of unknown origin: nothing to say
    bank.data = {"sources": ["mydata"], "window": 96}
    bank.save(tmp_path / "b.safetensors")
    again = CodeBank.load(tmp_path / "b.safetensors")
    assert again.data == {"sources": ["mydata"], "window": 96}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again.check_data(["mydata"], 96)
    for sources, window in ((["zoo"], 96), (["mydata"], 48)):
        with pytest.warns(UserWarning, match=r"drawn from \['mydata'\] \(96 frames\)"):
            again.check_data(sources, window, "b.safetensors")


def test_several_banks_are_joined_and_foreign_ones_named(banked, tmp_path):
    from satagraph.data.caption_datamodule import CaptionDataModule
    _, _, coded = banked
    bank = copy.copy(coded)
    bank.save(tmp_path / "a.safetensors")
    bank.save(tmp_path / "b.safetensors")
    paths = [str(tmp_path / "a.safetensors"), str(tmp_path / "b.safetensors")]
    joined = CaptionDataModule([], code_bank=paths)._read_banks()
    assert len(joined) == 2 * len(coded) and joined.texts == 2 * list(coded.texts)
    assert torch.equal(joined.codes, torch.cat([coded.codes, coded.codes]))
    bank.fingerprint = "another"
    bank.save(tmp_path / "b.safetensors")
    with pytest.raises(ValueError, match="a.safetensors, .*b.safetensors hold the codes of"):
        CaptionDataModule([], code_bank=paths)._read_banks()
    with pytest.raises(ValueError, match="missing.safetensors"):
        CaptionDataModule([], code_bank=[paths[0], str(tmp_path / "missing.safetensors")]
                          )._read_banks()


def test_drawing_stops_when_its_time_is_up_with_the_batch_in_hand(banked):
    module, batch, coded = banked
    n, epochs = len(coded), []

    def loader_for_epoch(epoch):
        epochs.append(epoch)
        return [batch, batch, batch]

    bank = draw_code_bank(module, loader_for_epoch, windows=1000, max_seconds=0.0)
    assert len(bank) == n and epochs == [0]
    bank = draw_code_bank(module, loader_for_epoch, windows=4 * n)
    assert len(bank) == 4 * n and epochs == [0, 0, 1]
    assert torch.equal(bank.codes[:coded.codes.size(0)], coded.codes)


def test_ctrl_c_keeps_the_batches_drawn(banked):
    """Ctrl-C after two batches: the interrupt holds their bank (still a
    KeyboardInterrupt); before any batch, the plain interrupt."""
    module, batch, coded = banked

    def two_then_ctrl_c(epoch):
        yield batch
        yield batch
        raise KeyboardInterrupt

    with pytest.raises(DrawInterrupted) as stop:
        draw_code_bank(module, two_then_ctrl_c, windows=1000)
    assert isinstance(stop.value, KeyboardInterrupt) and len(stop.value.bank) == 2 * len(coded)
    assert torch.equal(stop.value.bank.codes[:coded.codes.size(0)], coded.codes)

    def at_once(epoch):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as stop:
        draw_code_bank(module, at_once, windows=10)
    assert type(stop.value) is KeyboardInterrupt


def test_satagraph_code_bank_writes_what_ctrl_c_leaves(autoencoder_ckpt, tmp_path, capsys,
                                                       monkeypatch):
    """Ctrl-C while the second batch is coded: the first one's 4 windows
    are written as a whole bank, said in one line, exit code 130."""
    from satagraph.lightning.text_to_motion import TextToMotionModule
    coded, calls = TextToMotionModule.bank_batch, []

    def ctrl_c_at_the_second(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return coded(self, *args, **kwargs)

    monkeypatch.setattr(TextToMotionModule, "bank_batch", ctrl_c_at_the_second)
    path = tmp_path / "bank.safetensors"
    overrides = tiny_train_overrides(autoencoder_ckpt, tmp_path / "run", windows=8)
    assert main(["code-bank", "t2m_tiny", str(path), *overrides, "--windows", "100"]) == 130
    assert len(CodeBank.load(path)) == 4
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith(f"satagraph: interrupted: wrote 4 windows (") and str(path) in last


def test_code_bank_refuses_what_it_cannot_bank(autoencoder_ckpt, tmp_path, capsys):
    path = tmp_path / "bank.safetensors"
    assert main(["code-bank", "tiny", str(path), "--windows", "2"]) == 2
    assert "is not a text-to-motion model" in capsys.readouterr().err
    overrides = tiny_train_overrides(autoencoder_ckpt, tmp_path / "run", windows=4)
    assert main(["code-bank", "t2m_tiny", str(path), *overrides, f"data.code_bank={path}",
                 "--windows", "2"]) == 2
    assert "unset data.code_bank" in capsys.readouterr().err
    assert main(["code-bank", "t2m_tiny", str(path), *overrides, "--windows", "2",
                 "--swap-rigs", "1.5"]) == 2
    assert "(--swap-rigs) must be in [0, 1], got 1.5" in capsys.readouterr().err
    assert not path.exists()


def _rig_bank(rigs, texts) -> CodeBank:
    """A bank of one-frame windows on the skeletons :obj:`rigs` (a node
    count each: a chain with node features equal to that count)."""
    x = torch.cat([torch.full((n, 3), float(n)) for n in rigs])
    parent = torch.cat([torch.arange(-1, n - 1) for n in rigs])
    count = len(rigs)
    return CodeBank(torch.arange(count)[:, None], torch.ones(count, dtype=torch.long), x,
                    parent, torch.tensor(rigs), torch.ones(count), texts, "f")


def test_captured_human_rigs_swap_skeletons_and_nothing_else_moves():
    # two captured human rigs (5 and 7 nodes, 30 windows each), a dog rig
    # as often, and zoo people whose rigs are new in every window
    rigs = [5] * 30 + [7] * 30 + [9] * 30 + list(range(10, 40))
    texts = (["a person walks"] * 30 + ["someone jumps"] * 30 + ["a dog trots"] * 30
             + ["a person waves"] * 30)
    bank = _rig_bank(rigs, texts)
    swapped = swap_skeletons(bank, share=0.5, seed=3)
    assert swapped.texts == bank.texts and torch.equal(swapped.codes, bank.codes)
    nodes = swapped.num_nodes.tolist()
    human = nodes[:60]
    assert set(human) == {5, 7} and 10 <= sum(a != b for a, b in zip(human, rigs[:60])) <= 50
    assert nodes[60:] == rigs[60:]  # the dog and the zoo's rigs keep theirs
    batch = swapped.collate(range(len(swapped)))  # every window whole on its new rig
    for i, n in enumerate(nodes):
        assert torch.equal(batch.x[batch.node_clip == i], torch.full((n, 3), float(n)))
    assert swap_skeletons(bank, share=0.5, seed=3).num_nodes.tolist() == nodes  # seeded
    assert swap_skeletons(bank, share=0.0) is bank
    with pytest.raises(ValueError, match="share"):
        swap_skeletons(bank, share=1.5)


def test_progress_is_a_line_in_place_on_a_terminal_and_lines_in_a_log():
    """``code-bank``'s count was redrawn with carriage returns everywhere, so
    a log file read it as one run-on line (``16 windows, 0 s22 windows, 0
    s...``): a log now gets a line of its own every 30 s, a terminal keeps
    the line redrawn in place."""
    import io
    from satagraph.cli.progress import ProgressLine
    now = [0.0]
    log = io.StringIO()
    line = ProgressLine(log, "windows", every=30.0, clock=lambda: now[0])
    for count, t in ((16, 5.0), (22, 31.0), (40, 40.0), (64, 62.0)):
        now[0] = t
        line(count)
    line.end()
    assert log.getvalue() == "22 windows, 31 s\n64 windows, 62 s\n"

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True
    term = Terminal()
    line = ProgressLine(term, "windows", clock=lambda: 0.0)
    line(16), line(22), line.end()
    assert term.getvalue() == "\r16 windows, 0 s\r22 windows, 0 s\n"
