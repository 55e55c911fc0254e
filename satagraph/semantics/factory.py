"""One factory of text encoders by spec string, and the check that a
checkpoint is used with the text encoder it was trained with.

Specs (:func:`build_text_encoder`):

* ``offline`` (or ``offline:D``): :class:`~.encoders.OfflineTextEncoder`;
* ``t5:PATH``: :class:`~.encoders.T5TextEncoder`;
* ``sentence:PATH`` or ``minilm:PATH``: :class:`~.sentence.SentenceEncoder`;
* ``glove:PATH``: :class:`~.glove.GloVeEncoder`;
* ``NAME:ARG``: an encoder of one's own, by :func:`register_text_encoder`.

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
from satagraph.utils.registry import register_name

#: Spec prefix -> encoder class built from the rest of the spec (a path):
#: the built-in ones and those :func:`register_text_encoder` adds.
TEXT_ENCODERS: Dict[str, Callable[[str], TextEncoder]] = {
    "t5": T5TextEncoder,
    "sentence": SentenceEncoder,
    "minilm": SentenceEncoder,
    "glove": GloVeEncoder,
}
#: The built-in prefixes.
BUILTIN_PREFIXES = tuple(TEXT_ENCODERS)
SPEC_HELP = ("use 'offline', 'offline:D', 't5:PATH', 'sentence:PATH' (or "
             "'minilm:PATH') or 'glove:PATH'")


def register_text_encoder(prefix: str, builder: Callable[[str], TextEncoder]) -> None:
    r"""Make ``prefix:ARG`` a text encoder spec (``model.text_encoder``,
    ``data.semantic_encoder``) that :obj:`builder` builds from ``ARG``.

    A checkpoint keeps the spec and the encoder's :attr:`~.encoders.TextEncoder.id`
    and width (:func:`text_encoder_state`), so the code that registers it
    must run before such a checkpoint is loaded: import it first, or name
    its file in ``SATAGRAPH_PLUGINS``, which :func:`build_text_encoder`
    imports on a prefix it does not know (from Python as on the command
    line, as a config's ``module:`` and ``model.local_conv`` are found).

    Example::

        from satagraph.semantics import TextEncoder, register_text_encoder

        class BagEncoder(TextEncoder):
            def __init__(self, arg: str) -> None:
                self._id, self._dim = f"bag:{arg}", 48
            def encode(self, texts):   # list[str] -> float32 tensor [N, 48]
                ...

        register_text_encoder("bag", BagEncoder)   # model.text_encoder: bag:v1

    Args:
        prefix (str): The spec's name before ``:`` (not a built-in one).
        builder (callable): ``ARG`` -> :class:`~.encoders.TextEncoder`.

    Raises:
        ValueError: The prefix is taken, empty, or holds ``:``.
    """
    key = str(prefix).strip()
    if not key or ":" in key:
        raise ValueError(f"text encoder prefix {prefix!r}: a name without ':' is expected")
    register_name(TEXT_ENCODERS, key, builder, "text encoder", reserved=("offline",))


def spec_help() -> str:
    """What :func:`build_text_encoder` takes, registered prefixes included."""
    own = [f"'{k}:ARG'" for k in TEXT_ENCODERS if k not in BUILTIN_PREFIXES]
    return (SPEC_HELP + (f"; registered: {', '.join(own)}" if own else "")
            + " (register_text_encoder adds one, in a file SATAGRAPH_PLUGINS names for "
            "the command line)")


class TextEncoderMismatch(ValueError):
    """A checkpoint used with another text encoder than it was trained with."""


def build_text_encoder(spec: Union[str, TextEncoder]) -> TextEncoder:
    """A text encoder from its spec.

    Args:
        spec: A spec string (see the module) or an encoder (returned as is).

    Returns:
        TextEncoder: The encoder (models load lazily, on first use).

    Raises:
        ValueError: An unknown spec (one line: the known ones, and how to
            register one), after the plugins ``SATAGRAPH_PLUGINS`` names
            are imported (:func:`~satagraph.experiment.registry.import_user_plugins`),
            or a plugin that does not import.
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
    if sep and kind not in TEXT_ENCODERS and rest:  # one's own, registered in a plugin
        from satagraph.experiment.registry import import_user_plugins
        import_user_plugins()
    if sep and kind in TEXT_ENCODERS and rest:
        return TEXT_ENCODERS[kind](rest)
    raise ValueError(f"unknown text encoder {text!r}: {spec_help()}")


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
           "register_text_encoder", "spec_help",
           "text_encoder_state", "check_text_encoder", "check_text_encoder_state"]
