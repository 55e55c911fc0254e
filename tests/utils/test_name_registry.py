"""The one rule of the name registries (:mod:`satagraph.utils.registry`):
a name is registered once, and a taken one is one line naming it, in the
window transforms', text encoders' and local convolutions' registries
alike."""
from __future__ import annotations

import pytest

from satagraph.utils.registry import register_name


def test_a_name_is_registered_once():
    table = {"a": 1}
    register_name(table, "b", 2, "thing")
    assert table == {"a": 1, "b": 2}
    for key in ("a", "none"):
        with pytest.raises(ValueError) as err:
            register_name(table, key, 3, "thing", reserved=("none",))
        assert str(err.value) == f"thing '{key}' is registered already; pick another name"
    assert table == {"a": 1, "b": 2}


def test_each_registry_refuses_a_taken_name_in_the_same_words(monkeypatch):
    from satagraph.data import window_transform as wt
    from satagraph.nn.layers import local_conv
    from satagraph.semantics import factory
    monkeypatch.setattr(wt, "_TRANSFORMS", {"jitter_t": print})
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(local_conv._BUILDERS))
    monkeypatch.setattr(factory, "TEXT_ENCODERS", dict(factory.TEXT_ENCODERS))
    for register, name, what in ((wt.register_window_transform, "jitter_t", "window transform"),
                                 (local_conv.register_local_conv, "GINE", "local conv"),
                                 (local_conv.register_local_conv, "none", "local conv"),
                                 (factory.register_text_encoder, "offline", "text encoder"),
                                 (factory.register_text_encoder, "t5", "text encoder")):
        with pytest.raises(ValueError, match=f"^{what} '{name.lower()}' is registered "
                           "already; pick another name$"):
            register(name, print)
