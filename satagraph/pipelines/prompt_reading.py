r"""A prompt read in a generator's own words (``satagraph generate``).

A text-to-motion model knows the words of the captions it was trained on
and nothing else: the built-in generator's captions name their subject
"a person", "a four-legged animal", "a bird", "an insect", ..., never "a
dog" or "a woman". With the offline text encoder an unseen word is a
hashed feature the model never learnt, so "a dog walks forward" reads as
a prompt about nothing in particular (``experiments/T2M.md`` section 24).

:func:`read_prompt` replaces a subject noun the model never saw
(:data:`SUBJECT_NOUNS`: dog, horse, woman, chicken, ant, ...) by the
model's own subject of that body plan (:data:`~satagraph.datasets.zoo_captions.ZOO_SUBJECTS`'
first phrase) when the model saw every word of that phrase, fixing the
article ("an ostrich" -> "a bird"), and lists the words it still never
saw. A model without a record of its words
(:data:`VOCABULARY_KEY`, written by training since 29 Nov) is read
literally.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Dict, FrozenSet, Iterable, List, Optional, Tuple

from satagraph.datasets.zoo_captions import ZOO_SUBJECTS

#: Where a text-to-motion module keeps the sorted words of its training
#: captions (``module.meta``, hence checkpoints and weights files).
VOCABULARY_KEY = "caption_words"

#: Nouns naming a subject -> the body plan whose zoo subject replaces them
#: (none that is also a common motion word: "fly", "figure" (eight)).
SUBJECT_NOUNS: Dict[str, str] = {
    **dict.fromkeys(("man", "woman", "human", "boy", "girl", "child", "kid", "guy",
                     "lady", "adult", "actor", "dancer", "athlete", "soldier", "humanoid",
                     "robot", "zombie", "walker", "runner"), "biped"),
    **dict.fromkeys(("dog", "puppy", "cat", "kitten", "horse", "pony", "foal", "wolf",
                     "fox", "cow", "calf", "deer", "lion", "tiger", "leopard", "cheetah",
                     "bear", "sheep", "goat", "pig", "donkey", "mule", "camel", "zebra",
                     "giraffe", "elephant", "rabbit", "hound", "mammal", "beast"),
                    "quadruped"),
    **dict.fromkeys(("chicken", "hen", "rooster", "chick", "duck", "goose", "turkey",
                     "ostrich", "emu", "pigeon", "crow", "raven", "penguin", "parrot",
                     "seagull", "gull", "heron", "flamingo", "sparrow"), "bird"),
    **dict.fromkeys(("ant", "beetle", "cockroach", "roach", "bug", "cricket",
                     "grasshopper", "mantis", "bee", "wasp"), "hexapod"),
    **dict.fromkeys(("tarantula", "arachnid"), "spider"),
    **dict.fromkeys(("lobster", "crayfish"), "crab"),
    **dict.fromkeys(("serpent", "python", "cobra", "viper"), "snake"),
}
_WORD = re.compile(r"[A-Za-z0-9]+(?:-[A-Za-z0-9]+)*")
_PLAIN = re.compile(r"[a-z0-9]+")
_WRITTEN = re.compile(r"[^\W_]+")  # a word as written, in any script


@dataclass(frozen=True)
class PromptReading:
    """What :func:`read_prompt` made of a prompt.

    Attributes:
        text (str): The prompt the model is given.
        replaced (tuple): ``(noun, subject)`` pairs, e.g. ``("dog",
            "four-legged animal")``.
        unknown (tuple): Words of :attr:`text` the model never saw, in order.
    """

    text: str
    replaced: Tuple[Tuple[str, str], ...] = ()
    unknown: Tuple[str, ...] = ()

    def note(self) -> Optional[str]:
        """One line for the user, or ``None`` where the prompt is read as
        written and every word is known."""
        parts = [f'read "{noun}" as "{subject}"' for noun, subject in self.replaced]
        if self.unknown:
            parts.append("never saw " + ", ".join(f'"{w}"' for w in self.unknown)
                         + " in training")
        return "; ".join(parts) if parts else None


def words_of(texts: Iterable[str]) -> FrozenSet[str]:
    """The lower-case words of :obj:`texts` (as the offline text encoder
    splits them: letters and digits)."""
    return frozenset(w for text in texts for w in _PLAIN.findall(text.lower()))


def vocabulary_of(module) -> Optional[FrozenSet[str]]:
    """The words a text-to-motion module was trained on (``None``: it keeps
    no record, e.g. a checkpoint of before 29 Nov)."""
    words = (getattr(module, "meta", None) or {}).get(VOCABULARY_KEY)
    return None if not words else frozenset(words)


def _subject(plan: str, vocabulary: FrozenSet[str]) -> Optional[str]:
    """The zoo subject of :obj:`plan` without its article, if the model saw
    all its words."""
    phrase = ZOO_SUBJECTS[plan][0].split(" ", 1)[1]
    return phrase if words_of([phrase]) <= vocabulary else None


def article(phrase: str) -> str:
    """The indefinite article of :obj:`phrase` ("a" or "an")."""
    return "an" if phrase[:1].lower() in tuple("aeiou") else "a"


def _with_article(tokens: List[str], index: int, phrase: str) -> None:
    """Replace ``tokens[index]`` by :obj:`phrase`, the article just before
    it ("a" or "an") made to fit."""
    tokens[index] = phrase
    before = [j for j in range(index) if _WORD.fullmatch(tokens[j])]
    if before and tokens[before[-1]].lower() in ("a", "an"):
        j = before[-1]
        tokens[j] = article(phrase).capitalize() if tokens[j][0].isupper() else article(phrase)


def read_prompt(text: str, vocabulary: Optional[FrozenSet[str]],
                subjects: bool = True) -> PromptReading:
    """:obj:`text` in the words of a model that saw :obj:`vocabulary`.

    Args:
        text (str): The user's prompt.
        vocabulary (frozenset, optional): The model's words
            (:func:`vocabulary_of`); ``None`` reads the prompt as written.
        subjects (bool): Replace the subject nouns the model never saw
            (``False``: only name the unknown words).

    Returns:
        PromptReading: The text to encode, the replaced nouns and the words
        still unknown.
    """
    if not vocabulary:
        return PromptReading(text)
    tokens = re.split(f"({_WORD.pattern})", text)
    replaced = []
    for i, token in enumerate(tokens):
        word = token.lower()
        plan = SUBJECT_NOUNS.get(word)
        if not subjects or plan is None or word in vocabulary:
            continue
        subject = _subject(plan, vocabulary)
        if subject is not None:
            _with_article(tokens, i, subject)
            replaced.append((token, subject))
    out = "".join(tokens)
    return PromptReading(out, tuple(replaced), unknown_words(out, vocabulary))


def has_words(text: str) -> bool:
    """Whether :obj:`text` holds a word, in any script (``"!!!"`` holds none)."""
    return _WRITTEN.search(text) is not None


def unknown_words(text: str, vocabulary: FrozenSet[str]) -> Tuple[str, ...]:
    """The words of :obj:`text`, as written (lower case), that a model which
    saw :obj:`vocabulary` never saw: those with a piece the offline text
    encoder reads ("très": "tr", "s") outside it, or with none at all
    ("人が歩く"), so the note names the user's words, not their pieces."""
    unknown = []
    for word in _WRITTEN.findall(text.lower()):
        pieces = set(_PLAIN.findall(word))
        if not pieces or not pieces <= vocabulary:
            unknown.append(word)
    return tuple(dict.fromkeys(unknown))


__all__ = ["VOCABULARY_KEY", "SUBJECT_NOUNS", "PromptReading", "words_of", "vocabulary_of",
           "article", "read_prompt", "has_words", "unknown_words"]
