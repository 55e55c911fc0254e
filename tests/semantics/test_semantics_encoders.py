"""Semantic tags: text encoders (offline and a tiny local T5), embedding cache
and X_t of skeletons."""
from __future__ import annotations

import json
import multiprocessing
import os
import subprocess
import sys
import warnings
from pathlib import Path
from typing import List, Sequence

import numpy as np
import pytest
import torch

from satagraph import Skeleton
from satagraph.semantics import (EmbeddingCache, OfflineTextEncoder,
                                 T5TextEncoder, TextEncoder, clear_memory,
                                 default_cache_dir, describe_joints,
                                 embed_skeleton, embed_texts)
from satagraph.semantics import cache as cache_mod
from satagraph.semantics.cache import cache_file
from satagraph.utils.cache import ENV_VAR

REPO_ROOT = Path(__file__).resolve().parents[2]


def cos(a: torch.Tensor, b: torch.Tensor) -> float:
    return float(torch.nn.functional.cosine_similarity(a, b, dim=0))


class CountingEncoder(TextEncoder):
    """Offline encoder that counts the texts it is asked to encode."""

    def __init__(self) -> None:
        self.inner = OfflineTextEncoder(32)
        self.calls: List[List[str]] = []

    @property
    def id(self) -> str:
        return "counting-test-encoder"

    @property
    def out_channels(self) -> int:
        return 32

    def encode(self, texts: Sequence[str]) -> torch.Tensor:
        self.calls.append(list(texts))
        return self.inner.encode(texts)


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path, monkeypatch):
    """No test writes to the user's real cache."""
    monkeypatch.setenv(ENV_VAR, str(tmp_path / "default-cache"))
    clear_memory()
    yield
    clear_memory()


def skel(names: List[str], parents: List[int]) -> Skeleton:
    return Skeleton(names=names, parents=np.array(parents),
                    offsets=np.zeros((len(names), 3)))


# ---------------------------------------------------------------- offline
def test_offline_shape_norm_and_identity():
    enc = OfflineTextEncoder()
    assert enc.out_channels == 256 and enc.id.startswith("offline")
    x = enc.encode(["left hind limb upper segment (thigh)", "tail tip",
                    "left hind limb upper segment (thigh)", ""])
    assert x.shape == (4, 256) and x.dtype == torch.float32
    assert torch.allclose(x[:3].norm(dim=1), torch.ones(3), atol=1e-6)
    assert torch.equal(x[0], x[2])
    assert torch.equal(x[3], torch.zeros(256))  # empty text: zeros, no NaN
    assert OfflineTextEncoder(64).encode(["a b"]).shape == (1, 64)
    assert OfflineTextEncoder(64).id != enc.id
    with pytest.raises(ValueError):
        OfflineTextEncoder(0)


@pytest.mark.slow
def test_offline_is_deterministic_across_processes():
    text = "left hind limb upper segment (thigh)"
    here = OfflineTextEncoder().encode([text])[0]
    # A fresh interpreter with another hash seed, loading only the module.
    code = ("import importlib.util, sys;"
            "spec = importlib.util.spec_from_file_location('enc', sys.argv[1]);"
            "mod = importlib.util.module_from_spec(spec);"
            "spec.loader.exec_module(mod);"
            f"print(mod.OfflineTextEncoder().encode([{text!r}])[0].tolist())")
    module = REPO_ROOT / "satagraph" / "semantics" / "encoders.py"
    env = dict(os.environ, PYTHONHASHSEED="12345")
    out = subprocess.run([sys.executable, "-c", code, str(module)], env=env,
                         check=True, capture_output=True, text=True)
    assert torch.equal(torch.tensor(json.loads(out.stdout)), here)
    # Golden values: the same on every machine (BLAKE2b, no salted hash()).
    golden = {0: 0.469248, 3: 0.469248, 6: 0.39104, 189: 0.329446}
    for index, value in golden.items():
        assert here[index].item() == pytest.approx(value, abs=1e-5)


def test_offline_shared_words_are_closer():
    enc = OfflineTextEncoder()
    a, b, c, d = enc.encode([
        "left hind limb upper segment (thigh)",
        "left hind limb upper segment",
        "head top tip",
        "right front limb lower segment (forearm)"])
    assert cos(a, b) > 0.8
    assert cos(a, b) > cos(a, d) > cos(a, c)
    assert cos(a, c) < 0.2


def test_offline_functional_words_dominate():
    enc = OfflineTextEncoder()
    texts = ["left front limb terminal segment (hand / front paw)",
             "right front limb terminal segment (hand / front paw)",
             "left hind limb terminal segment (foot / hind paw)",
             "left front limb upper segment (upper arm)",
             "spine segment (back)", "tail segment"]
    emb = enc.encode(texts)
    for query, want in [("left hind paw", 2), ("right front paw", 1),
                        ("Left Upper Arm", 3), ("back", 4), ("tail base", 5),
                        ("left hand", 0)]:
        sims = emb @ enc.encode([query])[0]
        assert int(sims.argmax()) == want, query


# ------------------------------------------------------------------ cache
def test_cache_hit_does_not_call_encoder(tmp_path):
    enc = CountingEncoder()
    texts = ["a b", "c d", "a b"]
    first = embed_texts(texts, enc, tmp_path)
    assert enc.calls == [["a b", "c d"]]
    assert cache_file(tmp_path, enc.id).is_file()
    second = embed_texts(texts, enc, tmp_path)
    assert len(enc.calls) == 1 and torch.equal(first, second)
    clear_memory()  # a new process: read from disk
    third = embed_texts(["c d", "e f"], enc, tmp_path)
    assert enc.calls[1:] == [["e f"]]
    assert torch.equal(third[0], first[1])
    assert torch.equal(embed_texts([], enc, tmp_path), torch.zeros(0, 32))
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_cache_default_dir_and_env(tmp_path, monkeypatch):
    monkeypatch.setenv(ENV_VAR, str(tmp_path / "envcache"))
    assert default_cache_dir() == tmp_path / "envcache"
    enc = CountingEncoder()
    embed_texts(["x"], enc)
    assert cache_file(tmp_path / "envcache", enc.id).is_file()
    monkeypatch.delenv(ENV_VAR)
    assert default_cache_dir() == Path.home() / ".cache" / "satagraph" / \
        "embeddings"


@pytest.mark.parametrize("garbage", [b"not a torch file", b""])
def test_corrupt_cache_is_rebuilt_with_warning(tmp_path, garbage):
    enc = CountingEncoder()
    path = cache_file(tmp_path, enc.id)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(garbage)
    with pytest.warns(RuntimeWarning, match="unreadable embedding cache"):
        out = embed_texts(["a", "b"], enc, tmp_path)
    assert out.shape == (2, 32) and enc.calls == [["a", "b"]]
    clear_memory()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = embed_texts(["a", "b"], enc, tmp_path)  # rebuilt file is fine
    assert torch.equal(out, again) and len(enc.calls) == 1


def test_malformed_cache_content_is_rebuilt(tmp_path):
    enc = CountingEncoder()
    path = cache_file(tmp_path, enc.id)
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save({"format": "satagraph-embeddings", "encoder_id": enc.id,
                "texts": ["a"], "embeddings": torch.zeros(2, 5)}, path)
    with pytest.warns(RuntimeWarning):
        embed_texts(["a"], enc, tmp_path)
    assert enc.calls == [["a"]]


def test_unwritable_cache_only_warns(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    enc = CountingEncoder()
    with pytest.warns(RuntimeWarning, match="cannot write"):
        out = embed_texts(["a"], enc, blocker / "cache")
    assert out.shape == (1, 32)


def test_cache_merges_concurrent_writers(tmp_path):
    a, b = CountingEncoder(), CountingEncoder()
    EmbeddingCache(tmp_path).embed(a, ["one"])
    clear_memory()
    EmbeddingCache(tmp_path).embed(b, ["two"])  # another "process"
    clear_memory()
    c = CountingEncoder()
    EmbeddingCache(tmp_path).embed(c, ["one", "two"])
    assert c.calls == []



def _embed_in_a_fresh_process(folder: Path, texts: List[str]) -> None:
    clear_memory()
    EmbeddingCache(folder).embed(CountingEncoder(), texts)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="forks the other writer")
def test_a_write_between_a_merge_and_its_write_is_kept(tmp_path, monkeypatch):
    """Another process that wrote between a process's merge and its write
    was replaced, its rows lost (two processes adding 200 texts each kept
    230 of the 400); the merge and the write hold the lock file."""
    saved, others = cache_mod.save_checkpoint, []

    def another_writes_meanwhile(payload, path):
        if not others:  # once, and not in the other process
            others.append(multiprocessing.get_context("fork").Process(
                target=_embed_in_a_fresh_process, args=(tmp_path, ["two"])))
            others[0].start()
            others[0].join(timeout=0.5)  # it ends at once unless it waits for the lock
        saved(payload, path)
    monkeypatch.setattr(cache_mod, "save_checkpoint", another_writes_meanwhile)
    EmbeddingCache(tmp_path).embed(CountingEncoder(), ["one"])
    others[0].join(timeout=30.0)
    assert others[0].exitcode == 0
    clear_memory()
    c = CountingEncoder()
    EmbeddingCache(tmp_path).embed(c, ["one", "two"])
    assert c.calls == []
    assert [p.name for p in tmp_path.iterdir()] == [cache_file(tmp_path, c.id).name]

# -------------------------------------------------------------- skeletons
def test_embed_skeleton_rows_follow_descriptions(tmp_path):
    sk = skel(["Hips", "LeftUpLeg", "RightUpLeg", "Spine", "Spine1"],
              [-1, 0, 0, 0, 3])
    x = embed_skeleton(sk, cache_dir=tmp_path)
    assert x.shape == (5, 256) and x.dtype == torch.float32
    assert torch.equal(x[3], x[4])  # Spine == Spine1 (numeric invariance)
    assert not torch.equal(x[1], x[2])  # left != right
    assert cos(x[1], x[2]) > cos(x[1], x[3])
    y = embed_skeleton(sk, cache_dir=tmp_path, anchors=["Spine1=chest"],
                       dictionary={"Hips": "centre of mass"})
    assert torch.equal(y[4], embed_texts(["chest"], cache_dir=tmp_path)[0])
    assert torch.equal(y[0], embed_texts(["centre of mass"],
                                         cache_dir=tmp_path)[0])
    z = embed_skeleton(sk, use_cache=False)
    assert torch.allclose(x, z)


def test_embed_skeleton_uses_cache(tmp_path):
    sk = skel(["Hips", "Spine", "Head"], [-1, 0, 1])
    enc = CountingEncoder()
    embed_skeleton(sk, encoder=enc, cache_dir=tmp_path)
    embed_skeleton(sk, encoder=enc, cache_dir=tmp_path)
    assert len(enc.calls) == 1 and len(enc.calls[0]) == 3


# --------------------------------------------------------------------- T5
@pytest.fixture(scope="module")
def tiny_t5(tmp_path_factory) -> Path:
    """A random 1-layer T5 (d_model 16) and a word-level tokenizer built
    here, saved like a downloaded checkpoint."""
    transformers = pytest.importorskip("transformers")
    tokenizers = pytest.importorskip("tokenizers")
    from tokenizers import models, pre_tokenizers, processors

    folder = tmp_path_factory.mktemp("tiny_t5")
    words = ("left right front hind limb upper lower segment terminal digit "
             "tip spine neck head pelvis tail thigh hand foot").split()
    vocab = {"<pad>": 0, "</s>": 1, "<unk>": 2,
             **{w: i + 3 for i, w in enumerate(words)}}
    tok = tokenizers.Tokenizer(models.WordLevel(vocab, unk_token="<unk>"))
    tok.pre_tokenizer = pre_tokenizers.Whitespace()
    tok.post_processor = processors.TemplateProcessing(
        single="$A </s>", special_tokens=[("</s>", 1)])
    transformers.PreTrainedTokenizerFast(
        tokenizer_object=tok, pad_token="<pad>", eos_token="</s>",
        unk_token="<unk>").save_pretrained(folder)
    torch.manual_seed(0)
    config = transformers.T5Config(
        vocab_size=len(vocab), d_model=16, d_kv=4, d_ff=32, num_layers=1,
        num_heads=2, pad_token_id=0, eos_token_id=1,
        decoder_start_token_id=0)
    transformers.T5EncoderModel(config).save_pretrained(folder)
    return folder


def test_t5_encoder_loads_and_pools(tiny_t5):
    enc = T5TextEncoder(tiny_t5, device="cpu", batch_size=2)
    assert enc.out_channels == 16 and enc.id.startswith("t5:")
    texts = ["left hind limb upper segment", "tail tip",
             "left hind limb upper segment", "spine segment (back) neck",
             "head"]
    x = enc.encode(texts)
    assert x.shape == (5, 16) and x.dtype == torch.float32
    assert torch.isfinite(x).all()
    assert torch.equal(x[0], x[2])
    # batching and padding do not change a text's vector
    single = torch.cat([enc.encode([t]) for t in texts])
    assert torch.allclose(single, x, atol=1e-5)
    assert enc.encode([]).shape == (0, 16)
    model = enc._model
    assert not model.training
    assert not any(p.requires_grad for p in model.parameters())


def test_t5_id_is_stable_and_tracks_the_checkpoint(tiny_t5, tmp_path):
    assert T5TextEncoder(tiny_t5).id == T5TextEncoder(tiny_t5).id
    other = tmp_path / tiny_t5.name
    other.mkdir()
    for item in tiny_t5.iterdir():
        (other / item.name).write_bytes(item.read_bytes())
    config = json.loads((other / "config.json").read_text())
    config["d_ff"] = 64
    (other / "config.json").write_text(json.dumps(config))
    assert T5TextEncoder(other).id != T5TextEncoder(tiny_t5).id


def test_t5_warm_cache_never_loads_the_model(tiny_t5, tmp_path):
    sk = skel(["Hips", "LeftUpLeg", "LeftLeg"], [-1, 0, 1])
    first = embed_skeleton(sk, T5TextEncoder(tiny_t5), cache_dir=tmp_path)
    assert first.shape == (3, 16)
    clear_memory()
    enc = T5TextEncoder(tiny_t5)
    second = embed_skeleton(sk, enc, cache_dir=tmp_path)
    assert enc._model is None and torch.equal(first, second)


def test_t5_missing_path_explains_how_to_provide_one(tmp_path):
    with pytest.raises(FileNotFoundError) as err:
        T5TextEncoder(tmp_path / "no-such-model")
    msg = str(err.value)
    assert "no-such-model" in msg and "never downloads" in msg
    assert "pass" in msg
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError, match="config.json"):
        T5TextEncoder(tmp_path / "empty")


def test_t5_broken_folder_gives_clear_error(tmp_path):
    folder = tmp_path / "broken"
    folder.mkdir()
    (folder / "config.json").write_text(json.dumps({"model_type": "t5",
                                                    "d_model": 8}))
    enc = T5TextEncoder(folder)
    with pytest.raises(FileNotFoundError, match="cannot load"):
        enc.encode(["x"])


def test_descriptions_feed_t5_and_offline_alike(tiny_t5):
    sk = skel(["Hips", "Spine", "Neck", "Head"], [-1, 0, 1, 2])
    texts = describe_joints(sk)
    t5 = T5TextEncoder(tiny_t5).encode(texts)
    off = OfflineTextEncoder().encode(texts)
    assert t5.shape[0] == off.shape[0] == 4
