"""The SATA modules on a second device, emulated without one
(:class:`~tests.device_emulation.HostTracker`): no tensor of a training step
or of inference is made on the host and mixed with the model's or the
batch's."""
from __future__ import annotations

import pytest
import torch

from tests.device_emulation import HostTracker


def test_the_tracker_names_a_host_tensor_mixed_with_a_device_one():
    """What the emulation catches: an ``arange`` without ``device=`` added to
    a parameter's output, and a device tensor read into NumPy."""
    torch.manual_seed(0)
    layer = torch.nn.Linear(3, 3)
    with HostTracker(layer) as tracker:
        out = layer(torch.ones(2, 3, device=layer.weight.device))
        out = out + torch.arange(3.0)
        out.detach().numpy()
        out.detach().cpu().numpy()  # moved first: fine
    assert [m.split(": ", 1)[1] for m in tracker.mixes] == [
        "add: host and device tensors mixed", "numpy: a device tensor read into NumPy"]


@pytest.mark.parametrize("name", ["vae", "rvq"])
def test_a_training_step_and_inference_make_nothing_on_the_host(build_tiny_module,
                                                                train_batch, name):
    module = build_tiny_module(name).train()
    with HostTracker() as tracker:
        out = module(train_batch)
        module.compute_losses(out, train_batch)["loss"].backward()
        with torch.no_grad():
            module.eval()(train_batch)
    assert tracker.mixes == []
