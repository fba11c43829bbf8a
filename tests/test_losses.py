"""The training loss terms: map L1, its 8-pixel differences, the photometric and MS-SSIM terms."""

from __future__ import annotations

import pytest
import torch

from doctrpp.training.data import to_tensors
from doctrpp.udir.sample import generate


def test_gradient_loss_ignores_placement_and_weighs_local_shape():
    from doctrpp.training.losses import map_gradient_l1, map_l1, map_loss

    target = torch.randn(2, 2, 32, 32)
    shifted = target + 3.0  # the whole page moved: plain L1 sees it, the gradient term not
    assert float(map_gradient_l1(shifted, target)) == pytest.approx(0.0, abs=1e-6)
    assert float(map_l1(shifted, target)) == pytest.approx(3.0)
    bent = target.clone()
    bent[:, :, 16:, :] += 1.0  # a fold: a step across the map
    assert float(map_gradient_l1(bent, target)) > 0
    assert torch.equal(map_loss(bent, target, 0.0), map_l1(bent, target))
    both = map_loss(bent, target, 2.0)
    expected = map_l1(bent, target) + 2.0 * map_gradient_l1(bent, target)
    assert torch.allclose(both, expected)


def test_photometric_loss_is_zero_on_the_true_map_and_pulls_a_shifted_one_back():
    from doctrpp.training.losses import map_l1, map_loss, rectified_image_l1

    sample = generate(3, "complete")
    images, target = (t[None] for t in to_tensors(sample.image, sample.backward_map))
    assert float(rectified_image_l1(images, target, target)) == pytest.approx(0.0, abs=1e-7)
    shifted = (target + torch.tensor([2.0, 0.0]).view(1, 2, 1, 1)).requires_grad_(True)
    loss = rectified_image_l1(images, shifted, target)
    assert float(loss.detach()) > 1e-3
    (gradient,) = torch.autograd.grad(loss, shifted)
    # descending the gradient moves x back toward the true map
    assert float(gradient[:, 0].sum()) > 0 and abs(float(gradient[:, 1].sum())) < float(
        gradient[:, 0].sum()
    )
    both = map_loss(shifted, target, 0.0, images, 5.0)
    assert torch.allclose(both, map_l1(shifted, target) + 5.0 * loss)
    with pytest.raises(ValueError, match="need the input images"):
        map_loss(shifted, target, 0.0, None, 5.0)


def test_ms_ssim_loss_is_zero_on_the_true_map_and_grows_with_a_shift():
    from doctrpp.training.losses import map_l1, map_loss, rectified_image_ms_ssim

    sample = generate(3, "complete")
    images, target = (t[None] for t in to_tensors(sample.image, sample.backward_map))
    assert float(rectified_image_ms_ssim(images, target, target)) == pytest.approx(0.0, abs=1e-5)
    losses = []
    for shift in (1.0, 3.0):
        shifted = (target + torch.tensor([shift, 0.0]).view(1, 2, 1, 1)).requires_grad_(True)
        loss = rectified_image_ms_ssim(images, shifted, target)
        (gradient,) = torch.autograd.grad(loss, shifted)
        assert torch.isfinite(gradient).all() and float(gradient.abs().sum()) > 0
        losses.append(float(loss.detach()))
    print(f"1 - MS-SSIM at 1 px / 3 px shift: {losses[0]:.4f} / {losses[1]:.4f}")
    assert 1e-3 < losses[0] < losses[1] < 1.0
    both = map_loss(shifted, target, 0.0, images, 0.0, 2.0)
    assert torch.allclose(both, map_l1(shifted, target) + 2.0 * loss)
    with pytest.raises(ValueError, match="need the input images"):
        map_loss(shifted, target, 0.0, None, 0.0, 2.0)
