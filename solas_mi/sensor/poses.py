"""The camera's pose over a frame (`rendered`): its `to_world` read from a scene's sensor (`camera_pose`), checked
(`checked_end`), interpolated between the frame's start and end (`pose_at`), and the end reached by a constant
velocity and angular velocity, as a simulator exports a camera's motion (`end_pose`). NumPy and SciPy are imported
when a function runs (`MAX_TURN_DEG` is a command's help)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..errors import SolasError

if TYPE_CHECKING:
    import numpy as np

MAX_TURN_DEG = 180.0  # over the frame: a turn of more has two shortest ways, the interpolation can take neither


def pose_at(start: np.ndarray, end: np.ndarray, fraction: float) -> np.ndarray:
    """The 4×4 transform `fraction` of the way from `start` to `end`: the rotation of each (its polar
    decomposition's) interpolated spherically, the stretch and translation linearly; SolasError where one
    mirrors and the other does not."""
    import numpy as np
    from scipy.linalg import polar
    from scipy.spatial.transform import Rotation, Slerp

    (ra, sa), (rb, sb) = polar(start[:3, :3]), polar(end[:3, :3])
    mirror = np.diag([1.0, 1.0, np.sign(np.linalg.det(ra))])
    if np.sign(np.linalg.det(ra)) != np.sign(np.linalg.det(rb)):
        raise SolasError("the camera's to_world at the frame's start and end: one mirrors, the other does not")
    turn = Slerp([0.0, 1.0], Rotation.from_matrix([ra @ mirror, rb @ mirror]))([fraction]).as_matrix()[0]
    pose = np.eye(4)
    pose[:3, :3] = turn @ mirror @ ((1.0 - fraction) * sa + fraction * sb)
    pose[:3, 3] = (1.0 - fraction) * start[:3, 3] + fraction * end[:3, 3]
    return pose


def camera_pose(sensor) -> tuple:
    """The sensor's parameters (`mitsuba.traverse`) and its `to_world` (4×4); SolasError for a sensor
    without one."""
    import mitsuba as mi
    import numpy as np

    params = mi.traverse(sensor)
    if "to_world" not in params:
        raise SolasError(f"camera motion: the scene's sensor {sensor.class_name()} has no to_world parameter")
    return params, np.array(params["to_world"].matrix, dtype=np.float64).reshape(4, 4)


def checked_end(to_world_end) -> np.ndarray:
    """`to_world_end` as a 4×4 float64 array; SolasError unless it is a finite affine transform."""
    import numpy as np

    end = np.asarray(to_world_end, dtype=np.float64)
    if end.shape != (4, 4) or not np.isfinite(end).all() or not np.allclose(end[3], [0.0, 0.0, 0.0, 1.0]):
        raise SolasError(
            f"to_world_end must be a finite 4x4 affine transform (last row 0 0 0 1), not {np.shape(to_world_end)}"
        )
    return end


def end_pose(start, velocity, angular_deg_s, span_s: float):
    """The camera's `to_world` (4×4) `span_s` after `start` moving at `velocity` and turning at `angular_deg_s`
    about the world's axes through its own position; SolasError for a turn of `MAX_TURN_DEG` or more."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    turn = np.radians(np.asarray(angular_deg_s, dtype=np.float64)) * span_s
    if np.degrees(np.linalg.norm(turn)) >= MAX_TURN_DEG:
        raise SolasError(
            f"the camera's angular velocity turns it {np.degrees(np.linalg.norm(turn)):g}° over the frame's {span_s:g} s; "
            f"it must turn less than {MAX_TURN_DEG:g}° (a turn is interpolated the shortest way)"
        )
    end = np.array(start, dtype=np.float64)
    end[:3, :3] = Rotation.from_rotvec(turn).as_matrix() @ end[:3, :3]
    end[:3, 3] += np.asarray(velocity, dtype=np.float64) * span_s
    return end
