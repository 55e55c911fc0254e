"""The shipped text-to-motion model (``satagraph/weights/t2m_builtin.safetensors``):
small, saying what made it and on which data (no Bandai, no dog), loaded
offline, and generating on real skeletons of three species it never
trained on."""
from __future__ import annotations

import json
import socket
from pathlib import Path

import numpy as np
import pytest
import torch

from satagraph.cli import main
from satagraph.io import read_bvh
from satagraph.io.weights import MAX_WEIGHTS_BYTES, builtin_path, read_weights_metadata

SHIPPED = builtin_path("text-to-motion")
pytestmark = pytest.mark.skipif(not SHIPPED.is_file(),
                                reason="no built-in text-to-motion weights ship in this checkout")


def test_shipped_generator_describes_itself() -> None:
    assert SHIPPED.stat().st_size <= MAX_WEIGHTS_BYTES
    meta = read_weights_metadata(SHIPPED)
    assert meta["module"] == "t2m"
    assert "satagraph train t2m_builtin" in json.dumps(meta["provenance"])
    hparams = meta["hyper_parameters"]
    sources = json.dumps(hparams["meta"]["data"]["sources"]).lower()
    autoencoder = json.dumps(hparams["model"]["autoencoder"]["hparams"]["meta"]["data"]
                             ["sources"]).lower()
    for used in (sources, autoencoder):
        assert "zoo" in used and "ccbase" in used
        assert "bandai" not in used and "dataset: dog" not in used
    assert hparams["meta"]["text_encoder"]["id"].startswith("offline")


def test_generate_without_ckpt_on_three_species_offline(
        shared_data: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`satagraph generate` with no --ckpt, sockets refused: a Bandai human
    and the dog (real rigs it never trained on, in cm) and a zoo bird of a
    test seed get a finite motion each, on their own rigs, of the asked
    length; the same seed gives the same file."""
    def refuse(*args, **kwargs):
        raise AssertionError("network access at run time")
    monkeypatch.setattr(socket, "socket", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.datasets.zoo.dialects import export_dialect
    from satagraph.io import write_bvh
    bandai = shared_data / "bandai" / "dataset-1_walk_normal_001.bvh"
    dog = shared_data / "dog" / "D1_001_KAN01_001.bvh"
    bird = tmp_path / "bird.bvh"
    write_bvh(export_dialect(generate_clip(zoo_rigs(["bird"], seed=911)[0], frames=4),
                             scale=0.01), bird)  # in cm like the others
    out = tmp_path / "out"
    out.mkdir()
    args = ["generate", "--text", "walks forward", "--seconds", "2", "--seed", "3",
            "--skeleton", str(bandai), str(dog), str(bird), "--units", "cm", str(out)]
    assert main(args) == 0
    for src in (bandai, dog, bird):
        motion, rig = read_bvh(out / src.name), read_bvh(src)
        assert motion.skeleton.names == rig.skeleton.names
        assert motion.num_frames == 60
        assert np.isfinite(motion.global_positions()).all()
    first = (out / dog.name).read_bytes()
    assert main(args) == 0
    assert (out / dog.name).read_bytes() == first


def test_shipped_length_model_draws_full_motions_on_unseen_rigs() -> None:
    """Its captions describe motions at least 4 s long (zoo clips of drawn
    lengths are lower bounds), so without --seconds it draws 4 s on rigs
    it never saw, for any prompt, not a random 1-4 s."""
    import torch
    from satagraph.data.collate import collate_clips
    from satagraph.datasets.zoo.endless import EndlessZoo
    from satagraph.pipelines.generate import load_generator, rig_inputs
    from satagraph.pipelines.inference import target_clip
    module = load_generator("builtin").eval()
    zoo = EndlessZoo(["biped", "quadruped", "bird"], fps=30.0, seed=0)
    for i, subject in enumerate(("a person", "a quadruped", "a bird")):
        rig = rig_inputs(module, zoo.sample(0, i, 40, "test").motion)
        skel = module.skeleton_embedding(collate_clips([target_clip(rig.feats, 1,
                                                                    rig.semantic)]))
        for text in (f"{subject} walks forward", f"{subject} jumps", None):
            emb = None if text is None else module.encode_text([text])
            with torch.no_grad():
                p = module.length(emb, skel).softmax(-1)[0]
            assert float(p[-1]) > 0.9, (subject, text, p)


def test_generate_plants_the_feet_by_default(tmp_path: Path) -> None:
    """The built-in generator on a zoo quadruped of a test seed: by default
    the body is lowered onto its standing feet (it hovers less above its
    floor than with ``--no-plant``), with the same horizontal root path
    (``experiments/T2M.md`` section 47)."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    from satagraph.pipelines.quality import hover
    from satagraph.transforms.canonical import canonicalize
    rig = tmp_path / "quadruped.bvh"
    write_bvh(generate_clip(zoo_rigs(["quadruped"], seed=911)[0], frames=4), rig)
    motions = {}
    for flags in ((), ("--no-plant",)):
        out = tmp_path / f"out{len(flags)}.bvh"
        assert main(["generate", "--text", "a quadruped walks forward", "--seconds", "3",
                     "--skeleton", str(rig), *flags, str(out)]) == 0
        motions[flags] = canonicalize(read_bvh(out), fps=30.0, floor=False)
    planted, decoded = motions[()], motions[("--no-plant",)]
    np.testing.assert_allclose(planted.translations[:, 0, [0, 2]],
                               decoded.translations[:, 0, [0, 2]], atol=1e-6 * decoded.height())
    assert hover(planted) < 0.5 * hover(decoded)


def test_generate_carries_a_quadruped_as_its_own_clip_does(tmp_path: Path) -> None:
    """The built-in generator decodes "a quadruped walks forward" onto a
    zoo quadruped of a test seed with the forepaws held up (``--carriage
    never``: ``lands`` 0.11 against the rig's own walk, a forepaw down in
    a tenth as many frames); by default it is carried as that walk carries itself, the paws
    come down, and the root's horizontal path is the decoded one
    (``experiments/T2M.md`` sections 92-93). A carriage no mode names is
    refused in one line."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    from satagraph.pipelines.generate import GenerationSettings, SettingError
    from satagraph.pipelines.quality import lands
    from satagraph.transforms.canonical import canonicalize
    rig = tmp_path / "quadruped.bvh"
    write_bvh(generate_clip(zoo_rigs(["quadruped"], seed=911)[0], frames=60, seed=1), rig)
    own = canonicalize(read_bvh(rig), fps=30.0)
    motions = {}
    for flags in ((), ("--carriage", "never")):
        out = tmp_path / f"out{len(flags)}.bvh"
        assert main(["generate", "--text", "a quadruped walks forward", "--seconds", "3",
                     "--skeleton", str(rig), *flags, str(out)]) == 0
        motions[flags] = read_bvh(out)
    carried, decoded = motions[()], motions[("--carriage", "never")]
    assert lands(canonicalize(decoded, fps=30.0), own) < 0.2  # 0.11
    assert lands(canonicalize(carried, fps=30.0), own) > 0.8  # 0.88
    np.testing.assert_allclose(carried.translations[:, 0, [0, 2]],  # the file's own frame
                               decoded.translations[:, 0, [0, 2]], atol=1e-4 * decoded.height())
    with pytest.raises(SettingError, match="carriage must be one of"):
        GenerationSettings(carriage="sometimes")


@pytest.mark.slow
def test_residual_window_holds_the_pace_of_a_four_second_walk(tmp_path):
    """The built-in generator's four-second walks speed up along the clip
    (its residual guidance, ``experiments/T2M.md`` section 57);
    ``--residual-window 2`` fills the residual layers in two-second windows
    and the pace holds: over three seeds on a zoo biped the mean pace drift
    falls by more than 0.1, to under 0.1."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    from satagraph.pipelines.quality import pace_drift
    from satagraph.transforms.canonical import canonicalize
    rig = tmp_path / "biped.bvh"
    write_bvh(generate_clip(zoo_rigs(["biped"], seed=7)[0], frames=4), rig)
    drift = {}
    for flags in ((), ("--residual-window", "2")):
        values = []
        for seed in range(3):
            out = tmp_path / f"out{len(flags)}_{seed}.bvh"
            assert main(["generate", "--text", "a person walks forward", "--seconds", "4",
                         "--seed", str(seed), "--skeleton", str(rig), *flags, str(out)]) == 0
            values.append(pace_drift(canonicalize(read_bvh(out), fps=30.0)))
        drift[flags] = float(np.mean(values))
    whole, windowed = drift[()], drift[("--residual-window", "2")]
    assert whole - windowed > 0.1 and abs(windowed) < 0.1, drift


def test_a_residual_window_under_half_a_second_is_refused(tmp_path, capsys):
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    rig, out = tmp_path / "biped.bvh", tmp_path / "x.bvh"
    write_bvh(generate_clip(zoo_rigs(["biped"], seed=7)[0], frames=4), rig)
    with pytest.raises(SystemExit):
        main(["generate", "--text", "a walk", "--skeleton", str(rig), "--residual-window",
              "0.2", str(out)])
    assert "--residual-window" in capsys.readouterr().err and not out.exists()


@pytest.mark.slow
def test_a_clip_longer_than_the_trained_window_keeps_the_pace_of_one_within_it(tmp_path):
    """The built-in generator learnt 4-s windows (``meta["window"]``). A 12-s
    walk generated whole (``--window 0``) reads positions it never learnt;
    drawn from the guided logits (``--guide logits``, where it fails on
    every seed tried: experiments/T2M.md section 61) it shuffles at under
    half a 4-s walk's pace (0.17 of it with seed 0); by default it is
    generated in 4-s windows, each continuing the one before, and keeps at
    least 0.7 of that pace (0.88)."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    from satagraph.pipelines.quality import root_travel
    from satagraph.transforms.canonical import canonicalize
    rig = tmp_path / "biped.bvh"
    write_bvh(generate_clip(zoo_rigs(["biped"], seed=7)[0], frames=4), rig)

    def pace(seconds: str, *flags: str) -> float:
        out = tmp_path / f"walk_{seconds}_{len(flags)}.bvh"
        assert main(["generate", "--text", "a person walks forward", "--seconds", seconds,
                     "--seed", "0", "--guide", "logits", "--skeleton", str(rig), *flags,
                     str(out)]) == 0
        return root_travel(canonicalize(read_bvh(out), fps=30.0)) / float(seconds)

    four = pace("4")
    windowed, whole = pace("12") / four, pace("12", "--window", "0") / four
    assert windowed >= 0.7 and whole < 0.5, (windowed, whole)


def test_model_autoencoder_builtin_is_the_shipped_generators_own() -> None:
    """``model.autoencoder: builtin`` builds the SATA-RVQ the built-in
    generator was trained over from the generator's own file (it was a
    missing checkpoint: a user could not fine-tune the shipped generator),
    weight for weight the one ``generate`` decodes with."""
    from satagraph.lightning.text_to_motion import load_autoencoder
    from satagraph.pipelines.generate import load_generator
    autoencoder, stored = load_autoencoder("builtin")
    shipped = load_generator("builtin").autoencoder.state_dict()
    own = autoencoder.state_dict()
    assert stored["checkpoint"] == "builtin" and hasattr(autoencoder, "codes")
    assert own.keys() == shipped.keys()
    assert all(torch.equal(v, shipped[k]) for k, v in own.items())
    assert not any(p.requires_grad for p in autoencoder.parameters())


def test_init_from_builtin_starts_a_generator_from_the_shipped_one() -> None:
    """``satagraph train finetune_t2m_builtin --init-from builtin``: the
    config builds the shipped architecture over the shipped autoencoder,
    and ``builtin`` names the built-in generator's weights (it named the
    built-in retargeting model's, which fit none of them), every one loaded
    without a warning."""
    import warnings
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import build_module, init_weights
    from satagraph.pipelines.generate import load_generator
    module = build_module(load_config("finetune_t2m_builtin"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        init_weights(module, "builtin")
    shipped = load_generator("builtin").state_dict()
    state = module.state_dict()
    assert state.keys() == shipped.keys()
    assert all(torch.equal(v, shipped[k]) for k, v in state.items())
    assert set(load_generator("builtin").meta["caption_words"]) <= set(module.meta["caption_words"])


def test_init_from_builtin_on_another_generator_size_names_its_settings_shortly(
        autoencoder_ckpt: Path) -> None:
    """A generator of another size refuses ``--init-from builtin`` naming the
    settings that differ by their override names (``model.masked.heads=4``),
    not whole sections: the line held the built-in autoencoder's every
    hyperparameter, 2 000 characters."""
    from satagraph.experiment.train import init_weights
    from tests.t2m.conftest import build_t2m
    with pytest.raises(ValueError, match="another architecture") as err:
        init_weights(build_t2m(autoencoder_ckpt), "builtin")
    line = str(err.value)
    assert "model.masked.hidden_channels=128" in line and "finetune_t2m_builtin" in line
    assert "hparams" not in line and len(line) < 400, line
