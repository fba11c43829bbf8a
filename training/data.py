"""Training data: generated on the fly (by seed) or read from a folder made by `doctrpp crops`."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import torch
from torch.utils.data import Dataset, Sampler

from doctrpp import contract
from doctrpp.udir.sample import generate, kind_for_index

VALIDATION_SEED_OFFSET = 1_000_000_000  # training seeds stay far below this


def hsv_jitter(image_bgr: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The paper's colour augmentation: random hue shift, saturation and value scaling."""
    hsv = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2HSV).astype(np.float32)
    hsv[..., 0] = (hsv[..., 0] + rng.uniform(-12, 12)) % 180
    hsv[..., 1] *= rng.uniform(0.6, 1.4)
    hsv[..., 2] *= rng.uniform(0.7, 1.3)
    return cv2.cvtColor(np.clip(hsv, 0, 255).astype(np.uint8), cv2.COLOR_HSV2BGR)


def to_tensors(
    image_bgr: np.ndarray, backward_map: np.ndarray
) -> tuple[torch.Tensor, torch.Tensor]:
    """Crop -> model input (3, 288, 288) RGB in [0, 1]; map -> target in 288-grid pixels."""
    size = contract.INPUT_SIZE
    if image_bgr.shape[:2] != (size, size):
        image_bgr = cv2.resize(image_bgr, (size, size), interpolation=cv2.INTER_LINEAR)
    rgb = image_bgr[:, :, ::-1].astype(np.float32) / 255.0
    target = contract.normalised_to_pixels(backward_map.astype(np.float32))
    return (
        torch.from_numpy(np.ascontiguousarray(rgb.transpose(2, 0, 1))),
        torch.from_numpy(np.ascontiguousarray(target.transpose(2, 0, 1))),
    )


class GeneratedCrops(Dataset):
    """Sample i is `generate(seed_offset + i, self.kind_of(i))`, with colour jitter."""

    def __init__(
        self,
        seed_offset: int = 0,
        kind: str = "mixed",
        augment: bool = True,
        length: int = 10**12,
        complete_until: int = 0,
        page_reuse: int = 1,
    ) -> None:
        self.seed_offset, self.kind, self.augment, self.length = seed_offset, kind, augment, length
        # A curriculum: samples before this index are complete-boundary crops. Trained on the
        # mixed stream from the start, our CPU runs collapsed to the mean map (session 1).
        self.complete_until = complete_until
        self.page_reuse = page_reuse  # consecutive samples share a page (see udir make_scene)

    def kind_of(self, index: int) -> str:
        return "complete" if index < self.complete_until else kind_for_index(index, self.kind)

    def __len__(self) -> int:
        return self.length

    def __getitem__(self, index: int) -> tuple[torch.Tensor, torch.Tensor]:
        seed = self.seed_offset + index
        sample = generate(seed, self.kind_of(index), page_reuse=self.page_reuse)
        image = sample.image
        if self.augment:
            image = hsv_jitter(image, np.random.default_rng([seed, 7]))
        return to_tensors(image, sample.backward_map)


class FolderCrops(Dataset):
    """Samples written by `doctrpp crops` (NNNNN.png + NNNNN_map.npy), cycled."""

    def __init__(self, folder: str | Path, augment: bool = True) -> None:
        self.maps = sorted(Path(folder).glob("*_map.npy"))
        if not self.maps:
            raise FileNotFoundError(f"{folder}: no *_map.npy samples")
        self.augment = augment

    def __len__(self) -> int:
        return 10**12

    def __getitem__(self, index: int) -> tuple[torch.Tensor, torch.Tensor]:
        map_path = self.maps[index % len(self.maps)]
        image = cv2.imread(str(map_path).replace("_map.npy", ".png"), cv2.IMREAD_COLOR)
        if self.augment:
            image = hsv_jitter(image, np.random.default_rng([index, 7]))
        return to_tensors(image, np.load(map_path))


class StreamSampler(Sampler[int]):
    """Indices start, start + world, ... for one rank: a never-repeating, resumable stream."""

    def __init__(self, start: int, rank: int = 0, world: int = 1) -> None:
        self.start, self.rank, self.world = start, rank, world

    def __iter__(self) -> Iterator[int]:
        index = self.start + self.rank
        while True:
            yield index
            index += self.world
