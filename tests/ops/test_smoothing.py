"""gaussian_smooth: per-clip temporal smoothing that keeps constants and
means, lowers jitter, and never mixes clips."""
from __future__ import annotations

import torch

from satagraph.ops.smoothing import gaussian_smooth


def test_smoothing_keeps_constants_lowers_jitter_and_never_mixes_clips() -> None:
    gen = torch.Generator().manual_seed(0)
    ramp = torch.linspace(0, 1, 40)[:, None].repeat(1, 3)
    noisy = ramp + 0.1 * torch.randn(40, 3, generator=gen)
    const = torch.full((25, 3), 7.0)
    x = torch.cat([noisy, const])
    out = gaussian_smooth(x, torch.tensor([40, 25]), sigma=2.0)
    assert out.shape == x.shape
    torch.testing.assert_close(out[40:], const)  # the other clip's values never leak in
    jitter = lambda v: (v[2:] - 2 * v[1:-1] + v[:-2]).abs().mean()  # noqa: E731
    assert jitter(out[:40]) < 0.25 * jitter(noisy)
    interior = slice(8, 32)  # away from the replicated edges a ramp stays a ramp
    assert (out[:40][interior] - noisy[interior]).abs().mean() < 0.1
    torch.testing.assert_close(out[:40][interior].mean(0), noisy[interior].mean(0), atol=0.03,
                               rtol=0)
    assert torch.equal(gaussian_smooth(x, torch.tensor([40, 25]), 0.0), x)
