"""Keyword arguments → the library's flags and scene tables.

Keyword names are the CLI's flags with ``-`` as ``_`` (``--light-dir`` is
``light_dir=``, ``--box`` is ``box=``): they are the library's flags
(``voxless::SceneFlags``), which check them and apply them over the scene by
the CLI's rules, so a keyword means here what its flag means there. This
module only adds what a command line cannot say, as scene tables:

- ``camera=Camera(…)`` (or a dict): the whole ``[camera]`` table;
- ``colormap=[[x, r, g, b], …]`` and ``opacity=[[x, a], …]``: control points;
- ``log=False`` / ``linear=False`` (the other one), ``shade=False`` (no
  light), ``orthographic=True`` / ``False`` (the projection alone);
- ``size=N`` (a square), ``iso=x`` (one value), ``scalars="f.scalars"`` (one
  file), ``box=(lo, hi)`` (a periodic box's corners, besides a side ``L`` or
  six numbers), and paths as ``os.PathLike``.

Unknown keywords are a ``TypeError`` naming the closest known one; values the
library refuses are a :class:`voxless.VoxlessError` (a ``ValueError``) naming
the keyword.
"""

from __future__ import annotations

import difflib
import math
import os
from numbers import Integral, Real

import numpy as np

from . import _voxless

#: The flags (the library's names), those of them that describe data, and
#: the data flags each in-memory constructor takes.
FLAG_NAMES, DATA_FLAGS, _CONSTRUCTORS = _voxless.flag_names()
FLAG_NAMES, DATA_FLAGS = tuple(FLAG_NAMES), tuple(DATA_FLAGS)
CONSTRUCTOR_FLAGS = {name: tuple(flags) for name, flags in _CONSTRUCTORS}
VIEW_FLAGS = tuple(n for n in FLAG_NAMES if n not in DATA_FLAGS)

CAMERA_KEYS = ("eye", "look_at", "up", "fov", "projection", "ortho_height", "orbit", "elevation", "zoom")

# ---- converters (for the few arguments checked here) ---------------------------


def number(name, v):
    """A finite real number."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (Real, np.number)):
        raise TypeError(f"{name}: expected a number, got {type(v).__name__}")
    v = float(v)
    if not math.isfinite(v):
        raise ValueError(f"{name}: {v} is not finite")
    return v


def integer(name, v, lo=None):
    """An integer, at least ``lo``."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (Integral, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(v).__name__}")
    v = int(v)
    if lo is not None and v < lo:
        raise ValueError(f"{name}: {v} is less than {lo}")
    return v


def boolean(name, v):
    if not isinstance(v, (bool, np.bool_)):
        raise TypeError(f"{name}: expected True or False, got {type(v).__name__}")
    return bool(v)


def vector(name, v, n):
    """A sequence of ``n`` finite numbers (a numpy array is fine)."""
    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
        raise TypeError(f"{name}: expected {n} numbers, got {type(v).__name__}")
    items = list(np.asarray(v, dtype=object).ravel()) if isinstance(v, np.ndarray) else list(v)
    if len(items) != n:
        raise ValueError(f"{name}: expected {n} numbers, got {len(items)}")
    return [number(f"{name}[{i}]", x) for i, x in enumerate(items)]


def box(name, v):
    """A box: six numbers ``(x0, y0, z0, x1, y1, z1)`` or ``(lo, hi)`` corners."""
    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
        raise TypeError(f"{name}: expected (x0, y0, z0, x1, y1, z1) or (lo, hi), got {type(v).__name__}")
    if len(v) == 2:
        return vector(f"{name}[0]", v[0], 3) + vector(f"{name}[1]", v[1], 3)
    return vector(name, v, 6)


def periodic_box(name, v):
    """A periodic box: a side ``L`` (the box ``[0, L)³``), six numbers or ``(lo, hi)`` corners."""
    if isinstance(v, np.ndarray) and v.ndim == 0:
        v = v.item()
    if isinstance(v, (Real, np.number)) and not isinstance(v, (bool, np.bool_)):
        return number(name, v)
    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
        raise TypeError(f"{name}: expected a side L, (x0, y0, z0, x1, y1, z1) or (lo, hi), got {type(v).__name__}")
    if len(v) == 1:
        return [number(f"{name}[0]", v[0])]
    if len(v) not in (2, 6):
        raise ValueError(f"{name}: expected a side L, (x0, y0, z0, x1, y1, z1) or (lo, hi), got {len(v)} values")
    return box(name, v)


def points(name, v, k):
    """A list of control points, ``k`` numbers each."""
    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
        raise TypeError(f"{name}: expected a name or a list of {k}-number points, got {type(v).__name__}")
    return [vector(f"{name}[{i}]", p, k) for i, p in enumerate(v)]


def path(name, v):
    """A file path as a string (``os.PathLike`` is fine)."""
    if not isinstance(v, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a path, got {type(v).__name__}")
    return os.fspath(v)


# ---- keyword arguments → (tables, flags) ---------------------------------------


def unknown(where, name, known):
    """The TypeError for an unknown keyword, with the closest known one."""
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return TypeError(f"{where}() got an unexpected keyword argument {name!r}{hint}")


def camera_table(v):
    """The ``[camera]`` table of a :class:`voxless.Camera` or a dict (unset keys: the defaults)."""
    cam = v.to_dict() if hasattr(v, "to_dict") else v
    if not isinstance(cam, dict):
        raise TypeError(f"camera: expected a voxless.Camera or a dict, got {type(v).__name__}")
    for k in cam:
        if k not in CAMERA_KEYS:
            raise unknown("Camera", k, CAMERA_KEYS)
    # A camera replaces the whole table: what it leaves unset is the default.
    return {k: cam.get(k) for k in CAMERA_KEYS}


def _table(tables, name):
    t = tables.get(name)
    if not isinstance(t, dict):
        t = tables[name] = {}
    return t


def split(where, kwargs, data=()):
    """Keyword arguments as ``(tables, flags)``: scene tables for what only Python
    can say (see the module docs) and the library's flags for the rest.

    ``data`` names the data flags ``where`` takes (beyond the view's); None
    values are left out (as a flag not given).
    """
    tables, flags = {}, {}
    known = VIEW_FLAGS + tuple(data) + ("camera",)
    for name, v in kwargs.items():
        if v is None:
            continue
        if name in DATA_FLAGS and name not in data:
            raise TypeError(
                f"{where}() does not take {name}=: it describes the data, which is fixed when the volume is made"
                if where in ("render", "describe", "project")
                else f"{where}() does not take {name}= (see voxless.load for files)"
            )
        if name not in known:
            raise unknown(where, name, known)
        if name == "camera":
            tables["camera"] = camera_table(v)
        elif name == "size" and isinstance(v, (Integral, np.integer)) and not isinstance(v, (bool, np.bool_)):
            flags["size"] = [int(v), int(v)]
        elif name == "iso" and isinstance(v, (Real, np.number)):
            flags["iso"] = [v]
        elif name == "colormap" and not isinstance(v, str):
            t = _table(tables, "transfer")
            t.update(colormap_points=points(name, v, 4), colormap=None, colormap_file=None)
        elif name == "opacity" and not isinstance(v, str):
            t = _table(tables, "transfer")
            t.update(opacity_points=points(name, v, 2), opacity=None)
        elif name in ("log", "linear") and v is False:
            flags["linear" if name == "log" else "log"] = True
        elif name == "shade" and v is False:
            tables["light"] = None
        elif name == "orthographic" and isinstance(v, (bool, np.bool_)):
            _table(tables, "camera")["projection"] = "orthographic" if v else "perspective"
        elif name == "scalars" and isinstance(v, (str, os.PathLike)):
            flags["scalars"] = [os.fspath(v)]
        elif name == "clip":
            flags["clip"] = box(name, v)
        elif name == "box":
            flags["box"] = periodic_box(name, v)
        else:
            flags[name] = os.fspath(v) if isinstance(v, os.PathLike) else v
    return tables, flags


def merge(base, over):
    """``over``'s tables merged into ``base`` (a new dict): key by key, None removes."""
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k].update(v)
        else:
            out[k] = v
    return out
