"""`DegradeSpec`: every option of degrading images by a PSF grid as one frozen value, checked when
built, defined once: `degrade` and `batch degrade` make their flags from its fields and build it from
them (`options.OptionSpec`: `DegradeSpec.add_flags`, `DegradeSpec.from_args`), `convolution.output.
degrade_file` and the batch (`batch.degrade.degrade_batch`, `plan_batch`) take it, and a batch's
manifest header and identity are made from it (`header`, `identity`).

The frame's camera, a batch's camera and a batch's grid options are objects the commands build from
several flags each (`commands.add_frame_options`, `isp.commands.add_camera_options`, the `psf-grid`
flags): fields without a flag of their own.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from ..errors import SolasError
from ..labelkinds import KINDS, RULES, kinds_help, parse_label_files
from ..optics.calibration.command import calibration_help
from ..optics.calibration.models import MODELS
from ..optics.frame import FrameCamera
from ..options import OptionSpec, option
from ..psf.spec import GridSpec
from .depth import OCCLUSIONS, SILHOUETTES
from .ghosts import DEFAULT_THRESHOLD, check_threshold
from .kernels import BOUNDARIES, check_boundary
from .methods import DEFAULT_METHOD, METHODS, check_method

# float32 OpenEXR (14 MB a 1280×960 RGB frame uncompressed), half floats, or a 16-bit sRGB PNG (its own
# preview; its metadata in a JSON file beside it): OUTPUT_FILES gives each one's two files' suffixes
OUTPUT_FILES = {"exr": (".exr", ".png"), "exr-half": (".exr", ".png"), "png16": (".png", ".json")}
OUTPUT_FORMATS = tuple(OUTPUT_FILES)
DEPTH_WITH = "with a depth map (degrade --depth, batch degrade --depth-pattern)"


@dataclass(frozen=True)
class DegradeSpec(OptionSpec):
    """How images are degraded by a PSF grid, checked when built.

    ``solas-mi degrade`` and ``solas-mi batch degrade`` make their flags from its fields and build it
    from them; one image (`output.degrade_file`) takes method, boundary, linear, output format,
    occlusion, silhouette and frame; the others are a batch's (`solas_mi.batch.degrade_batch`).

    Parameters
    ----------
    method : str, default "interp"
        The convolution method, a name of `methods.METHODS`.
    boundary : str, default "edge"
        The padding outside the image, one of `kernels.BOUNDARIES`; never wrapped around.
    linear : bool, default False
        PNG/JPEG values are already linear (not sRGB-decoded).
    output_format : str, default "exr"
        A batch's items' data, one of `OUTPUT_FORMATS`.
    depth_pattern : str, optional
        A batch's depth map beside each image, e.g. "{stem}_depth.exr" (a grid over object distance).
    occlusion : str, default "filled"
        With a depth map, how layers are composited, one of `depth.OCCLUSIONS` (`convolution.depth`).
    silhouette : str, default "nearest"
        With a depth map, the depth of a silhouette's mixed pixels, one of `depth.SILHOUETTES`.
    label_patterns : tuple of (str, str), optional
        A batch's label files beside each image, (kind, pattern) pairs of `labelkinds.KINDS`, warped with it
        (`convolution.labels`).
    scale_lens : float, optional
        A batch's camera's pixel pitch (µm): its lens scaled to the camera's focal length
        (`batch.degrade.scaled_lens`).
    calibration_model : str, default "opencv-fisheye"
        The camera model whose fit to the lens the degraded frames' metadata records, a name of
        `optics.calibration.MODELS` (`convolution.camera`).
    ghosts : bool, default False
        Add the lens's ghosts of each frame's bright sources and write the flare label (`convolution.ghosts`).
    ghost_threshold : float, default 10
        With ghosts: the pixels whose brightest channel exceeds it (linear input units) are the sources.
    frame : FrameCamera, optional
        The camera every input was taken with (`optics.frame.FrameCamera`); default: the image spans the
        grid's x field range.
    camera : isp.camera.Camera, optional
        A batch's sensor and image processor each degraded frame goes through (checked by the batch).
    grid_spec : GridSpec, optional
        The grid a batch computes from its lens (`psf.spec.GridSpec`); default: its defaults.

    Raises
    ------
    SolasError
        For a value that is not among its choices or of its kind.

    Examples
    --------
    >>> from solas_mi.convolution import DegradeSpec
    >>> DegradeSpec(method="patch").header()
    {'method': 'patch', 'boundary': 'edge', 'linear': False, 'format': 'exr', 'calibration_model': 'opencv-fisheye'}
    """

    method: str = option(METHODS.help, DEFAULT_METHOD, choices=METHODS.names)
    boundary: str = option(
        "padding outside the image, never wrapped around: edge (default) replicates the border "
        "pixels, zero pads with black, reflect mirrors the image about its border",
        BOUNDARIES[0],
        choices=BOUNDARIES,
    )
    linear: bool = option("PNG/JPEG values are already linear: do not decode sRGB", False)
    output_format: str = option(
        "output data: exr (float, default), exr-half (half floats, half the size) or png16 "
        "(16-bit sRGB PNG, values clipped to [0, 1], its metadata in <name>.json beside it)",
        OUTPUT_FORMATS[0],
        flag="--format",
        choices=OUTPUT_FORMATS,
    )
    depth_pattern: str | None = option(
        "each image's depth map beside it (metres), with a grid over object distance "
        "(--distances-m): `degrade --depth` per image",
        metavar="{stem}_depth.exr",
    )
    occlusion: str = option(
        f"{DEPTH_WITH}: filled (default): layers composited far to near, the background hidden "
        "behind near objects continued from their silhouettes; layered: without that; none: "
        "layers added (no occlusion)",
        OCCLUSIONS[0],
        choices=OCCLUSIONS,
    )
    silhouette: str = option(
        f"{DEPTH_WITH}: nearest (default): a silhouette's pixels of mixed (antialiased) depth "
        "take the nearest depth around them; as-given: the map's depths",
        SILHOUETTES[0],
        choices=SILHOUETTES,
    )
    label_patterns: tuple[tuple[str, str], ...] | None = option(
        lambda: (
            f"each image's label files beside it, KIND=PATTERN[,KIND=PATTERN...] (KIND one of {kinds_help()}; "
            "e.g. instance={stem}_instance.png): warped by the mapping the image goes "
            "through, written beside its output (<name>.labels.exr, <name>.boxes.json); never taken as frames"
        ),
        flag="--label-pattern",
        parse=lambda text: parse_label_files(text, "--label-pattern", pattern=True),
        metavar="KIND={stem}_KIND.png",
        shown=lambda v: ",".join("=".join(p) for p in v),
    )
    scale_lens: float | None = option(
        "with --lens and --intrinsics/--fisheye: the camera's pixel pitch (µm); the "
        "lens scaled to its focal length fx x PIXEL_UM, f-number kept, stated in the "
        "metadata",
        parse=float,
        metavar="PIXEL_UM",
    )
    calibration_model: str = option(calibration_help, MODELS.default, choices=MODELS.names)
    ghosts: bool = option(
        "add the lens's ghosts of the frame's bright sources (an HDR frame: EXR; others refused without --force): "
        "each source's ghosts at their own field-dependent places and shapes (`solas-mi ghost-grid`, cached), "
        "and the flare label (flare.irradiance, flare.ratio) in <name>.labels.exr",
        False,
    )
    ghost_threshold: float = option(
        f"with --ghosts: pixels whose brightest channel exceeds it (linear input units) are the ghosts' sources "
        f"(default {DEFAULT_THRESHOLD:g})",
        DEFAULT_THRESHOLD,
        parse=float,
        metavar="VALUE",
    )
    frame: FrameCamera | None = None
    camera: Any = None
    grid_spec: GridSpec | None = None

    def __post_init__(self) -> None:
        check_method(self.method)
        check_boundary(self.boundary)
        if not isinstance(self.linear, bool):
            raise SolasError(f"linear {self.linear!r} must be True or False")
        for name, allowed in (
            ("output format", OUTPUT_FORMATS),
            ("occlusion", OCCLUSIONS),
            ("silhouette", SILHOUETTES),
            ("calibration model", tuple(MODELS.names())),
        ):
            value = getattr(self, name.replace(" ", "_"))
            if not isinstance(value, str) or value not in allowed:
                raise SolasError(f"{name} {value!r} must be one of {', '.join(allowed)}")
        pattern = self.depth_pattern
        if pattern is not None and not (
            isinstance(pattern, str) and "{stem}" in pattern and "/" not in pattern and pattern.lower().endswith(".exr")
        ):
            raise SolasError(
                f"depth pattern {pattern!r} must be a file name with {{stem}} ending in .exr, "
                "e.g. {stem}_depth.exr (beside each image)"
            )
        if self.label_patterns is not None:  # as `parse_label_files` reads them: (kind, pattern) pairs
            object.__setattr__(
                self, "label_patterns", parse_label_files(self.label_patterns, "label patterns", pattern=True)
            )
        if not isinstance(self.ghosts, bool):
            raise SolasError(f"ghosts {self.ghosts!r} must be True or False")
        check_threshold(self.ghost_threshold)
        if not self.ghosts and self.ghost_threshold != DEFAULT_THRESHOLD:
            raise SolasError(f"ghost threshold {self.ghost_threshold!r} is for ghosts: give --ghosts too")
        scale = self.scale_lens
        if scale is not None and (
            isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (math.isfinite(scale) and scale > 0)
        ):
            raise SolasError(f"scale_lens {scale!r} must be the camera's pixel pitch, a positive number of µm")
        for name, kind in (("frame", FrameCamera), ("grid_spec", GridSpec)):
            if getattr(self, name) is not None and not isinstance(getattr(self, name), kind):
                raise SolasError(f"{name} {getattr(self, name)!r} must be a {kind.__module__}.{kind.__name__}")

    def identity(self) -> list:
        """What a batch's outputs depend on besides its grid.

        Returns
        -------
        list
            JSON values in the order and form a batch's id has always hashed them
            (`batch.degrade.plan_batch`): a finished batch resumes only under the same id, so an option
            joins only away from its default (the depth rules only with a depth map).
        """
        return (
            [self.method, self.boundary, self.linear]
            + ([self.output_format] if self.output_format != "exr" else [])
            + ([self.depth_pattern, self.occlusion, self.silhouette] if self.depth_pattern is not None else [])
            + ([asdict(self.frame)] if self.frame is not None else [])
            + ([self.camera.describe()] if self.camera is not None else [])
            + ([dict(self.label_patterns)] if self.label_patterns else [])
            + ([self.calibration_model] if self.calibration_model != MODELS.default else [])
            + ([{"ghosts": self.ghost_threshold}] if self.ghosts else [])
        )

    def header(self, lens_scale: dict | None = None) -> dict[str, Any]:
        """The options as a batch's manifest states them.

        Parameters
        ----------
        lens_scale : dict, optional
            What scaling the lens did (`batch.degrade.scaled_lens`); None: not scaled.

        Returns
        -------
        dict
            Method, boundary, linear, format, and the frame's camera, the lens's scale and the batch's camera
            where given.
        """
        return {
            "method": self.method,
            "boundary": self.boundary,
            "linear": self.linear,
            "format": self.output_format,
            "calibration_model": self.calibration_model,
            **({"frame_camera": asdict(self.frame)} if self.frame is not None else {}),
            **({"lens_scale": lens_scale} if lens_scale is not None else {}),
            **({"camera": self.camera.describe()} if self.camera is not None else {}),
            **({"labels": self.labels_header()} if self.label_patterns else {}),
            **({"ghosts": {"threshold": self.ghost_threshold}} if self.ghosts else {}),
        }

    def labels_header(self) -> dict[str, dict[str, str]]:
        """Each label kind a batch warps, as its manifest states them.

        Returns
        -------
        dict
            Kind → its pattern and how it follows the mapping (`labelkinds.RULES`).
        """
        return {
            kind: {"pattern": pattern, "rule": KINDS[kind].extra["rule"], "how": RULES[KINDS[kind].extra["rule"]]}
            for kind, pattern in self.label_patterns or ()
        }
