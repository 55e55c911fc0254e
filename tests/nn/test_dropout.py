import pytest
import torch
from torch import nn

from satagraph.nn import FastDropout, SpatioTemporalBlock, fast_dropout, use_fast_dropout


@pytest.mark.parametrize("p", [0.1, 0.5, 0.9])
def test_drop_rate_and_scaling(p):
    torch.manual_seed(0)
    x = torch.ones(200_001)
    out = fast_dropout(x, p, True)
    dropped = (out == 0).float().mean().item()
    assert abs(dropped - p) < 0.005
    kept = out[out != 0]
    assert torch.allclose(kept, torch.full_like(kept, 1 / (1 - p)))
    assert abs(out.mean().item() - 1.0) < 0.02  # expectation preserved


def test_lanes_are_independent():
    torch.manual_seed(1)
    out = fast_dropout(torch.ones(400_000), 0.25, True).view(-1, 4)
    rates = (out == 0).float().mean(0)
    assert torch.all((rates - 0.25).abs() < 0.01), rates


def test_identity_when_off_and_reproducible():
    x = torch.randn(7, 5)
    assert fast_dropout(x, 0.3, False) is x
    assert fast_dropout(x, 0.0, True) is x
    torch.manual_seed(3)
    a = fast_dropout(x, 0.3, True)
    torch.manual_seed(3)
    b = fast_dropout(x, 0.3, True)
    assert torch.equal(a, b)
    assert torch.equal(fast_dropout(x, 1.0, True), torch.zeros_like(x))


def test_gradient_is_the_mask():
    torch.manual_seed(0)
    x = torch.randn(64, 16, dtype=torch.float64, requires_grad=True)
    out = fast_dropout(x, 0.2, True)
    out.sum().backward()
    mask = torch.where(out != 0, 1 / 0.8, 0.0).to(x.dtype)
    assert torch.allclose(x.grad, mask)


def test_swaps_every_dropout_and_keeps_state():
    layer = nn.TransformerEncoderLayer(8, 2, 16, 0.1, batch_first=True)
    before = {k: v.clone() for k, v in layer.state_dict().items()}
    use_fast_dropout(layer)
    kinds = [type(m) for m in layer.modules() if isinstance(m, nn.Dropout)]
    assert kinds and all(k is FastDropout for k in kinds)
    assert all(torch.equal(before[k], v) for k, v in layer.state_dict().items())
    layer.eval()
    x = torch.randn(2, 3, 8)
    assert torch.equal(layer(x), layer(x))


def test_spatio_temporal_block_uses_fast_dropout():
    block = SpatioTemporalBlock(16, heads=2, ff_channels=32, dropout=0.1)
    assert not any(type(m) is nn.Dropout for m in block.modules())
    assert any(isinstance(m, FastDropout) for m in block.modules())
