"""voxless: render particles, AMR cells and phase-space tessellations in their native form.

Volumes come from numpy arrays (:class:`Particles`, :class:`AmrCells`,
:class:`Tessellation`) or from any file the ``voxless`` CLI reads
(:func:`load`), are built once, and are then rendered (:meth:`Volume.render`:
an :class:`Image`, H×W×4 float32 premultiplied linear RGBA), projected
(:meth:`Volume.project`: H×W float32 column density) and sampled
(:meth:`Volume.sample`: N×k float32 with column names) — from the same Rust
library and with the same defaults as the CLI. Keyword arguments are the
CLI's flags; a scene dictionary is the TOML scene file's tables.

:func:`project` projects a file without building a volume: particles are
streamed from their files in chunks when they can be, so a snapshot of
10⁸ particles projects in the memory of its image.

The GIL is released while voxless works and Ctrl-C cancels a render. Bad
input raises ``TypeError`` or ``ValueError`` (:class:`VoxlessError`, a
``ValueError``) naming the argument. ``voxless.yt`` (imported on use) brings
yt data sets: ``voxless.yt.off_axis_projection`` and ``VoxlessSource``.

>>> import numpy as np, voxless
>>> vol = voxless.Particles(np.random.rand(1000, 3), radius=0.05)
>>> img = vol.render(size=(320, 240), colormap="magma")
>>> img.shape, img.dtype
((240, 320, 4), dtype('float32'))
"""

from ._voxless import VoxlessError, colormaps, default_north
from .image import Fields, Image, Projection, Slice
from .volume import AmrCells, Camera, Particles, Tessellation, Volume, load, project, render

__all__ = [
    "AmrCells",
    "Camera",
    "Fields",
    "Image",
    "Particles",
    "Projection",
    "Slice",
    "Tessellation",
    "Volume",
    "VoxlessError",
    "colormaps",
    "default_north",
    "load",
    "project",
    "render",
]


def __getattr__(name):
    # voxless.yt imports yt, which is slow and optional: only when used.
    if name == "yt":
        import importlib

        return importlib.import_module(".yt", __name__)
    raise AttributeError(f"module 'voxless' has no attribute {name!r}")
