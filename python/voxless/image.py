"""What renders, projections and samples return: numpy arrays with a little more.

- :class:`Image`: H×W×4 float32, **premultiplied linear RGBA**, row 0 at the
  top — colour already multiplied by alpha, in linear light (not sRGB). To
  show or save it, composite it over a background and encode it as sRGB:
  :meth:`Image.to_srgb8` (what the CLI writes to PNG, byte for byte),
  :meth:`Image.to_png`, :meth:`Image.save`; Jupyter shows it by itself
  (``_repr_png_``).
- :class:`Projection`: H×W float32 column density with its geometry
  (``pixel_area``, ``width``, ``center``, ``right``, ``up``, ``normal``).
- :class:`Fields`: N×k float32 samples with ``columns``; ``fields["density"]``
  is a column.

They are ``numpy.ndarray`` subclasses: ``np.asarray(x)`` gives the plain
array, and arithmetic works as on any array.
"""

from __future__ import annotations

import os

import numpy as np

from . import _voxless


class Image(np.ndarray):
    """H×W×4 float32 premultiplied linear RGBA, row 0 at the top (see the module docs).

    ``background`` is the linear RGB colour the render asked for behind the
    volume (used by :meth:`to_srgb8` when no other is given); ``notes`` are
    the defaults the render chose.
    """

    background = (0.0, 0.0, 0.0)
    notes = ()

    @classmethod
    def wrap(cls, rgba, background=(0.0, 0.0, 0.0), notes=()):
        img = np.asarray(rgba, dtype=np.float32).view(cls)
        img.background = tuple(float(c) for c in background)
        img.notes = tuple(notes)
        return img

    def __array_finalize__(self, obj):
        if obj is not None:
            self.background = getattr(obj, "background", (0.0, 0.0, 0.0))
            self.notes = getattr(obj, "notes", ())

    def _is_rgba(self):
        return self.ndim == 3 and self.shape[2] == 4

    def _rgba(self):
        if not self._is_rgba():
            raise ValueError(f"image: expected an H×W×4 RGBA array, got shape {self.shape}")
        return np.ascontiguousarray(self, dtype=np.float32).view(np.ndarray)

    def _bg(self, background):
        from ._options import vector

        return vector("background", self.background if background is None else background, 3)

    @property
    def rgb(self):
        """The premultiplied linear RGB channels (H×W×3)."""
        return np.asarray(self)[..., :3]

    @property
    def alpha(self):
        """Opacity (H×W)."""
        return np.asarray(self)[..., 3]

    def to_srgb8(self, background=None):
        """H×W×3 uint8 sRGB over an opaque linear ``background`` (default: the render's)."""
        return _voxless.srgb8(self._rgba(), self._bg(background))

    def to_png(self, background=None) -> bytes:
        """PNG bytes of :meth:`to_srgb8`."""
        return _voxless.png(self._rgba(), self._bg(background))

    def save(self, path, background=None):
        """Writes a PNG (the CLI's output for the same render)."""
        path = os.fspath(path)
        if not path.lower().endswith(".png"):
            raise ValueError(f"path: {path!r}: Image.save writes .png (use numpy for float data)")
        with open(path, "wb") as f:
            f.write(self.to_png(background))

    def _repr_png_(self):
        return self.to_png() if self._is_rgba() and self.size else None


class Projection(np.ndarray):
    """H×W float32 column density ∫ field dt, row 0 at the top, with its geometry.

    ``width`` is the world (width, height) covered, ``pixel_area`` the world
    area of a pixel, ``center`` the world image centre, ``right``/``up`` the
    unit vectors of increasing column and decreasing row, ``normal`` =
    right × up, ``total_mass`` the exact ∫ field dV when known.
    """

    geometry = {}

    @classmethod
    def wrap(cls, column, geometry):
        p = np.asarray(column, dtype=np.float32).view(cls)
        geometry = dict(geometry)
        # What the projection said (the device standing in), as Image.notes.
        notes = tuple(geometry.pop("notes", ()))
        p.geometry = {k: (np.array(v) if isinstance(v, (list, tuple)) else v) for k, v in geometry.items()}
        p.geometry["notes"] = notes
        return p

    def __array_finalize__(self, obj):
        if obj is not None:
            self.geometry = getattr(obj, "geometry", {})

    def __getattr__(self, name):
        geometry = self.__dict__.get("geometry") or type(self).geometry
        if name in geometry:
            return geometry[name]
        raise AttributeError(name)

    def mass(self) -> float:
        """Σ pixels × pixel area (float64): the total mass when the image covers the data."""
        return float(np.asarray(self, dtype=np.float64).sum() * self.geometry["pixel_area"])

    @property
    def extent(self):
        """``(left, right, bottom, top)`` in image-plane coordinates (world along ``right`` and ``up``), for imshow."""
        g = self.geometry
        u = float(np.dot(g["center"], g["right"]))
        v = float(np.dot(g["center"], g["up"]))
        w, h = g["width"]
        return (u - w / 2, u + w / 2, v - h / 2, v + h / 2)


class Slice(np.ndarray):
    """H×W float32: the field on a plane, row 0 at the top (NaN outside AMR cells).

    ``quantity`` names the field shown; ``geometry`` holds the plane:
    ``center`` (a point of the plane, at the image centre), ``right``/``up``
    (unit vectors of increasing column and decreasing row), ``normal`` and
    ``width`` (world width and height).
    """

    geometry = {}
    quantity = ""

    @classmethod
    def wrap(cls, values, quantity, geometry):
        s = np.asarray(values, dtype=np.float32).view(cls)
        s.quantity = quantity
        s.geometry = {k: np.array(v) for k, v in geometry.items()}
        return s

    def __array_finalize__(self, obj):
        if obj is not None:
            self.geometry = getattr(obj, "geometry", {})
            self.quantity = getattr(obj, "quantity", "")

    def __getattr__(self, name):
        geometry = self.__dict__.get("geometry") or type(self).geometry
        if name in geometry:
            return geometry[name]
        raise AttributeError(name)

    @property
    def extent(self):
        """``(left, right, bottom, top)`` in plane coordinates (world along ``right`` and ``up``), for imshow."""
        g = self.geometry
        u = float(np.dot(g["center"], g["right"]))
        v = float(np.dot(g["center"], g["up"]))
        w, h = g["width"]
        return (u - w / 2, u + w / 2, v - h / 2, v + h / 2)


class Fields(np.ndarray):
    """N×k float32 field values at points; ``columns`` names the k columns."""

    columns = ()

    @classmethod
    def wrap(cls, values, columns):
        f = np.asarray(values, dtype=np.float32).view(cls)
        f.columns = tuple(columns)
        return f

    def __array_finalize__(self, obj):
        if obj is not None:
            self.columns = getattr(obj, "columns", ())

    def __getitem__(self, key):
        if isinstance(key, str):
            if key not in self.columns:
                raise KeyError(f"{key!r}: the columns are {', '.join(self.columns)}")
            return np.asarray(self)[:, self.columns.index(key)]
        return super().__getitem__(key)

    def to_dict(self):
        """``{column: values}``."""
        return {c: np.asarray(self)[:, i] for i, c in enumerate(self.columns)}
