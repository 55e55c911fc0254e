"""Prompts read in a generator's own words: subject nouns it never saw
replaced by its subject of that body plan, the article fitted, the words it
still never saw named; the record of the words a module trained on, kept by
checkpoints, weights files and ``--init-from``; the shipped generator's
record; and `satagraph generate`'s note."""
from __future__ import annotations

import pytest
import torch

from satagraph.pipelines.prompt_reading import (SUBJECT_NOUNS, VOCABULARY_KEY, read_prompt,
                                                vocabulary_of, words_of)
from tests.t2m.conftest import build_t2m, save_checkpoint, zoo_batch

WORDS = words_of(["a person walks forward, then trots", "a four-legged animal trots to the left",
                  "a bird walks backward", "an insect runs"])


@pytest.mark.parametrize("prompt, read, nouns", [
    ("a dog walks forward", "a four-legged animal walks forward",
     (("dog", "four-legged animal"),)),
    ("An ostrich walks backward", "A bird walks backward", (("ostrich", "bird"),)),
    ("a woman walks, then a horse trots", "a person walks, then a four-legged animal trots",
     (("woman", "person"), ("horse", "four-legged animal"))),
    ("an ant runs", "an insect runs", (("ant", "insect"),)),
    ("a person walks forward", "a person walks forward", ()),
])
def test_unseen_subject_nouns_become_the_models_subjects(prompt, read, nouns):
    reading = read_prompt(prompt, WORDS)
    assert reading.text == read
    assert reading.replaced == nouns
    assert reading.unknown == ()


def test_words_still_unknown_are_named_in_order():
    reading = read_prompt("a big dog waves goodbye", WORDS)
    assert reading.text == "a big four-legged animal waves goodbye"
    assert reading.unknown == ("big", "waves", "goodbye")
    assert reading.note() == ('read "dog" as "four-legged animal"; never saw "big", '
                              '"waves", "goodbye" in training')
    assert read_prompt("a person walks", WORDS).note() is None


def test_unknown_words_are_named_as_written_in_any_script():
    """The note named the pieces the offline encoder cuts a non-ASCII word
    into ("très" was "tr", "s") and said nothing of a prompt in another
    script, read as no words at all."""
    assert read_prompt("a person walks très vite", WORDS).unknown == ("très", "vite")
    assert read_prompt("人が歩く", WORDS).unknown == ("人が歩く",)
    # a word whose pieces the model saw stays known, as the encoder reads it
    assert read_prompt("a person wälks", WORDS | {"w", "lks"}).unknown == ()


def test_known_nouns_and_unknown_subjects_are_left_alone():
    # a model that saw "dog" keeps it
    assert read_prompt("a dog walks", WORDS | {"dog"}).text == "a dog walks"
    # no replacement by a phrase the model never saw: no "spider" here
    reading = read_prompt("a tarantula walks", WORDS)
    assert reading.text == "a tarantula walks" and reading.unknown == ("tarantula",)
    # literal: nothing replaced, the unknown words still named
    literal = read_prompt("a dog walks", WORDS, subjects=False)
    assert literal.text == "a dog walks" and literal.unknown == ("dog",)
    # no record: as written, nothing to say
    assert read_prompt("a dog walks", None).note() is None


def test_every_subject_noun_names_a_zoo_plan():
    from satagraph.datasets.zoo_captions import ZOO_SUBJECTS
    assert set(SUBJECT_NOUNS.values()) <= set(ZOO_SUBJECTS)
    assert all(n == n.lower() and n.isalpha() for n in SUBJECT_NOUNS)


def test_training_records_its_caption_words_through_checkpoints_and_weights(
        autoencoder_ckpt, tmp_path):
    from satagraph.experiment.train import init_weights, load_module
    from satagraph.io.weights import save_weights
    from satagraph.data.captioned import batch_texts
    module = build_t2m(autoencoder_ckpt)
    assert vocabulary_of(module) is None
    batch = zoo_batch(4)
    module.eval()
    module.compute_losses(batch, torch.Generator().manual_seed(0))
    assert vocabulary_of(module) is None  # validation teaches no words
    module.train()
    module.compute_losses(batch, torch.Generator().manual_seed(0))
    words = words_of(batch_texts(batch))
    assert words and vocabulary_of(module) == words
    assert module.meta[VOCABULARY_KEY] == sorted(words)
    ckpt = save_checkpoint(module.eval(), tmp_path / "t2m.ckpt")
    assert vocabulary_of(load_module(str(ckpt))) == words
    save_weights(module, str(tmp_path / "t2m.safetensors"))
    assert vocabulary_of(load_module(str(tmp_path / "t2m.safetensors"))) == words
    fresh = build_t2m(autoencoder_ckpt)
    init_weights(fresh, str(tmp_path / "t2m.safetensors"))
    assert vocabulary_of(fresh) == words  # a fine-tune keeps the words it starts from


def test_the_shipped_generator_knows_its_words():
    from satagraph.io.weights import builtin_path
    if not builtin_path("text-to-motion").is_file():
        pytest.skip("no built-in text-to-motion weights ship in this checkout")
    from satagraph.pipelines.generate import load_generator
    words = vocabulary_of(load_generator("builtin"))
    assert {"person", "four", "legged", "animal", "bird", "insect", "walks"} <= words
    assert not {"dog", "man", "chicken"} & words


def test_generate_says_how_it_read_the_prompt(zoo_skeletons, tmp_path, capsys):
    from satagraph.io.weights import builtin_path
    if not builtin_path("text-to-motion").is_file():
        pytest.skip("no built-in text-to-motion weights ship in this checkout")
    from satagraph.cli import main
    from satagraph.io import read_bvh
    target = str(zoo_skeletons["quadruped"])
    base = ["generate", "--seconds", "1", "--skeleton", target]
    assert main(base + ["--text", "a dog walks forward", str(tmp_path / "read.bvh")]) == 0
    assert 'read "dog" as "four-legged animal"' in capsys.readouterr().err
    assert main(base + ["--text", "a four-legged animal walks forward",
                        str(tmp_path / "own.bvh")]) == 0
    assert "the generator" not in capsys.readouterr().err
    # reading the noun gives the model's own prompt: the same motion
    assert (read_bvh(tmp_path / "read.bvh").rotations ==
            read_bvh(tmp_path / "own.bvh").rotations).all()
    assert main(base + ["--literal", "--text", "a dog walks forward",
                        str(tmp_path / "literal.bvh")]) == 0
    assert 'never saw "dog"' in capsys.readouterr().err
    # a prompt of no words is drawn without text, and said (it was drawn from noise unsaid)
    for text, name in (("!!!", "marks.bvh"), ("", "none.bvh")):
        assert main(base + ["--seed", "4", "--text", text, str(tmp_path / name)]) == 0
    assert "has no words: the motion is drawn without text" in capsys.readouterr().err
    assert (read_bvh(tmp_path / "marks.bvh").rotations ==
            read_bvh(tmp_path / "none.bvh").rotations).all()
