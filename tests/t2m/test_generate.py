"""`satagraph generate`: BVH on the target's own rig (zoo and real
skeletons), one file per skeleton, same seed same output, no network, and
one-line errors without partial output."""
from __future__ import annotations

import socket
from collections import Counter
from pathlib import Path

import numpy as np
import torch
import pytest

from satagraph.cli import main
from satagraph.pipelines.generate import GenerationSettings, output_paths
from satagraph.io import read_bvh
from tests.conftest import data_dir

TEXT = "a person walks forward and turns to the left"


def _generate(ckpt, skeletons, out, *extra) -> int:
    return main(["generate", "--ckpt", str(ckpt), "--text", TEXT, "--skeleton",
                 *[str(s) for s in skeletons], *extra, str(out)])


def _same_rig(out_path: Path, target_path: Path) -> None:
    out, target = read_bvh(str(out_path)), read_bvh(str(target_path))
    assert out.skeleton.names == target.skeleton.names
    assert np.array_equal(out.skeleton.parents, target.skeleton.parents)
    assert out.skeleton.channels == target.skeleton.channels
    np.testing.assert_allclose(out.skeleton.offsets, target.skeleton.offsets, atol=1e-4)
    assert np.isfinite(out.rotations).all() and np.isfinite(out.translations).all()


def test_generate_on_a_zoo_skeleton_writes_its_rig(t2m_ckpt, zoo_skeletons, tmp_path):
    out = tmp_path / "walk.bvh"
    assert _generate(t2m_ckpt, [zoo_skeletons["biped"]], out, "--seconds", "1.5") == 0
    _same_rig(out, zoo_skeletons["biped"])  # +Z up, centimetres: the target's own
    motion = read_bvh(str(out))
    assert motion.num_frames == 45 and motion.fps == pytest.approx(30.0)
    height = np.ptp(motion.global_positions()[0], axis=0)
    assert height[2] > 50  # still in centimetres, still +Z up


def test_several_skeletons_give_one_file_each(t2m_ckpt, zoo_skeletons, tmp_path, capsys):
    skeletons = [zoo_skeletons[s] for s in ("biped", "quadruped", "bird")]
    out = tmp_path / "walk.bvh"
    assert _generate(t2m_ckpt, skeletons, out, "--seconds", "1") == 0
    for path, skeleton in zip(output_paths(str(out), [str(s) for s in skeletons]),
                              skeletons):
        assert Path(path).name == f"walk_{Path(skeleton).stem}.bvh"
        _same_rig(Path(path), skeleton)
    assert not out.exists()
    assert capsys.readouterr().out.count("wrote ") == 3


def test_without_seconds_the_length_model_decides(t2m_ckpt, zoo_skeletons, tmp_path):
    out = tmp_path / "any.bvh"
    assert _generate(t2m_ckpt, [zoo_skeletons["quadruped"]], out) == 0
    frames = read_bvh(str(out)).num_frames
    assert 1 <= frames <= 3.0 * 30  # the tiny length model's range: up to 3 s


def test_same_seed_same_output(t2m_ckpt, zoo_skeletons, tmp_path):
    paths = [tmp_path / f"{name}.bvh" for name in ("a", "b", "c")]
    for path, seed in zip(paths, ("3", "3", "4")):
        assert _generate(t2m_ckpt, [zoo_skeletons["bird"]], path, "--seconds", "1",
                         "--seed", seed) == 0
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert paths[0].read_bytes() != paths[2].read_bytes()


def test_generate_needs_no_network(t2m_ckpt, zoo_skeletons, tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("network access during generation")
    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket.socket, "connect_ex", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    monkeypatch.setattr(socket, "getaddrinfo", refuse)
    out = tmp_path / "offline.bvh"
    assert _generate(t2m_ckpt, [zoo_skeletons["biped"]], out, "--seconds", "1") == 0
    assert out.is_file()


@pytest.mark.skipif(data_dir() is None, reason="../shared/data not found: the real "
                    "CMU file is needed")
def test_generate_on_a_real_file_writes_its_rig(t2m_ckpt, tmp_path):
    target = data_dir() / "cmu" / "01_01.bvh"
    out = tmp_path / "cmu.bvh"
    assert _generate(t2m_ckpt, [target], out, "--seconds", "1") == 0
    _same_rig(out, target)


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("satagraph: error: ")
    return err[0]


@pytest.mark.skipif(data_dir() is None, reason="../shared/data not found: the real "
                    "dog file is needed")
@pytest.mark.parametrize("frames", [0, 1])
def test_a_line_rest_that_shows_no_body_is_refused(tmp_path, capsys, frames):
    """The dog's rig without frames, or in one frame at rest: ``retarget``
    refused the first; ``generate`` tumbled a walk on it, or (carried as
    that frame) laid it flat. Refused in one line naming the file, before
    any model loads."""
    from satagraph.io import write_bvh
    dog = read_bvh(data_dir() / "dog" / "D1_001_KAN01_001.bvh").slice(0, frames)
    rig = tmp_path / "rig.bvh"
    write_bvh(dog.with_(rotations=np.broadcast_to(np.eye(3), dog.rotations.shape).copy()), rig)
    assert main(["generate", "--text", "a dog walks forward", "--skeleton", str(rig),
                 "--units", "cm", str(tmp_path / "out.bvh")]) == 2
    assert f"{rig}: a rig " in _error(capsys) and not (tmp_path / "out.bvh").exists()


def test_missing_checkpoint_is_one_line(zoo_skeletons, tmp_path, capsys):
    out = tmp_path / "x.bvh"
    assert _generate(tmp_path / "none.ckpt", [zoo_skeletons["biped"]], out) == 2
    assert "none.ckpt" in _error(capsys) and not out.exists()


def test_an_autoencoder_checkpoint_is_refused(autoencoder_ckpt, zoo_skeletons, tmp_path,
                                              capsys):
    out = tmp_path / "x.bvh"
    assert _generate(autoencoder_ckpt, [zoo_skeletons["biped"]], out) == 2
    line = _error(capsys)
    assert str(autoencoder_ckpt) in line and "not a text-to-motion" in line
    assert not out.exists()


def test_an_input_or_a_capture_is_never_overwritten(t2m_ckpt, zoo_skeletons, tmp_path,
                                                    capsys):
    """Without OUT, ``--skeleton a.bvh clip.bvh`` makes ``clip.bvh`` the
    output: a capture satagraph did not write is refused, as is an output
    that is an input; a file generate wrote may be written again."""
    import shutil
    clip = tmp_path / "clip.bvh"
    shutil.copy(zoo_skeletons["quadruped"], clip)
    before = clip.read_bytes()
    assert main(["generate", "--ckpt", str(t2m_ckpt), "--text", TEXT, "--skeleton",
                 str(zoo_skeletons["biped"]), str(clip)]) == 2
    assert "not written by satagraph" in _error(capsys) and clip.read_bytes() == before
    assert _generate(t2m_ckpt, [clip], clip, "--seconds", "1") == 2
    assert "overwrite an input" in _error(capsys) and clip.read_bytes() == before
    out = tmp_path / "again.bvh"
    for _ in range(2):
        assert _generate(t2m_ckpt, [zoo_skeletons["biped"]], out, "--seconds", "1") == 0


def test_a_bad_skeleton_file_is_named(t2m_ckpt, zoo_skeletons, tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n")
    out = tmp_path / "x.bvh"
    assert _generate(t2m_ckpt, [zoo_skeletons["biped"], bad], out) == 2
    assert "bad.bvh" in _error(capsys)
    assert not list(tmp_path.glob("x*.bvh"))  # no partial set of outputs


def test_an_empty_text_generates_for_the_skeleton_alone(t2m_ckpt, zoo_skeletons, tmp_path):
    """No text: a motion for the skeleton alone, which the text changes (a
    barely trained model may agree with itself on some seeds: any of four
    must differ; strong guidance makes the text's share of the logits
    count; the seeds after the first that differs would not change that)."""
    differ = []
    for seed in range(4):
        out, text = tmp_path / f"none{seed}.bvh", tmp_path / f"text{seed}.bvh"
        argv = ["generate", "--ckpt", str(t2m_ckpt), "--skeleton", str(zoo_skeletons["bird"]),
                "--seconds", "1", "--seed", str(seed), "--guidance", "8"]
        assert main(argv + ["--text", "", str(out)]) == 0
        assert main(argv + ["--text", TEXT, str(text)]) == 0
        _same_rig(out, zoo_skeletons["bird"])
        differ.append(out.read_bytes() != text.read_bytes())
        if differ[-1]:
            break
    assert any(differ)


@pytest.mark.parametrize("flag,value,said", [
    ("--threads", "0", "--threads must be at least 1"),
    ("--steps", "0", "error: --steps must be at least 1"),  # the option, as --threads
    ("--guidance", "nan", "error: --guidance must be a finite number >= 0, got nan"),
    ("--draw-guidance", "-1", "error: --draw-guidance must be a finite number >= 0"),
    ("--guide", "greedy", "unknown guide 'greedy'"),
])
def test_bad_numbers_are_one_line(t2m_ckpt, zoo_skeletons, tmp_path, capsys, flag, value, said):
    out = tmp_path / "x.bvh"
    assert _generate(t2m_ckpt, [zoo_skeletons["biped"]], out, flag, value) == 2
    assert said in _error(capsys) and not out.exists()


def test_settings_refuse_what_no_sampling_means():
    GenerationSettings(guidance=0.0, temperature=0.0, window=None, layers=1)  # all meaningful
    for bad, said in ((dict(guidance=float("inf")), "guidance must be a finite"),
                      (dict(temperature=-0.5), "temperature must be a finite"),
                      (dict(topk_ratio=1.5), r"topk_ratio must be in \(0, 1\]"),
                      (dict(rerank=0), "rerank must be at least 1"),
                      (dict(layers=0), "layers must be at least 1"),
                      (dict(smooth=-1.0), "smooth must be a finite")):
        with pytest.raises(ValueError, match=said):
            GenerationSettings(**bad)


def test_a_refused_setting_carries_its_field():
    """``generate`` named the option by parsing the field out of the start
    of the message; the error carries it (and survives a worker's pickle)."""
    import pickle
    from satagraph.pipelines.generate import SettingError
    for bad in (dict(draw_guidance=-1.0), dict(residual_window=float("nan")), dict(steps=0),
                dict(topk_ratio=0.0)):
        with pytest.raises(SettingError) as error:
            GenerationSettings(**bad)
        (field, value), = bad.items()
        assert error.value.field == field and str(error.value) == (
            f"{field} {error.value.problem}") and f"got {value}" in error.value.problem
        copy = pickle.loads(pickle.dumps(error.value))
        assert (copy.field, str(copy)) == (field, str(error.value))


def test_an_exported_weights_file_generates_like_its_checkpoint(t2m_ckpt, zoo_skeletons,
                                                                 tmp_path):
    """`export-weights` of a text-to-motion run (frozen autoencoder inside)
    gives a safetensors file that `generate` reads: same motion, float32."""
    weights = tmp_path / "t2m.safetensors"
    assert main(["export-weights", str(t2m_ckpt), str(weights)]) == 0
    a, b = tmp_path / "a.bvh", tmp_path / "b.bvh"
    assert _generate(t2m_ckpt, [zoo_skeletons["biped"]], a, "--seconds", "1") == 0
    assert _generate(weights, [zoo_skeletons["biped"]], b, "--seconds", "1") == 0
    np.testing.assert_allclose(read_bvh(str(b)).rotations, read_bvh(str(a)).rotations,
                               atol=1e-4)


def test_builtin_generator_is_the_default_and_says_so(t2m_ckpt, zoo_skeletons, tmp_path,
                                                      monkeypatch, capsys):
    """Without --ckpt, generate uses the package's text-to-motion weights
    (here a stand-in file) and says so in one line on stderr; without any,
    one line says how to train them."""
    from satagraph.io import weights
    shipped = tmp_path / "t2m_builtin.safetensors"
    assert main(["export-weights", str(t2m_ckpt), str(shipped), "--half",
                 "--note", "a stand-in"]) == 0
    monkeypatch.setattr(weights, "builtin_path",
                        lambda kind="autoencoder", name="builtin": shipped if kind == "text-to-motion"
                        else tmp_path / "none.safetensors")
    out = tmp_path / "walk.bvh"
    capsys.readouterr()
    assert main(["generate", "--text", TEXT, "--skeleton", str(zoo_skeletons["biped"]),
                 "--seconds", "1", str(out)]) == 0
    err = capsys.readouterr().err
    assert "using the built-in text-to-motion model" in err and "a stand-in" in err
    _same_rig(out, zoo_skeletons["biped"])
    shipped.unlink()
    assert main(["generate", "--text", TEXT, "--skeleton", str(zoo_skeletons["biped"]),
                 str(tmp_path / "none.bvh")]) == 2
    line = _error(capsys)
    assert "t2m_builtin" in line and not (tmp_path / "none.bvh").exists()


def test_generated_motion_stands_on_the_floor_unless_no_ground(t2m_ckpt, zoo_skeletons,
                                                               tmp_path,
                                                               assert_grounded_pair):
    """By default the motion is shifted (one constant) so that its median
    lowest joint is on the floor, and each frame that would then sink is
    raised onto it; --no-ground differs by that shift elsewhere."""
    outs = {}
    for flag in ("--ground", "--no-ground"):
        outs[flag] = tmp_path / f"g{flag}.bvh"
        assert main(["generate", "--ckpt", str(t2m_ckpt), "--skeleton",
                     str(zoo_skeletons["quadruped"]), "--text", TEXT, "--seconds", "1",
                     flag, "--no-plant", str(outs[flag])]) == 0
    assert_grounded_pair(outs["--ground"], outs["--no-ground"], lifted=True)


def _decoded_codes(t2m_ckpt, zoo_skeletons, monkeypatch):
    """The generator, the zoo biped, and the list every code stack that
    ``generate_on`` decodes is appended to."""
    from satagraph.io import read_bvh
    from satagraph.pipelines import generate as G
    seen = []
    real = G.decode_on
    monkeypatch.setattr(G, "decode_on", lambda m, codes, *a, **k: (seen.append(codes),
                                                                     real(m, codes, *a, **k))[1])
    return G.load_generator(str(t2m_ckpt)), read_bvh(str(zoo_skeletons["biped"])), seen


def test_fewer_layers_and_a_greedy_residual_change_only_what_they_name(
        t2m_ckpt, zoo_skeletons, monkeypatch):
    """``GenerationSettings.layers`` decodes the first layers only (the rest
    -1, a dropped layer to the RVQ), after the same layer-0 codes; with a
    residual temperature of 0 the residual layers no longer depend on the
    seed (given the same layer 0)."""
    from satagraph.pipelines import generate as G
    module, target, seen = _decoded_codes(t2m_ckpt, zoo_skeletons, monkeypatch)
    full = G.GenerationSettings(residual_temperature=1.0)
    G.generate_on(module, TEXT, target, 1.0, 0, full)
    G.generate_on(module, TEXT, target, 1.0, 0, G.GenerationSettings(layers=1))
    assert seen[0].shape == seen[1].shape and seen[0].shape[1] == module.num_quantizers
    assert (seen[1][:, 1:] == -1).all() and (seen[0][:, 1:] >= 0).all()
    assert torch.equal(seen[0][:, 0], seen[1][:, 0])
    # the same layer 0 for every seed: residual layers then vary with the
    # seed when sampled, not when greedy
    base = module.masked.generate
    monkeypatch.setattr(module.masked, "generate",  # the generator comes last
                        lambda *a, **k: base(*a[:-1], torch.Generator().manual_seed(0), **k))
    for settings in (full, G.GenerationSettings(residual_temperature=0.0)):
        for seed in (0, 1):
            G.generate_on(module, TEXT, target, 1.0, seed, settings)
    sampled, greedy = seen[2:4], seen[4:6]
    assert torch.equal(sampled[0][:, 0], sampled[1][:, 0])
    assert not torch.equal(sampled[0], sampled[1])
    assert torch.equal(greedy[0], greedy[1])


def test_generate_on_infills_around_kept_tokens(t2m_ckpt, zoo_skeletons, monkeypatch):
    """``generate_on(known=, keep=)``: the kept layer-0 tokens are decoded
    as given, over their frames (one token every ``pool`` frames)."""
    from satagraph.pipelines import generate as G
    module, target, seen = _decoded_codes(t2m_ckpt, zoo_skeletons, monkeypatch)
    frames, pool = 30, module.masked.pool
    known = torch.arange(-(-frames // pool)).remainder(module.masked.num_codes)[None]
    keep = torch.zeros_like(known, dtype=torch.bool)
    keep[:, ::2] = True
    G.generate_on(module, TEXT, target, frames / module.fps, 0, known=known, keep=keep)
    layer0 = seen[0][:, 0]
    assert layer0.numel() == frames
    for token in keep[0].nonzero().view(-1).tolist():
        assert (layer0[token * pool:(token + 1) * pool] == known[0, token]).all()


@pytest.mark.slow
def test_export_swaps_in_a_decoder_fine_tuned_under_frozen_codes(
        t2m_ckpt, autoencoder_ckpt, zoo_skeletons, tmp_path, capsys):
    """`export-weights --decoder`: the generator keeps its codes and decodes
    with the new decoder (also from a half-precision file), under the latent
    smoothing it was trained with; a checkpoint whose encoder moved is
    refused in one line, and nothing is written."""
    from satagraph.experiment.train import load_module
    from tests.t2m.conftest import save_checkpoint
    tuned = load_module(str(autoencoder_ckpt))
    tuned.hparams["model"]["latent_smooth"] = tuned.model.latent_smooth = 1.5
    with torch.no_grad():
        for param in tuned.model.decoder.parameters():
            param.add_(0.05 * torch.randn(param.shape, generator=torch.Generator().manual_seed(1)))
    tuned_ckpt = save_checkpoint(tuned, tmp_path / "tuned.ckpt")
    half = tmp_path / "half.safetensors"
    assert main(["export-weights", str(t2m_ckpt), str(half), "--half"]) == 0
    swapped = tmp_path / "swapped.safetensors"
    assert main(["export-weights", str(half), str(swapped), "--decoder", str(tuned_ckpt),
                 "--minutes", "3"]) == 0
    from satagraph.io.weights import read_weights_metadata
    provenance = read_weights_metadata(swapped)["provenance"]  # the first export's stays
    assert provenance["decoder"] == str(tuned_ckpt) and provenance["minutes"] == 3.0
    assert provenance["previous"] == read_weights_metadata(half)["provenance"]
    assert provenance["previous"]["source"] == str(t2m_ckpt)
    module, original = load_module(str(swapped)), load_module(str(half))
    assert (module.autoencoder.model.latent_smooth, original.autoencoder.model.latent_smooth) \
        == (1.5, 0.0)
    for name, value in module.autoencoder.state_dict().items():  # the tuned RVQ's ...
        torch.testing.assert_close(value, tuned.state_dict()[name], rtol=0, atol=0, msg=name)
        if not name.startswith("model.decoder."):  # ... whose other parts were the generator's
            torch.testing.assert_close(value.half(), original.autoencoder.state_dict()[name]
                                       .to(value.dtype).half(), rtol=0, atol=0, msg=name)
    a, b = tmp_path / "a.bvh", tmp_path / "b.bvh"
    assert _generate(half, [zoo_skeletons["biped"]], a, "--seconds", "1") == 0
    assert _generate(swapped, [zoo_skeletons["biped"]], b, "--seconds", "1") == 0
    assert np.abs(read_bvh(str(a)).rotations - read_bvh(str(b)).rotations).max() > 1e-3

    _refuses_a_moved_part(tuned, tuned.model.encoder, "--decoder", "model.encoder.", half,
                          tmp_path, capsys)


def test_codes_go_through_the_autoencoder_in_its_training_windows(t2m_ckpt, monkeypatch):
    """A motion longer than the RVQ's training window (32 frames here) is
    encoded and decoded window by window: no call sees more frames than the
    window, the first window's frames are what that window alone gives, and
    a motion within one window is decoded exactly as in one call."""
    from satagraph.data.collate import collate_clips
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.zoo import zoo_rigs
    from satagraph.datasets.zoo.motions import generate_clip
    from satagraph.pipelines.generate import (decode_windows, encode_windows, load_generator,
                                              rig_inputs)
    from satagraph.pipelines.inference import facing_smooth_of, target_clip
    module = load_generator(str(t2m_ckpt))
    ae = module.autoencoder
    assert ae.meta["window"] == 32
    rig = next(r for r in zoo_rigs(["biped"], seed=5))
    inputs = rig_inputs(module, generate_clip(rig, "walk", frames=80, seed=0))
    feats = motion_to_features(inputs.shown, facing_smooth=facing_smooth_of(module))
    seen = []
    codes_of, decode = ae.codes, ae.decode_codes
    monkeypatch.setattr(ae, "codes", lambda batch: seen.append(
        batch.clip_num_frames.tolist()) or codes_of(batch))
    monkeypatch.setattr(ae, "decode_codes", lambda c, t, s=0.0: seen.append(
        t.clip_num_frames.tolist()) or decode(c, t, s))
    codes = encode_windows(ae, feats, inputs.semantic)
    q, r = decode_windows(ae, codes, inputs)
    assert codes.shape == (80, module.num_quantizers) and bool((codes >= 0).all())
    assert r.shape == (80, 4) and q.shape == (80 * feats.skeleton.num_joints, 6)
    # 3 windows (stride 24): encoded in one batch, decoded one by one
    assert seen == [[32, 32, 32], [32], [32], [32]]
    first = codes_of(collate_clips([feats.to_clip(0, 32, inputs.semantic)]))
    assert torch.equal(codes[:32], first)
    alone = decode(codes[:32], collate_clips([target_clip(inputs.feats, 32, inputs.semantic)]))
    torch.testing.assert_close(r[:24], alone["r"][:24])
    # the 8 frames two windows share fade from the first's reading into the second's
    second = decode(codes[24:56], collate_clips([target_clip(inputs.feats, 32, inputs.semantic)]))
    fade = torch.arange(1, 9).unsqueeze(-1) / 9
    torch.testing.assert_close(
        r[24:32], (1 - fade) * alone["r"][24:] + fade * second["r"][:8])
    torch.testing.assert_close(r[32:48], second["r"][8:24])
    short = codes[:20]
    q_short, r_short = decode_windows(ae, short, inputs)
    whole = decode(short, collate_clips([target_clip(inputs.feats, 20, inputs.semantic)]))
    torch.testing.assert_close(r_short, whole["r"])
    torch.testing.assert_close(q_short, whole["q"])


def test_generator_trains_on_codes_of_the_autoencoders_windows(t2m_ckpt):
    """A training batch of windows longer than the RVQ's (32 frames here)
    gets the codes `generate` decodes: each clip's codes in the RVQ's
    windows, as `encode_windows` gives them; a batch within one window is
    encoded whole, as before."""
    from satagraph.data.collate import collate_clips
    from satagraph.data.dataset import _frames
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.zoo import zoo_rigs
    from satagraph.datasets.zoo.motions import generate_clip
    from satagraph.pipelines.generate import encode_windows, load_generator, rig_inputs
    from satagraph.pipelines.inference import facing_smooth_of
    module = load_generator(str(t2m_ckpt))
    feats, semantic = [], []
    for rig, action in zip(zoo_rigs(["biped", "quadruped"], seed=5), ("walk", "run")):
        inputs = rig_inputs(module, generate_clip(rig, action, frames=70, seed=1))
        feats.append(motion_to_features(inputs.shown, facing_smooth=facing_smooth_of(module)))
        semantic.append(inputs.semantic)
    clips = [f.to_clip(0, t, s) for f, s, t in zip(feats, semantic, (70, 50))]
    codes, lengths = module.batch_codes(collate_clips(clips))
    assert lengths.tolist() == [70, 50] and codes.shape == (2, 70, module.num_quantizers)
    for k, (f, s, t) in enumerate(zip(feats, semantic, (70, 50))):
        want = encode_windows(module.autoencoder, _frames(f, slice(0, t)), s)
        assert torch.equal(codes[k, :t], want)
        assert bool((codes[k, t:] == -1).all())
    one = collate_clips([feats[0].to_clip(0, 30, semantic[0])])
    assert torch.equal(module.batch_codes(one)[0][0], module.autoencoder.codes(one))
    whole = module.autoencoder.codes(collate_clips(clips[:1]))
    assert not torch.equal(codes[0], whole)  # past frame 32 the windows differ


def test_units_and_up_axes_per_skeleton(t2m_ckpt, zoo_skeletons, tmp_path, capsys):
    """``--units cm,m`` reads each skeleton file in its own units (the
    reading each output ends with says so); a list of another length is
    one error line before anything is written."""
    skeletons = [zoo_skeletons[s] for s in ("biped", "quadruped")]
    out = tmp_path / "walk.bvh"
    assert _generate(t2m_ckpt, skeletons, out, "--seconds", "1", "--up-axis", "+Z",
                     "--units", "cm,m") == 0
    tails = [Path(p).read_text().splitlines()[0]
             for p in output_paths(str(out), [str(s) for s in skeletons])]
    assert "up_axis=+Z" in tails[0] and "scale=0.01" in tails[0]
    assert "up_axis=+Z" in tails[1] and "scale=1" in tails[1]
    bad = tmp_path / "bad.bvh"
    assert _generate(t2m_ckpt, skeletons, bad, "--units", "cm,m,in") == 2
    assert "--units has 3 values for 2 files" in capsys.readouterr().err
    assert not list(tmp_path.glob("bad*"))


def test_export_swaps_in_a_length_model_trained_alone(t2m_ckpt, autoencoder_ckpt, tmp_path,
                                                      capsys):
    """`export-weights --length`: the generator draws durations with a length
    model trained with every other part frozen (other bins allowed); one whose
    transformer moved is refused in one line, and nothing is written."""
    from satagraph.experiment.train import load_module
    from satagraph.io.weights import read_weights_metadata
    from satagraph.nn.generators import LengthModel
    from tests.t2m.conftest import save_checkpoint
    tuned = load_module(str(t2m_ckpt))
    lm = tuned.length
    tuned.length = LengthModel(lm.text_proj.in_features, lm.skel_proj.in_features,
                               hidden_channels=16, bin_seconds=0.5, max_seconds=6.0)
    tuned.hparams["model"]["length"] = {"hidden_channels": 16, "bin_seconds": 0.5,
                                        "max_seconds": 6.0}
    tuned_ckpt = save_checkpoint(tuned, tmp_path / "length.ckpt")
    half = tmp_path / "half.safetensors"
    assert main(["export-weights", str(t2m_ckpt), str(half), "--half"]) == 0
    swapped = tmp_path / "swapped.safetensors"
    assert main(["export-weights", str(half), str(swapped), "--length", str(tuned_ckpt)]) == 0
    provenance = read_weights_metadata(swapped)["provenance"]
    assert provenance["length"] == str(tuned_ckpt) and "previous" in provenance
    module, original = load_module(str(swapped)), load_module(str(half))
    assert module.length.num_bins == 12
    for name, value in module.length.state_dict().items():
        torch.testing.assert_close(value, tuned.length.state_dict()[name], rtol=0, atol=0,
                                   msg=name)
    own = {k: v for k, v in module.state_dict().items() if not k.startswith("length.")}
    assert own.keys() == {k for k in original.state_dict() if not k.startswith("length.")}
    assert all(torch.equal(v, original.state_dict()[k]) for k, v in own.items())

    _refuses_a_moved_part(tuned, tuned.masked, "--length", "masked.", half, tmp_path, capsys)


def _refuses_a_moved_part(tuned, part, flag: str, name: str, half, tmp_path, capsys) -> None:
    """``export-weights HALF OUT FLAG CKPT`` with :obj:`part` of CKPT moved
    is refused in one line naming CKPT and the part, and writes nothing."""
    from tests.t2m.conftest import save_checkpoint
    with torch.no_grad():
        next(part.parameters()).add_(0.1)
    moved = save_checkpoint(tuned, tmp_path / "moved.ckpt")
    capsys.readouterr()
    bad = tmp_path / "bad.safetensors"
    assert main(["export-weights", str(half), str(bad), flag, str(moved)]) == 2
    line = _error(capsys)
    assert "moved.ckpt" in line and name in line and "optim.frozen" in line
    assert not bad.exists()


@pytest.mark.slow
def test_render_draws_every_skeletons_motion_side_by_side(t2m_ckpt, zoo_skeletons, tmp_path,
                                                          capsys):
    """`generate --render OUT.gif`: the motions written, rendered one panel
    per skeleton; a --render that is no GIF or MP4 is refused before
    anything is generated."""
    from PIL import Image
    skeletons = [zoo_skeletons["biped"], zoo_skeletons["quadruped"]]
    out, gif = tmp_path / "out.bvh", tmp_path / "both.gif"
    assert _generate(t2m_ckpt, skeletons, out, "--seconds", "1", "--render", str(gif)) == 0
    written = sorted(tmp_path.glob("out_*.bvh"))
    assert len(written) == 2
    with Image.open(gif) as image:  # 1 s at 30 fps, shown at the GIF's 33.3
        motion = read_bvh(str(written[0]))
        seconds = image.n_frames * image.info["duration"] / 1000
        assert abs(seconds - motion.num_frames / motion.fps) < 0.04
        width = image.size[0]
    single = tmp_path / "one.gif"
    assert _generate(t2m_ckpt, skeletons[:1], tmp_path / "one.bvh", "--seconds", "1",
                     "--render", str(single)) == 0
    with Image.open(single) as image:
        assert width > 1.5 * image.size[0]  # two panels side by side
    capsys.readouterr()
    bad = tmp_path / "bad.bvh"
    assert _generate(t2m_ckpt, skeletons, bad, "--render", str(tmp_path / "x.png")) == 2
    assert "x.png" in _error(capsys) and not list(tmp_path.glob("bad*.bvh"))


def test_the_rest_a_rig_is_shown_in_matters_only_where_auto_re_rests(t2m_ckpt, zoo_skeletons):
    """GenerationSettings.rest: a designed rest reads the same shown as in
    its file or re-rested (auto keeps it); a line rest is re-rested by auto
    only, and the output keeps the file's rest either way."""
    from satagraph.pipelines.generate import GenerationSettings, generate_on, load_generator
    from satagraph.transforms.rest import needs_rest
    from satagraph.transforms.canonical import canonicalize
    from satagraph.datasets.zoo.dialects import Dialect, apply_dialect
    module = load_generator(str(t2m_ckpt))
    designed = read_bvh(str(zoo_skeletons["quadruped"]))
    line, _ = apply_dialect(canonicalize(designed), Dialect(rest="axis"))  # the same motion
    assert not needs_rest(canonicalize(designed).skeleton)
    assert needs_rest(canonicalize(line).skeleton)
    outs = {}
    for name, rig in (("designed", designed), ("line", line)):
        for rest in ("auto", "file"):
            outs[name, rest] = generate_on(module, "a quadruped walks", rig, 1.0, 0,
                                           GenerationSettings(rest=rest))
            np.testing.assert_allclose(outs[name, rest].skeleton.offsets,
                                       rig.skeleton.offsets, atol=1e-6)
    assert np.array_equal(outs["designed", "auto"].rotations, outs["designed", "file"].rotations)
    assert not np.allclose(outs["line", "auto"].rotations, outs["line", "file"].rotations)


def test_smooth_decoded_smooths_each_joint_along_time_only():
    """``output_smooth``: each joint's 6D rotation and the root features are
    smoothed along the frames; joints never mix, a constant stays, 0 is a
    no-op."""
    from satagraph.pipelines.generate import smooth_decoded
    frames, joints = 40, 3
    q = torch.zeros(frames, joints, 6)
    q[:, 0] = torch.tensor([1.0, 0, 0, 0, 1.0, 0])  # constant
    q[:, 1, 0] = torch.tensor([(-1.0) ** t for t in range(frames)])  # shakes every frame
    q[:, 2, 3] = torch.linspace(0, 1, frames)  # a ramp
    r = torch.stack([torch.arange(frames, dtype=torch.float32) % 2] * 4, dim=-1)
    same_q, same_r = smooth_decoded(q.reshape(-1, 6), r, 0.0)
    assert torch.equal(same_q, q.reshape(-1, 6)) and torch.equal(same_r, r)
    sq, sr = smooth_decoded(q.reshape(-1, 6), r, 2.0)
    sq = sq.view(frames, joints, 6)
    assert sq.shape == q.shape and sr.shape == r.shape
    torch.testing.assert_close(sq[:, 0], q[:, 0])
    assert sq[5:-5, 1, 0].abs().max() < 0.05  # the shake is gone
    torch.testing.assert_close(sq[7:-7, 2, 3], q[7:-7, 2, 3], atol=1e-5, rtol=0)  # a ramp stays
    assert (sq[:, 1, 1:] == 0).all() and (sq[:, 2, :3] == 0).all()  # nothing leaks across
    assert sr[5:-5].sub(0.5).abs().max() < 0.05
    rq, rr = smooth_decoded(q.reshape(-1, 6), r, 0.0, root_sigma=2.0)  # the root alone
    assert torch.equal(rq, q.reshape(-1, 6)) and torch.equal(rr, sr)
    bq, br = smooth_decoded(q.reshape(-1, 6), r, 2.0, root_sigma=0.0)  # all but the root
    assert torch.equal(bq, sq.reshape(-1, 6)) and torch.equal(br, r)


def test_settings_generate_in_the_window_the_model_was_trained_on_unless_told():
    """``window=None`` reads the generator's training window
    (``meta["window"]``, none where it is not recorded), 0 means whole
    clips, seconds are frames at the model's rate; the residual layers take
    their own window where one is set, else the same."""
    from types import SimpleNamespace
    module = SimpleNamespace(fps=30.0, meta={"window": 120})
    assert GenerationSettings().window_frames(module) == 120
    assert GenerationSettings().residual_frames(module) == 120
    assert GenerationSettings(window=0.0).window_frames(module) is None
    assert GenerationSettings(window=0.0).residual_frames(module) is None
    assert GenerationSettings(window=2.5).window_frames(module) == 75
    assert GenerationSettings(residual_window=2.0).residual_frames(module) == 60
    assert GenerationSettings().window_frames(SimpleNamespace(fps=30.0, meta={})) is None


def test_the_masked_transformer_draws_among_candidates_the_residual_one_from_guided_logits(
        t2m_ckpt, zoo_skeletons, monkeypatch):
    """By default the masked transformer draws among candidates and the
    residual one from its guided logits (``experiments/T2M.md`` section
    66); ``residual_guide=None`` follows ``guide``; the residual draw
    changes only the residual layers (the same layer-0 codes)."""
    from satagraph.pipelines import generate as G
    module, target, seen = _decoded_codes(t2m_ckpt, zoo_skeletons, monkeypatch)
    guides = []
    for part in ("masked", "residual"):
        real = getattr(module, part).generate
        monkeypatch.setattr(getattr(module, part), "generate", lambda *a, _p=part, _r=real, **k: (
            guides.append((_p, k.get("guide", a[-2] if _p == "residual" else None))),
            _r(*a, **k))[1])
    cases = (G.GenerationSettings(), G.GenerationSettings(guide="logits"),
             G.GenerationSettings(residual_guide=None))
    for settings in cases:
        G.generate_on(module, TEXT, target, 1.0, 0, settings)
    assert guides == [("masked", "candidates"), ("residual", "logits"),
                      ("masked", "logits"), ("residual", "logits"),
                      ("masked", "candidates"), ("residual", "candidates")]
    assert [s.residual_draw for s in cases] == ["logits", "logits", "candidates"]
    assert torch.equal(seen[0][:, 0], seen[2][:, 0])


def test_rerank_keeps_the_draw_the_text_explains_best(t2m_ckpt, zoo_skeletons, monkeypatch):
    """``GenerationSettings.rerank``: that many layer-0 draws in one batch,
    the one of the highest ``text_score`` decoded; one draw (the default)
    never scores and gives what it gave before; without a text there is
    nothing to rank by."""
    from satagraph.pipelines import generate as G
    module, target, seen = _decoded_codes(t2m_ckpt, zoo_skeletons, monkeypatch)
    drawn, scores = [], []
    real_generate, real_score = module.masked.generate, module.masked.text_score
    monkeypatch.setattr(module.masked, "generate",
                        lambda *a, **k: (drawn.append(real_generate(*a, **k)), drawn[-1])[1])

    def score(codes, *a, **k):
        scores.append(real_score(codes, *a, **k))
        return scores[-1]
    monkeypatch.setattr(module.masked, "text_score", score)
    G.generate_on(module, TEXT, target, 1.0, 0)
    G.generate_on(module, TEXT, target, 1.0, 0, G.GenerationSettings(rerank=1))
    assert not scores and torch.equal(seen[0], seen[1])
    G.generate_on(module, TEXT, target, 1.0, 0, G.GenerationSettings(rerank=4))
    assert drawn[2].size(0) == 4 and len(scores) == 1
    best = int(scores[0].argmax())
    assert len({tuple(row.tolist()) for row in drawn[2]}) > 1
    assert torch.equal(seen[2][:, 0], drawn[2][best, :seen[2].size(0)])
    G.generate_on(module, None, target, 1.0, 0, G.GenerationSettings(rerank=4))
    assert drawn[3].size(0) == 1 and len(scores) == 1


def test_a_rig_s_inputs_made_once_generate_what_its_motion_generates(t2m_ckpt, zoo_skeletons):
    """``generate --prompts`` makes each skeleton's :func:`rig_inputs` once
    for every prompt: what
    ``generate_on`` gives from them is what it gives from the motion."""
    from satagraph.pipelines import generate as G
    module = G.load_generator(str(t2m_ckpt))
    target = read_bvh(str(zoo_skeletons["quadruped"]))
    settings = GenerationSettings()
    rig = G.rig_inputs(module, target, settings.rest)
    for seed in (0, 1):
        alone = G.generate_on(module, TEXT, target, 1.0, seed, settings)
        kept = G.generate_on(module, TEXT, rig, 1.0, seed, settings)
        np.testing.assert_array_equal(kept.rotations, alone.rotations)
        np.testing.assert_array_equal(kept.translations, alone.translations)


def test_a_failed_set_keeps_what_another_run_wrote_since(tiny_motion, random_motion, tmp_path,
                                                         monkeypatch):
    """A generate whose second file failed removed its first, even where
    another run (the same OUT) had written that file since: it removes its
    own files alone."""
    import satagraph.io
    from satagraph.pipelines.generate import write_all
    first, second = str(tmp_path / "a.bvh"), str(tmp_path / "b.bvh")
    write = satagraph.io.write_bvh
    other = random_motion(tiny_motion.skeleton, num_frames=5, seed=1)

    def another_run_meanwhile(motion, path, *args, **kwargs):
        if path == second:
            write(other, first)  # the other run's file, written over this one's
            raise OSError(28, "No space left on device", second)
        write(motion, path, *args, **kwargs)
    monkeypatch.setattr(satagraph.io, "write_bvh", another_run_meanwhile)
    with pytest.raises(OSError, match="No space left"):
        write_all([tiny_motion, tiny_motion], [first, second])
    assert read_bvh(first).num_frames == 5 and not Path(second).exists()
    with pytest.raises(OSError, match="No space left"):  # nobody else wrote: no partial set
        write_all([tiny_motion, tiny_motion], [str(tmp_path / "c.bvh"), second])
    assert not (tmp_path / "c.bvh").exists()


def test_raw_decoding_is_the_decoder_s_own_carriage(t2m_ckpt, zoo_skeletons):
    """:data:`RAW_DECODING` (``decode_on``'s default) decodes codes as the
    decoder gives them: not carried as the skeleton file's character, which
    ``carriage="always"`` would do (every joint turned to the clip's mean)."""
    from dataclasses import replace
    from satagraph.pipelines import generate as G
    module = G.load_generator(str(t2m_ckpt))
    rig = G.rig_inputs(module, read_bvh(str(zoo_skeletons["quadruped"])))
    codes = torch.randint(0, 16, (20, module.num_quantizers),
                          generator=torch.Generator().manual_seed(0))
    raw = G.decode_on(module, codes, rig)
    decoded = {mode: G.decode_on(module, codes, rig, replace(G.RAW_DECODING, carriage=mode))
               for mode in ("never", "always")}
    np.testing.assert_array_equal(raw.rotations, decoded["never"].rotations)
    assert np.abs(raw.rotations - decoded["always"].rotations).max() > 1e-3


def test_the_carriage_gate_in_decode_on(t2m_ckpt, zoo_skeletons, monkeypatch):
    """With ``lands`` stubbed to 0.0, generation's default settings carry
    the motion as ``always`` does and :data:`RAW_DECODING` as ``never``;
    the gate reads the motion as ``ground`` puts it on the floor, and
    where it keeps it (``lands`` 1.0) that reading is the output, not put
    on the floor again; the rig's carriage is computed once for all."""
    from dataclasses import replace
    from satagraph.pipelines import generate as G
    from satagraph.pipelines import inference
    module = G.load_generator(str(t2m_ckpt))
    rig = G.rig_inputs(module, read_bvh(str(zoo_skeletons["quadruped"])))
    codes = torch.randint(0, 16, (20, module.num_quantizers),
                          generator=torch.Generator().manual_seed(0))
    landing, seen, calls = [0.0], [], Counter()
    monkeypatch.setattr(inference, "lands_against",
                        lambda motion, own: seen.append(motion) or landing[0])
    mean_carriage, on_floor = inference.mean_carriage, G._on_floor
    monkeypatch.setattr(inference, "mean_carriage",
                        lambda m: calls.update(["carriage"]) or mean_carriage(m))
    monkeypatch.setattr(G, "_on_floor", lambda m: calls.update(["floor"]) or on_floor(m))
    default = G.GenerationSettings(smooth=0.0, root_smooth=0.0, ground=False, plant=False)
    always = G.decode_on(module, codes, rig, replace(G.RAW_DECODING, carriage="always"))
    never = G.decode_on(module, codes, rig, replace(G.RAW_DECODING, carriage="never"))
    np.testing.assert_array_equal(G.decode_on(module, codes, rig, default).rotations,
                                  always.rotations)
    np.testing.assert_array_equal(G.decode_on(module, codes, rig).rotations, never.rotations)
    assert calls == {"carriage": 1, "floor": 1}  # the default's gate, on the floor
    landing[0], seen[:] = 1.0, []
    G.decode_on(module, codes, rig, replace(G.RAW_DECODING, carriage="auto", ground=True))
    assert calls == {"carriage": 1, "floor": 2} and len(seen) == 1
    lowest = seen[0].global_positions()[..., 1].min(axis=1)
    assert abs(lowest.min()) < 1e-9  # on the floor, none of its frames under it
