"""A seeded camera noise model: sensor noise, blur and a brightness change. Off by default."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class CameraNoiseConfig:
    """How much to disturb each rendered image; all zero means the clean render.

    ``sensor_sigma`` is the standard deviation of per-pixel Gaussian noise in 0..255 grey levels;
    ``blur_sigma_px`` a Gaussian blur (defocus, motion) in pixels; ``brightness_jitter`` the
    half-width of a uniform gain around 1 applied to the whole frame (a lamp, an exposure change).
    """

    sensor_sigma: float = 0.0
    blur_sigma_px: float = 0.0
    brightness_jitter: float = 0.0
    seed: int = 0

    @property
    def enabled(self) -> bool:
        """True when any disturbance is on."""
        return self.sensor_sigma > 0 or self.blur_sigma_px > 0 or self.brightness_jitter > 0

    @classmethod
    def realistic(cls, seed: int = 0) -> CameraNoiseConfig:
        """A noisy but working camera: sigma 4 grey levels, 0.8 px blur, +-15 % brightness."""
        return cls(sensor_sigma=4.0, blur_sigma_px=0.8, brightness_jitter=0.15, seed=seed)


class CameraNoise:
    """Applies a ``CameraNoiseConfig`` to frames, from its own random stream."""

    def __init__(self, config: CameraNoiseConfig | None = None) -> None:
        self.config = config or CameraNoiseConfig()
        self._rng = np.random.default_rng(self.config.seed)

    def apply(self, rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """Return a disturbed copy of ``rgb`` (the same array when the model is off)."""
        config = self.config
        if not config.enabled:
            return rgb
        import cv2

        image = rgb.astype(np.float32)
        if config.blur_sigma_px > 0:
            image = cv2.GaussianBlur(image, (0, 0), config.blur_sigma_px)
        if config.brightness_jitter > 0:
            image *= 1.0 + self._rng.uniform(-config.brightness_jitter, config.brightness_jitter)
        if config.sensor_sigma > 0:
            image += self._rng.normal(0.0, config.sensor_sigma, image.shape).astype(np.float32)
        return np.clip(image, 0, 255).astype(np.uint8)
