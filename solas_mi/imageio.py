"""Reading and writing images: OpenEXR (linear float + metadata) for data, PNG (sRGB) for viewing.

Every writer is atomic: it writes a temporary file beside the target and renames it.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

import numpy as np

from . import jsonio
from .errors import SolasError
from .userfiles import check

META_KEY = "solas_mi"
# each write first removes the temporaries that killed writers of its target left (a scan of the
# folder: 25 ms in one of 20 000 files, measured); a batch's workers turn it off, the batch having
# swept its folder once while holding it (`outputs.remove_temporaries`)
SWEEP_STALE = True


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process
        return True
    return True


def remove_stale_temporaries(path: str | os.PathLike) -> int:
    """Remove the temporary files of `path` (".NAME.PID.XXXXXXXX.SUFFIX", `atomic_path`) that writers
    killed outright (SIGKILL, out of memory) left: those of processes that no longer run. The number
    removed."""
    path = Path(path)
    start = f".{path.name}."
    removed = 0
    try:
        entries = [e for e in os.scandir(path.parent or ".") if e.name.startswith(start)]
    except OSError:
        return 0
    for entry in entries:
        pid, _, rest = entry.name[len(start) :].partition(".")
        if (
            pid.isdigit()
            and len(rest) == 8 + len(path.suffix)
            and rest.endswith(path.suffix)
            and entry.is_file(follow_symlinks=False)
            and not _alive(int(pid))
        ):
            Path(entry.path).unlink(missing_ok=True)
            removed += 1
    return removed


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[str]:
    """Yield a temporary path beside `path` (".NAME.PID.XXXXXXXX.SUFFIX"); rename it onto `path` only if
    the block succeeds. The temporary file is removed on any error or interruption (and those of
    writers of `path` killed outright, by the next write of it: `remove_stale_temporaries`); a write that fails (a full disk, a folder
    that cannot be written) is a SolasError naming `path` and the reason."""
    path = Path(path)
    try:
        if path.parent and not path.parent.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
        if SWEEP_STALE:
            remove_stale_temporaries(path)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=path.suffix, dir=path.parent)
    except OSError as exc:
        raise SolasError(f"cannot write {path}: {exc.strerror or exc}") from None
    os.close(fd)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes the file private; give it the usual mode
        os.replace(tmp, path)
    except OSError as exc:
        raise SolasError(f"cannot write {path}: {exc.strerror or exc}") from None
    except RuntimeError as exc:  # OpenEXR reports failed writes (e.g. no space left) this way
        if "write" not in str(exc).lower():
            raise
        reason = str(exc).rsplit(". ", 1)[-1].rstrip(".") if ". " in str(exc) else str(exc)
        raise SolasError(f"cannot write {path}: {reason}") from None
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


def write_exr(
    path: str | os.PathLike,
    channels: dict[str, np.ndarray],
    meta: dict | None = None,
    compress: bool = True,
    infinite: bool = False,
    half: bool = False,
) -> None:
    """Write float32 channels (equal 2-D shapes, row 0 = top) and JSON metadata to an OpenEXR file.

    `compress=False` skips ZIP compression, for data that does not compress (PSF grids); `half`
    stores half floats (11-bit mantissa, 6e-5 … 65504). A NaN (or, unless `infinite`, e.g. a depth
    map's sky, an infinite value) is a SolasError before anything is written (`check_finite`)."""
    import OpenEXR

    for name, channel in channels.items():
        values = np.nan_to_num(channel, nan=np.nan, posinf=0.0, neginf=0.0) if infinite else channel
        check_finite(np.asarray(values), f"{path}: channel {name}")
    compression = OpenEXR.ZIP_COMPRESSION if compress else OpenEXR.NO_COMPRESSION
    header = {"compression": compression, "type": OpenEXR.scanlineimage}
    if meta is not None:
        try:
            header[META_KEY] = jsonio.dumps(meta)
        except SolasError as exc:
            raise SolasError(f"{path}: metadata: {exc}") from None
    data = {name: np.ascontiguousarray(a, dtype=np.float16 if half else np.float32) for name, a in channels.items()}
    with atomic_path(path) as tmp, OpenEXR.File(header, data) as f:
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

    check(path, "image file")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = f.header()
            # read the metadata before the pixels: loading channels rebuilds the header dictionary
            meta = jsonio.loads(header[META_KEY]) if META_KEY in header else {}
            # the binding's arrays own their pixels (kept after the file closes): no copy (a 315 MB grid's took 0.2 s)
            channels = {name: np.asarray(c.pixels) for name, c in f.channels().items()}
    except (RuntimeError, OSError, ValueError) as exc:  # not an EXR, truncated, bad metadata
        raise SolasError(f"cannot read {path} as OpenEXR: {str(exc).splitlines()[0] if str(exc) else exc}") from None
    return channels, meta


def write_png(path: str | os.PathLike, image: np.ndarray, *, encoded: bool = False) -> None:
    """Write a linear [0, 1] image (H×W or H×W×3) as 8-bit sRGB PNG; `encoded=True` skips the encoding."""
    import imageio.v3 as iio

    check_finite(np.asarray(image), str(path))
    if encoded:
        data = np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)
    else:
        data = _srgb8_table()[(np.clip(image, 0.0, 1.0) * 65535.0 + 0.5).astype(np.uint16)]
    with atomic_path(path) as tmp:
        iio.imwrite(tmp, data, extension=".png", compress_level=1)  # fast zlib: viewing copies only


def write_png16(path: str | os.PathLike, image: np.ndarray) -> int:
    """Write a linear image (H×W or H×W×3) as 16-bit sRGB PNG (`read_image` decodes it back to within
    half a step of 1/65535); values outside [0, 1] are clipped: returns how many were."""
    import png  # pypng: Pillow, behind imageio, writes no 16-bit RGB

    image = check_finite(np.asarray(image, dtype=np.float64), str(path))
    clipped = int(np.count_nonzero((image < 0.0) | (image > 1.0)))
    data = np.round(srgb_encode(np.clip(image, 0.0, 1.0)) * 65535.0).astype(np.uint16)
    height, width = data.shape[:2]
    planes = 1 if data.ndim == 2 else data.shape[2]
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        png.Writer(width, height, greyscale=planes == 1, bitdepth=16).write(f, data.reshape(height, width * planes))
    return clipped


# The channel names read as an RGB image, in order; or one layer's LAYER.R, LAYER.G, LAYER.B.
RGB_SPELLINGS = (("R", "G", "B"), ("r", "g", "b"))
GREY_SPELLINGS = ("Y", "y", "L", "l")


def exr_image_channels(names: list[str], path: str | os.PathLike) -> list[str]:
    """The channels of an EXR file that make an image, by name: R, G, B (or r, g, b, or one layer's
    LAYER.R/G/B) for colour; Y (or L, or the only channel) for grey; A is ignored. SolasError naming
    the channels otherwise."""
    for rgb in RGB_SPELLINGS:
        if all(c in names for c in rgb):
            return list(rgb)
    layers = sorted(
        {n.rsplit(".", 1)[0] for n in names if "." in n and all(f"{n.rsplit('.', 1)[0]}.{c}" in names for c in "RGB")}
    )
    if len(layers) == 1:
        return [f"{layers[0]}.{c}" for c in "RGB"]
    colour = [n for n in names if n not in ("A", "a")]
    grey = [n for n in colour if n in GREY_SPELLINGS]
    if len(grey) == 1 or len(colour) == 1:
        return grey[:1] or colour
    why = f"several layers have R, G, B ({', '.join(layers)})" if layers else "no R, G, B or single grey channel"
    raise SolasError(
        f"{path}: channels {', '.join(names)}: {why}; an image needs R, G, B (or r, g, b, or one "
        f"layer's LAYER.R/G/B) or one grey channel (Y)"
    )


def check_finite(image: np.ndarray, what: str) -> np.ndarray:
    """`image` unchanged if every value is finite, else a SolasError with the count and the first one."""
    bad = ~np.isfinite(image)
    if bad.any():
        first = np.argwhere(bad)[0]
        where = f"row {first[0]}, column {first[1]}" + (f", channel {first[2]}" if len(first) > 2 else "")
        raise SolasError(
            f"{what}: {int(bad.sum())} values are NaN or infinite (the first at {where}); "
            "images must hold finite values"
        )
    return image


def _png_bit_depth(path: Path) -> int:
    with open(path, "rb") as f:
        head = f.read(25)
    return head[24] if head[:8] == b"\x89PNG\r\n\x1a\n" and len(head) == 25 else 8


def _read_png16(path: Path) -> np.ndarray:
    """A 16-bit PNG at full depth (Pillow, behind imageio, reduces 16-bit RGB to 8 bits)."""
    import png

    width, height, rows, info = png.Reader(filename=str(path)).asDirect()
    return np.vstack([np.asarray(r, dtype=np.uint16) for r in rows]).reshape(height, width, info["planes"]).squeeze()


@contextmanager
def _plain_imageio() -> Iterator[None]:
    """imageio without its noise: no warnings from probing legacy plugins (DICOM …) on unknown content,
    and no Pillow "decompression bomb" limit — the commands check an image's memory themselves
    (`budget`) before reading it."""
    from PIL import Image

    limit, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            yield
    finally:
        Image.MAX_IMAGE_PIXELS = limit


def exr_channel_names(path: str | os.PathLike) -> list[str]:
    """The channel names of an EXR file, read from its header only ([] where it cannot be read)."""
    import OpenEXR

    try:
        with OpenEXR.File(str(path), header_only=True) as f:
            return [c.name for c in f.header()["channels"]]
    except Exception:  # unreadable: the reader names the problem
        return []


def image_size(path: str | os.PathLike) -> tuple[int, int, int]:
    """(rows, columns, channels) of an image file, read from its header only (0, 0, 0 where the
    header cannot be read: `read_image` will then say why)."""
    path = Path(path)
    try:
        check(path, "image file")  # a FIFO or device would hang the header's reader
        if path.suffix.lower() == ".exr":
            import OpenEXR

            with OpenEXR.File(str(path), header_only=True) as f:
                lo, hi = f.header()["dataWindow"]
                return int(hi[1] - lo[1] + 1), int(hi[0] - lo[0] + 1), len(f.header()["channels"])
        import imageio.v3 as iio

        with _plain_imageio():
            shape = iio.improps(path).shape
        return int(shape[0]), int(shape[1]), int(shape[2]) if len(shape) > 2 else 1
    except Exception:  # unreadable: the reader names the problem
        return 0, 0, 0


def read_stored(path: str | os.PathLike) -> np.ndarray:
    """The values a PNG (8 or 16 bits), JPEG or TIFF file stores, unscaled (integers stay integers: label
    images of ids), H×W or H×W×C; SolasError naming the file where it cannot be read."""
    import imageio.v3 as iio

    path = check(path, "image file")
    try:
        if path.suffix.lower() == ".png" and _png_bit_depth(path) == 16:
            return _read_png16(path)
        with _plain_imageio():
            return np.asarray(iio.imread(path))
    except Exception as exc:  # imageio and pypng raise many types for unreadable files
        reason = str(exc).split("\n")[0].rstrip(".")  # its first line; the rest suggests plugins to install
        raise SolasError(f"cannot read image {path} as PNG, JPEG, TIFF or OpenEXR ({reason})") from None


def read_image(path: str | os.PathLike, *, linearize: bool = True) -> np.ndarray:
    """An image as float64 H×W or H×W×3: EXR as stored (linear; channels by name, `exr_image_channels`);
    PNG (8 or 16 bits), JPEG, TIFF scaled to [0, 1] and sRGB-decoded unless `linearize` is False; an
    alpha channel is dropped. SolasError for NaN or infinite values."""
    path = check(path, "image file")
    if path.suffix.lower() == ".exr":
        channels, _ = read_exr(path)
        names = exr_image_channels(list(channels), path)
        image = channels[names[0]] if len(names) == 1 else np.stack([channels[n] for n in names], axis=-1)
        return check_finite(image.astype(np.float64), str(path))
    raw = read_stored(path)
    if raw.dtype == np.uint8:
        scaled = raw.astype(np.float64) / 255.0
    elif raw.dtype == np.uint16:
        scaled = raw.astype(np.float64) / 65535.0
    else:
        scaled = check_finite(raw.astype(np.float64), str(path))
    if scaled.ndim == 3 and scaled.shape[-1] in (2, 4):
        scaled = scaled[..., :-1] if scaled.shape[-1] == 4 else scaled[..., 0]
    return srgb_decode(scaled) if linearize else scaled
