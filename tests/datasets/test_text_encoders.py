"""Caption encoders: a tiny local sentence-transformers BERT, word vectors
from a file, the factory of specs and the checkpoint check."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from satagraph.semantics import (GloVeEncoder, OfflineTextEncoder, SentenceEncoder,
                                 T5TextEncoder, TextEncoderMismatch,
                                 build_text_encoder, check_text_encoder,
                                 check_text_encoder_state, text_encoder_state)
from satagraph.datasets import captions_for

WORDS = ("a person walks runs forward backward slowly angrily left right turns jumps "
         "crab stands still").split()


def cos(a: torch.Tensor, b: torch.Tensor) -> float:
    return float(torch.nn.functional.cosine_similarity(a, b, dim=0))


# ---------------------------------------------------------------- offline
def test_offline_similar_captions_are_closer():
    enc = build_text_encoder("offline")
    texts = [c.text for c in captions_for("dataset-1_walk_angry_001.bvh")]
    assert texts[:3] == ["a person walks forward angrily", "someone walks forward angrily",
                         "a person walks forward in an angry manner"]
    x = enc.encode([texts[0], texts[2], "a crab stands still, swaying gently",
                    captions_for("dataset-1_bow_happy_001.bvh")[0].text])
    assert cos(x[0], x[1]) > cos(x[0], x[3]) > cos(x[0], x[2])
    assert torch.equal(enc.encode([texts[0]]), build_text_encoder("offline").encode(
        [texts[0]]))


# --------------------------------------------------------------- sentence
@pytest.fixture(scope="module")
def tiny_minilm(tmp_path_factory) -> Path:
    """A random 1-layer BERT (hidden 16) with a word-level tokenizer, laid
    out like a sentence-transformers folder (modules.json, 1_Pooling)."""
    transformers = pytest.importorskip("transformers")
    tokenizers = pytest.importorskip("tokenizers")
    from tokenizers import models, pre_tokenizers, processors

    folder = tmp_path_factory.mktemp("tiny_minilm")
    vocab = {"[PAD]": 0, "[UNK]": 1, "[CLS]": 2, "[SEP]": 3,
             **{w: i + 4 for i, w in enumerate(WORDS)}}
    tok = tokenizers.Tokenizer(models.WordLevel(vocab, unk_token="[UNK]"))
    tok.pre_tokenizer = pre_tokenizers.Whitespace()
    tok.post_processor = processors.TemplateProcessing(
        single="[CLS] $A [SEP]", special_tokens=[("[CLS]", 2), ("[SEP]", 3)])
    transformers.PreTrainedTokenizerFast(
        tokenizer_object=tok, pad_token="[PAD]", unk_token="[UNK]",
        cls_token="[CLS]", sep_token="[SEP]").save_pretrained(folder)
    torch.manual_seed(0)
    config = transformers.BertConfig(
        vocab_size=len(vocab), hidden_size=16, num_hidden_layers=1,
        num_attention_heads=2, intermediate_size=32, max_position_embeddings=64)
    transformers.BertModel(config).save_pretrained(folder)
    (folder / "modules.json").write_text(json.dumps([
        {"idx": 0, "name": "0", "path": "",
         "type": "sentence_transformers.models.Transformer"},
        {"idx": 1, "name": "1", "path": "1_Pooling",
         "type": "sentence_transformers.models.Pooling"}]))
    (folder / "1_Pooling").mkdir()
    (folder / "1_Pooling" / "config.json").write_text(json.dumps(
        {"word_embedding_dimension": 16, "pooling_mode_cls_token": False,
         "pooling_mode_mean_tokens": True}))
    return folder


def test_sentence_encoder_pools_and_normalises(tiny_minilm):
    enc = build_text_encoder(f"minilm:{tiny_minilm}")
    assert isinstance(enc, SentenceEncoder) and enc.out_channels == 16
    assert enc.id.startswith(f"sentence:{tiny_minilm.name}:")
    texts = ["a person walks forward", "a crab stands still", "a person walks forward",
             "person turns left slowly", "jumps"]
    x = SentenceEncoder(tiny_minilm, device="cpu", batch_size=2).encode(texts)
    assert x.shape == (5, 16) and x.dtype == torch.float32
    assert torch.allclose(x.norm(dim=1), torch.ones(5), atol=1e-5)
    assert torch.equal(x[0], x[2])
    single = torch.cat([enc.encode([t]) for t in texts])
    assert torch.allclose(single, x, atol=1e-5)  # padding does not matter
    again = SentenceEncoder(f"{tiny_minilm}", device="cpu").encode(texts)
    assert torch.allclose(again, x, atol=1e-6)  # deterministic
    # The pooled vector is the mean of the model's token states, normalised.
    from transformers import AutoModel, AutoTokenizer
    tokenizer = AutoTokenizer.from_pretrained(str(tiny_minilm), local_files_only=True)
    model = AutoModel.from_pretrained(str(tiny_minilm), local_files_only=True).eval()
    with torch.no_grad():
        hidden = model(**tokenizer(["jumps"], return_tensors="pt")).last_hidden_state
    want = torch.nn.functional.normalize(hidden[0].mean(0), dim=0)
    assert torch.allclose(x[4], want, atol=1e-5)
    assert enc.encode([]).shape == (0, 16)
    assert not enc._model.training
    assert not any(p.requires_grad for p in enc._model.parameters())


@pytest.mark.parametrize("encoder, config", [
    (T5TextEncoder, {"model_type": "t5", "d_model": 8}),
    (SentenceEncoder, {"model_type": "bert", "hidden_size": 8})])
def test_both_encoders_say_the_first_line_of_a_load_error(tmp_path, monkeypatch, encoder,
                                                           config):
    """transformers' load errors run over several lines: the T5 encoder
    carried them whole, the sentence encoder their first line."""
    transformers = pytest.importorskip("transformers")

    def refuse(*args, **kwargs):
        raise OSError("Can't load tokenizer for 'x'.\nIf you were trying to load it from "
                      "'https://huggingface.co/models', make sure ...\nOtherwise, ...")
    monkeypatch.setattr(transformers.AutoTokenizer, "from_pretrained", refuse)
    (tmp_path / "config.json").write_text(json.dumps(config))
    with pytest.raises(FileNotFoundError) as err:
        encoder(tmp_path).load()
    assert str(err.value).startswith(f"{encoder.__name__}: cannot load a ")
    assert f"{tmp_path}: Can't load tokenizer for 'x'. satagraph never downloads" in str(
        err.value) and "\n" not in str(err.value)


def test_sentence_encoder_errors_name_the_path(tiny_minilm, tmp_path):
    with pytest.raises(FileNotFoundError) as err:
        build_text_encoder(f"sentence:{tmp_path / 'no-such-model'}")
    message = str(err.value)
    assert "no-such-model" in message and "never downloads" in message
    assert "\n" not in message
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError, match="is not a model folder.*config.json"):
        SentenceEncoder(tmp_path / "empty")
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "config.json").write_text(json.dumps({"model_type": "bert",
                                                   "hidden_size": 8}))
    with pytest.raises(FileNotFoundError, match="cannot load") as err:
        SentenceEncoder(broken).encode(["x"])
    assert "broken" in str(err.value) and "\n" not in str(err.value)
    cls = tmp_path / "cls"
    cls.mkdir()
    for item in tiny_minilm.iterdir():
        if item.is_file():
            (cls / item.name).write_bytes(item.read_bytes())
    (cls / "1_Pooling").mkdir()
    (cls / "1_Pooling" / "config.json").write_text(json.dumps(
        {"pooling_mode_cls_token": True, "pooling_mode_mean_tokens": False}))
    with pytest.raises(ValueError, match="only mean pooling"):
        SentenceEncoder(cls)


# ------------------------------------------------------------------ GloVe
VECTORS = {"person": [1, 0, 0, 0], "walks": [0, 1, 0, 0], "runs": [0, 0.8, 0.6, 0],
           "crab": [0, 0, 0, 1], "not": [1, 1, 0, 0], "confident": [0, 0, 1, 1],
           "left": [0.5, 0, 0, 0.5]}


@pytest.fixture
def glove_file(tmp_path) -> Path:
    path = tmp_path / "vectors.4d.txt"
    path.write_text("".join(f"{w} {' '.join(str(v) for v in vec)}\n"
                            for w, vec in VECTORS.items()))
    return path


def test_glove_means_known_words(glove_file):
    enc = build_text_encoder(f"glove:{glove_file}")
    assert isinstance(enc, GloVeEncoder) and enc.out_channels == 4
    assert enc.vocabulary_size == len(VECTORS)
    x = enc.encode(["A person walks.", "person", "walks person", "zebra qux", "",
                    "not-confident", "crab runs"])
    assert x.shape == (7, 4) and x.dtype == torch.float32
    s = float(np.sqrt(0.5))
    assert torch.allclose(x[0], torch.tensor([s, s, 0, 0]))  # "a" unknown: skipped
    assert torch.allclose(x[1], torch.tensor([1.0, 0, 0, 0]))
    assert torch.equal(x[0], x[2])  # a bag of words
    assert torch.equal(x[3], torch.zeros(4)) and torch.equal(x[4], torch.zeros(4))
    assert torch.allclose(x[5], torch.full((4,), 0.5))  # split into known parts
    assert enc.words("the Crab, runs LEFT!") == ["crab", "runs", "left"]
    raw = GloVeEncoder(glove_file, normalize=False).encode(["person walks"])
    assert torch.allclose(raw[0], torch.tensor([0.5, 0.5, 0, 0]))
    assert raw.shape == (1, 4) and GloVeEncoder(glove_file, normalize=False).id != enc.id


def test_glove_id_tracks_the_file_and_header_is_skipped(glove_file, tmp_path):
    enc = GloVeEncoder(glove_file)
    assert enc.id == GloVeEncoder(glove_file).id and enc.id.startswith("glove:")
    assert enc.id.endswith(":d4")
    other = tmp_path / glove_file.name
    other.write_text(glove_file.read_text().replace("crab 0 0 0 1", "crab 0 0 1 0"))
    assert GloVeEncoder(other).id != enc.id
    w2v = tmp_path / "w2v.txt"
    w2v.write_text(f"{len(VECTORS)} 4\n" + glove_file.read_text())
    assert torch.equal(GloVeEncoder(w2v).encode(["crab walks"]),
                       enc.encode(["crab walks"]))


def test_glove_errors_name_file_and_line(tmp_path):
    with pytest.raises(FileNotFoundError, match="no word-vector file.*missing.txt"):
        build_text_encoder(f"glove:{tmp_path / 'missing.txt'}")
    bad = tmp_path / "bad.txt"
    bad.write_text("a 1 2 3\nb 1 2\n")
    with pytest.raises(ValueError, match=r"bad\.txt:2: expected a word and 3 numbers"):
        GloVeEncoder(bad).encode(["a"])
    bad.write_text("a 1 2 3\nb 1 x 3\n")
    with pytest.raises(ValueError, match=r"bad\.txt:2: the values of 'b'"):
        GloVeEncoder(bad).encode(["a"])
    bad.write_text("\n\n")
    with pytest.raises(ValueError, match="no word vectors"):
        GloVeEncoder(bad)


# -------------------------------------------------- factory and checkpoints
def test_factory_specs(tmp_path):
    assert build_text_encoder("offline").id == OfflineTextEncoder().id
    assert build_text_encoder("offline:64").out_channels == 64
    enc = OfflineTextEncoder(32)
    assert build_text_encoder(enc) is enc
    with pytest.raises(FileNotFoundError, match="no T5 model"):
        build_text_encoder(f"t5:{tmp_path / 'nothing'}")
    for spec in ("clip:/x", "offline:big", "glove:", "minilm", "bert:/x"):
        with pytest.raises(ValueError, match="text encoder"):
            build_text_encoder(spec)


def test_factory_builds_t5(tmp_path):
    folder = tmp_path / "t5"
    folder.mkdir()
    (folder / "config.json").write_text(json.dumps({"model_type": "t5", "d_model": 8}))
    assert isinstance(build_text_encoder(f"t5:{folder}"), T5TextEncoder)


def test_check_text_encoder(glove_file):
    glove = GloVeEncoder(glove_file)
    state = text_encoder_state(glove)
    assert state == {"id": glove.id, "width": 4}
    check_text_encoder(state["id"], state["width"], GloVeEncoder(glove_file))
    check_text_encoder_state(state, glove)
    with pytest.raises(TextEncoderMismatch, match="width mismatch.*4-D.*256-D"):
        check_text_encoder(glove.id, 4, OfflineTextEncoder())
    with pytest.raises(TextEncoderMismatch, match="mismatch.*offline-hash-v1-d4"):
        check_text_encoder(glove.id, 4, OfflineTextEncoder(4))
    offline = OfflineTextEncoder()
    check_text_encoder_state(text_encoder_state(offline), build_text_encoder("offline"))


def test_an_encoder_of_one_s_own_is_a_spec_once_registered(monkeypatch):
    """A text encoder of one's own (``encode(list[str]) -> [N, D]`` and an
    id) had no hook: only writing into the factory's private table made
    ``model.text_encoder: bag:v1`` a spec, and the refusal named the
    built-in specs alone."""
    from satagraph.semantics import TextEncoder, register_text_encoder
    from satagraph.semantics import factory
    monkeypatch.setattr(factory, "TEXT_ENCODERS", dict(factory.TEXT_ENCODERS))

    class Bag(TextEncoder):
        def __init__(self, arg: str) -> None:
            self._id, self._dim = f"bag:{arg}", 5

        def encode(self, texts):
            return torch.tensor([[float(len(t.split()))] * 5 for t in texts])

    with pytest.raises(ValueError, match=r"unknown text encoder 'bag_t:v1'.*"
                       "register_text_encoder adds one"):
        build_text_encoder("bag_t:v1")
    register_text_encoder("bag_t", Bag)
    enc = build_text_encoder("bag_t:v1")
    assert isinstance(enc, Bag) and enc.id == "bag:v1"
    assert enc.encode(["a person walks", "a dog"])[:, 0].tolist() == [3.0, 2.0]
    check_text_encoder_state(text_encoder_state(enc), build_text_encoder("bag_t:v1"))
    with pytest.raises(ValueError, match="registered: 'bag_t:ARG'"):
        build_text_encoder("clip:/x")
    for taken in ("bag_t", "glove", "offline", "a:b", " "):
        with pytest.raises(ValueError, match="text encoder"):
            register_text_encoder(taken, Bag)


def test_an_encoder_registered_in_a_plugin_is_found_from_python(tmp_path, monkeypatch):
    """``bag:v1`` in a config (``data.semantic_encoder``, a checkpoint's)
    was unknown from Python until the code registering it was imported by
    hand, though ``SATAGRAPH_PLUGINS`` named it, as it finds a config's
    ``module:`` and ``model.local_conv``; a plugin that does not import is
    one line naming it."""
    from satagraph.data.datamodule import semantic_embedder
    from satagraph.experiment import registry
    from satagraph.semantics import factory
    monkeypatch.setattr(factory, "TEXT_ENCODERS", dict(factory.TEXT_ENCODERS))
    monkeypatch.setattr(registry, "_IMPORTED_PLUGINS", set())
    plugin = tmp_path / "my_encoders.py"
    plugin.write_text("import torch\n"
                      "from satagraph.semantics import TextEncoder, register_text_encoder\n"
                      "class Bag(TextEncoder):\n"
                      "    def __init__(self, arg):\n"
                      "        self._id, self._dim = f'bag:{arg}', 3\n"
                      "    def encode(self, texts):\n"
                      "        return torch.ones(len(texts), 3)\n"
                      "register_text_encoder('bag_plugin_t', Bag)\n")
    monkeypatch.setenv("SATAGRAPH_PLUGINS", str(plugin))
    enc = build_text_encoder("bag_plugin_t:v1")
    assert type(enc).__name__ == "Bag" and enc.id == "bag:v1" and enc.out_channels == 3
    assert semantic_embedder("bag_plugin_t:v2").encoder.id == "bag:v2"
    monkeypatch.setenv("SATAGRAPH_PLUGINS", "no_such_encoders_here")
    with pytest.raises(ValueError, match="^SATAGRAPH_PLUGINS: cannot import "
                       "'no_such_encoders_here'"):
        build_text_encoder("other_t:v1")
