"""A synthetic scene of slanted squares whose blur grows from the centre to the periphery, shared by
the natural-scene SFR tests (the `graded_scene` fixture)."""

import numpy as np
import pytest

from solas_mi.metrics.targets import Square, slanted_squares

SHAPE = (480, 640)
CENTRE = (319.5, 239.5)
# square centres and the annulus they lie in (R = 400 px: centre < 96 px, middle < 240 px)
LAYOUT = (
    [((0, 0), 0)]
    + [((dx, dy), 1) for dx, dy in ((-170, 0), (170, 0), (0, -150), (0, 150))]
    + [((dx, dy), 2) for dx in (-250, 250) for dy in (-170, 170)]
)
SIGMA = (0.8, 1.4, 2.2)  # px per annulus


def scene(scale=(1.0, 1.0, 1.0), texture=False) -> np.ndarray:
    squares = [
        Square(CENTRE[0] + dx, CENTRE[1] + dy, 70, 6.0 if i % 2 else -7.0, SIGMA[ring] * scale[ring], 0.2)
        for i, ((dx, dy), ring) in enumerate(LAYOUT)
    ]
    img = slanted_squares(SHAPE, squares, background=0.7, noise=0.002, seed=7, supersample=4)
    if texture:  # random 3-px blocks between the squares: edges everywhere, none isolated
        blocks = np.random.default_rng(1).uniform(0.3, 0.6, (20, 20)).repeat(3, 0).repeat(3, 1)
        img[200:260, 420:480] = blocks
    return img


@pytest.fixture(scope="session")
def graded_scene():
    """scene(scale=(1, 1, 1), texture=False): the blur of each annulus multiplied by `scale`."""
    return scene
