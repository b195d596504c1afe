"""Reading and writing images: OpenEXR (linear float + metadata) for data, PNG (sRGB) for viewing.

Every writer is atomic: it writes a temporary file beside the target and renames it.
"""
from __future__ import annotations

import json
import os
import tempfile
import warnings
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Iterator

import numpy as np

from .errors import SolasError

META_KEY = "solas_mi"


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[str]:
    """Yield a temporary path beside `path`; rename it onto `path` only if the block succeeds."""
    path = Path(path)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes the file private; give it the usual mode
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] → sRGB-encoded [0, 1] (IEC 61966-2-1)."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


@lru_cache(maxsize=1)
def _srgb8_table() -> np.ndarray:
    """8-bit sRGB code of each 16-bit linear level (the nearest code, ±1 at code boundaries)."""
    return np.round(srgb_encode(np.linspace(0.0, 1.0, 65536)) * 255.0).astype(np.uint8)


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """sRGB-encoded [0, 1] → linear [0, 1] (IEC 61966-2-1)."""
    x = np.clip(encoded, 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def write_exr(path: str | os.PathLike, channels: dict[str, np.ndarray], meta: dict | None = None,
              compress: bool = True) -> None:
    """Write float32 channels (equal 2-D shapes, row 0 = top) and JSON metadata to an OpenEXR file.

    `compress=False` skips ZIP compression, for data that does not compress (PSF grids)."""
    import OpenEXR

    compression = OpenEXR.ZIP_COMPRESSION if compress else OpenEXR.NO_COMPRESSION
    header = {"compression": compression, "type": OpenEXR.scanlineimage}
    if meta is not None:
        header[META_KEY] = json.dumps(meta)
    data = {name: np.ascontiguousarray(a, dtype=np.float32) for name, a in channels.items()}
    with atomic_path(path) as tmp:
        with OpenEXR.File(header, data) as f:
            f.write(tmp)


def image_channels(image: np.ndarray, names: list[str] | None = None) -> dict[str, np.ndarray]:
    """EXR channels of an image: H×W → "Y"; H×W×3 → "R", "G", "B"; other channel counts need `names`."""
    if image.ndim == 2:
        return {"Y": image}
    names = names if names is not None else (list("RGB") if image.shape[-1] == 3 else None)
    if names is None or len(names) != image.shape[-1]:
        raise SolasError(f"image of shape {image.shape} needs one channel name per channel (got {names})")
    return dict(zip(names, np.moveaxis(image, -1, 0)))


def write_text(path: str | os.PathLike, text: str) -> None:
    """A text file, written atomically."""
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text)


def read_exr(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict]:
    """Channels (name → float32 2-D array) and the solas-mi metadata ({} if absent) of an EXR file."""
    import OpenEXR

    if not Path(path).is_file():
        raise SolasError(f"no such EXR file: {path}")
    with OpenEXR.File(str(path)) as f:
        header = f.header()
        # read the metadata before the pixels: loading channels rebuilds the header dictionary
        meta = json.loads(header[META_KEY]) if META_KEY in header else {}
        channels = {}
        for name, c in f.channels().items():
            pixels = np.array(c.pixels)
            if pixels.ndim == 3 and len(name) == pixels.shape[-1]:  # OpenEXR groups R, G, B as "RGB"
                channels.update({letter: pixels[..., k] for k, letter in enumerate(name)})
            else:
                channels[name] = pixels
    return channels, meta


def write_png(path: str | os.PathLike, image: np.ndarray, *, encoded: bool = False) -> None:
    """Write a linear [0, 1] image (H×W or H×W×3) as 8-bit sRGB PNG; `encoded=True` skips the encoding."""
    import imageio.v3 as iio

    if encoded:
        data = np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)
    else:
        data = _srgb8_table()[(np.clip(image, 0.0, 1.0) * 65535.0 + 0.5).astype(np.uint16)]
    with atomic_path(path) as tmp:
        iio.imwrite(tmp, data, extension=".png", compress_level=1)  # fast zlib: viewing copies only


def read_image(path: str | os.PathLike, *, linearize: bool = True) -> np.ndarray:
    """An image as float64 H×W or H×W×C: EXR as stored (linear); PNG/JPEG/TIFF scaled to [0, 1]
    and sRGB-decoded unless `linearize` is False."""
    path = Path(path)
    if path.is_dir():
        raise SolasError(f"{path} is a folder, not an image file")
    if not path.is_file():
        raise SolasError(f"no such image file: {path}")
    if path.suffix.lower() == ".exr":
        channels, _ = read_exr(path)
        names = list(channels)
        rgb = [n for n in ("R", "G", "B") if n in channels]
        if len(rgb) == 3:
            return np.stack([channels[n] for n in rgb], axis=-1).astype(np.float64)
        if len(names) == 1:
            return channels[names[0]].astype(np.float64)
        return np.stack([channels[n] for n in names], axis=-1).astype(np.float64)
    import imageio.v3 as iio

    try:
        with warnings.catch_warnings():  # imageio's probing of legacy plugins (DICOM …) on unknown content
            warnings.simplefilter("ignore", DeprecationWarning)
            raw = iio.imread(path)
    except Exception as exc:  # imageio raises many types for unreadable files
        reason = str(exc).split("\n")[0].rstrip(".")  # its first line; the rest suggests plugins to install
        raise SolasError(f"cannot read image {path} as PNG, JPEG, TIFF or OpenEXR ({reason})") from None
    if raw.dtype == np.uint8:
        scaled = raw.astype(np.float64) / 255.0
    elif raw.dtype == np.uint16:
        scaled = raw.astype(np.float64) / 65535.0
    else:
        scaled = raw.astype(np.float64)
    if scaled.ndim == 3 and scaled.shape[-1] == 4:
        scaled = scaled[..., :3]
    return srgb_decode(scaled) if linearize else scaled
