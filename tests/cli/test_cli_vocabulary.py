"""One concept, one spelling: options that several commands share read
the same way in each."""
from __future__ import annotations

import pytest

from satagraph.cli import build_parser, parse_args


@pytest.fixture(scope="module")
def parser():
    return build_parser()


@pytest.mark.parametrize("command", [
    ["train", "tiny"],
    ["code-bank", "t2m_tiny", "bank.safetensors", "--windows", "4"],
    ["eval", "--ckpt", "builtin"],
    ["demo"],
])
def test_repeated_data_keeps_every_source(parser, command):
    """``--data A --data B`` names two sources on every command that takes
    ``--data`` (eval and demo kept only B: train's spelling silently scored
    or trained on one folder of two)."""
    args = parse_args(parser, [*command, "--data", "mocap/a", "--data", "mocap/b"])
    assert args.data == ["mocap/a", "mocap/b"]


@pytest.mark.parametrize("command", [["eval", "--ckpt", "builtin"], ["demo"]])
def test_listed_data_still_reads(parser, command):
    """The list form those two commands had (``--data A B``) is kept."""
    assert parse_args(parser, [*command, "--data", "a", "b"]).data == ["a", "b"]
    assert parse_args(parser, command).data is None
