"""Training data: generated on the fly (by seed) or read from a folder made by `doctrpp crops`."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import torch
from torch.utils.data import Dataset, Sampler

from doctrpp import contract
from doctrpp.udir.sample import generate, kind_for_index

VALIDATION_SEED_OFFSET = 1_000_000_000  # training seeds stay far below this
REUSE_WINDOW = 256  # generated samples a data worker keeps for reuse (~0.9 MB each)


def generated_index(position: int, reuse: int, window: int = REUSE_WINDOW) -> int:
    """Which generated sample stream position `position` shows. With `reuse` K, each block
    of K * window positions shows its first `window` samples K times in a row of windows
    (so a batch holds distinct samples), each time with a fresh colour jitter."""
    if reuse <= 1:
        return position
    block, offset = divmod(position, reuse * window)
    return block * reuse * window + offset % window


def reuse_window(batch: int, workers: int, world: int = 1) -> int:
    """The smallest window of at least REUSE_WINDOW samples after which a position falls to
    the same rank and data worker again (batch k goes to worker k % workers), so the
    repeat finds the sample in that worker's cache."""
    unit = batch * max(workers, 1) * max(world, 1)
    return unit * -(-REUSE_WINDOW // unit)


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
        sample_reuse: int = 1,
        window: int = REUSE_WINDOW,
    ) -> None:
        self.seed_offset, self.kind, self.augment, self.length = seed_offset, kind, augment, length
        # A curriculum: samples before this index are complete-boundary crops. Trained on the
        # mixed stream from the start, our CPU runs collapsed to the mean map (session 1).
        self.complete_until = complete_until
        self.page_reuse = page_reuse  # consecutive samples share a page (see udir make_scene)
        # Each generated sample shown `sample_reuse` times (generation is the bottleneck on
        # a 2-core machine: the trainer waited for data a third of the time).
        self.sample_reuse, self.window = sample_reuse, window
        self._cache: OrderedDict[int, tuple[np.ndarray, np.ndarray]] = OrderedDict()

    def kind_of(self, index: int) -> str:
        return "complete" if index < self.complete_until else kind_for_index(index, self.kind)

    def __len__(self) -> int:
        return self.length

    def _generated(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        if index in self._cache:
            return self._cache[index]
        sample = generate(self.seed_offset + index, self.kind_of(index), page_reuse=self.page_reuse)
        if self.sample_reuse > 1:
            self._cache[index] = (sample.image, sample.backward_map)
            while len(self._cache) > self.window:
                self._cache.popitem(last=False)
        return sample.image, sample.backward_map

    def __getitem__(self, position: int) -> tuple[torch.Tensor, torch.Tensor]:
        image, backward_map = self._generated(
            generated_index(position, self.sample_reuse, self.window)
        )
        if self.augment:  # seeded by the position: each showing gets its own jitter
            image = hsv_jitter(image, np.random.default_rng([self.seed_offset + position, 7]))
        return to_tensors(image, backward_map)


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
