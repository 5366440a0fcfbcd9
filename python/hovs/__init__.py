"""hovs: hyperboloid catadioptric camera models, virtual views, datasets and design, from Python.

Frames and units are hovs' own: metres; points and bearings in the mirror frame (origin at the viewpoint F1, z
towards the mirror); pixels (u, v) = (column, row), the top-left pixel's centre at (0, 0).
"""

from ._hovs import (  # noqa: F401
    Camera,
    Dataset,
    Error,
    Unwrapper,
    calibrate,
    design_metrics,
    design_study,
    load_camera,
    radial_resolution,
    read_exr,
    triangulate,
    versions,
    write_point_cloud,
)

__version__ = versions()["hovs"]

__all__ = [
    "Camera",
    "Dataset",
    "Error",
    "Unwrapper",
    "calibrate",
    "design_metrics",
    "design_study",
    "load_camera",
    "radial_resolution",
    "read_exr",
    "triangulate",
    "versions",
    "write_point_cloud",
]
