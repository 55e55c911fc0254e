"""Fixtures of the generator tests."""
from __future__ import annotations

import pytest
import torch

from tests.nn.generators.generator_helpers import SKEL, TEXT


@pytest.fixture
def conditions():
    """Text and skeleton embeddings and lengths (frames) of three sequences."""
    gen = torch.Generator().manual_seed(1)
    return (torch.randn(3, TEXT, generator=gen), torch.randn(3, SKEL, generator=gen),
            torch.tensor([10, 7, 3]))
