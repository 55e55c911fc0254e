"""One factory of text encoders by spec string, and the check that a
checkpoint is used with the text encoder it was trained with.

Specs (:func:`build_text_encoder`):

* ``offline`` (or ``offline:D``): :class:`~.encoders.OfflineTextEncoder`;
* ``t5:PATH``: :class:`~.encoders.T5TextEncoder`;
* ``sentence:PATH`` or ``minilm:PATH``: :class:`~.sentence.SentenceEncoder`;
* ``glove:PATH``: :class:`~.glove.GloVeEncoder`.

A checkpoint stores :func:`text_encoder_state` (the encoder's :attr:`id`
and width); :func:`check_text_encoder` compares it with the encoder a user
passes.
"""
from __future__ import annotations

from typing import Callable, Dict, Mapping, Union

from satagraph.semantics.encoders import (OfflineTextEncoder, T5TextEncoder,
                                          TextEncoder)
from satagraph.semantics.glove import GloVeEncoder
from satagraph.semantics.sentence import SentenceEncoder

#: Spec prefix -> encoder class built from the rest of the spec (a path).
TEXT_ENCODERS: Dict[str, Callable[[str], TextEncoder]] = {
    "t5": T5TextEncoder,
    "sentence": SentenceEncoder,
    "minilm": SentenceEncoder,
    "glove": GloVeEncoder,
}
SPEC_HELP = ("use 'offline', 'offline:D', 't5:PATH', 'sentence:PATH' (or "
             "'minilm:PATH') or 'glove:PATH'")


class TextEncoderMismatch(ValueError):
    """A checkpoint used with another text encoder than it was trained with."""


def build_text_encoder(spec: Union[str, TextEncoder]) -> TextEncoder:
    """A text encoder from its spec.

    Args:
        spec: A spec string (see the module) or an encoder (returned as is).

    Returns:
        TextEncoder: The encoder (models load lazily, on first use).

    Raises:
        ValueError: An unknown spec.
        FileNotFoundError: A path that holds no model (message names it).
    """
    if isinstance(spec, TextEncoder):
        return spec
    text = str(spec).strip()
    if text == "offline":
        return OfflineTextEncoder()
    kind, sep, rest = text.partition(":")
    if sep and kind == "offline":
        if not rest.isdigit():
            raise ValueError(f"text encoder {text!r}: 'offline:D' needs an integer "
                             "width D")
        return OfflineTextEncoder(int(rest))
    if sep and kind in TEXT_ENCODERS and rest:
        return TEXT_ENCODERS[kind](rest)
    raise ValueError(f"unknown text encoder {text!r}: {SPEC_HELP}")


def text_encoder_state(encoder: TextEncoder) -> Dict[str, object]:
    """What a checkpoint stores of its text encoder.

    Args:
        encoder: The encoder.

    Returns:
        dict: ``{"id": encoder.id, "width": encoder.out_channels}``.
    """
    return {"id": encoder.id, "width": int(encoder.out_channels)}


def check_text_encoder(stored_id: str, stored_width: int, encoder: TextEncoder) -> None:
    """Refuse an encoder other than the one a checkpoint was trained with.

    Args:
        stored_id: The checkpoint's encoder id.
        stored_width: The checkpoint's encoder width.
        encoder: The encoder given now.

    Raises:
        TextEncoderMismatch: Different width or id; the message names both.
    """
    if int(stored_width) != int(encoder.out_channels):
        raise TextEncoderMismatch(
            f"text encoder width mismatch: the checkpoint was trained with "
            f"{stored_id!r} ({stored_width}-D), the encoder given is {encoder.id!r} "
            f"({encoder.out_channels}-D)")
    if stored_id != encoder.id:
        raise TextEncoderMismatch(
            f"text encoder mismatch: the checkpoint was trained with {stored_id!r}, the "
            f"encoder given is {encoder.id!r} (same width {stored_width}, other vectors):"
            " pass the encoder (and the very files) it was trained with")


def check_text_encoder_state(state: Mapping[str, object], encoder: TextEncoder) -> None:
    """:func:`check_text_encoder` on a stored :func:`text_encoder_state`."""
    check_text_encoder(str(state["id"]), int(state["width"]), encoder)


__all__ = ["TEXT_ENCODERS", "TextEncoderMismatch", "build_text_encoder",
           "text_encoder_state", "check_text_encoder", "check_text_encoder_state"]
