"""Keyword arguments → scene-description tables.

Keyword names are the CLI's flags with ``-`` as ``_`` (``--light-dir`` is
``light_dir=``); the scene description is the TOML scene as nested dicts. Each
converter checks its argument's type and shape and raises ``TypeError`` or
``ValueError`` naming it; ranges and defaults are the library's business (its
errors are re-labelled with the keyword they came from, see
:func:`relabel`).
"""

from __future__ import annotations

import difflib
import math
import os
from numbers import Integral, Real

import numpy as np

from ._voxless import VoxlessError

# ---- converters --------------------------------------------------------------


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


def string(name, v):
    if not isinstance(v, str):
        raise TypeError(f"{name}: expected a string, got {type(v).__name__}")
    return v


def choice(name, v, choices):
    v = string(name, v)
    if v not in choices:
        raise ValueError(f"{name}: {v!r} is not one of {', '.join(choices)}")
    return v


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


def size(name, v):
    """An image size: ``(width, height)`` or one number for a square."""
    if isinstance(v, (Integral, np.integer)) and not isinstance(v, (bool, np.bool_)):
        v = (v, v)
    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
        raise TypeError(f"{name}: expected (width, height), got {type(v).__name__}")
    if len(v) != 2:
        raise ValueError(f"{name}: expected (width, height), got {len(v)} numbers")
    return [integer(f"{name}[{i}]", x, lo=1) for i, x in enumerate(v)]


def points(name, v, k):
    """A list of control points, ``k`` numbers each."""
    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__"):
        raise TypeError(f"{name}: expected a list of {k}-number points")
    return [vector(f"{name}[{i}]", p, k) for i, p in enumerate(v)]


def path(name, v):
    """A file path, made absolute so it does not depend on the working directory later."""
    if not isinstance(v, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a path, got {type(v).__name__}")
    return os.path.abspath(os.fspath(v))


def file_or_column(name, v):
    """A file (made absolute) or a column name (no extension: left alone), as the CLI."""
    if not isinstance(v, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a file or column name, got {type(v).__name__}")
    v = os.fspath(v)
    return os.path.abspath(v) if os.path.splitext(v)[1] else v


def set_in(desc, dotted, value):
    """Sets ``desc[a][b] = value`` for ``dotted = "a.b"`` (None clears the key)."""
    *tables, key = dotted.split(".")
    for t in tables:
        desc = desc.setdefault(t, {})
    desc[key] = value


# ---- the view: camera, image, transfer function, render, light --------------

CAMERA_KEYS = ("eye", "look_at", "up", "fov", "projection", "ortho_height", "orbit", "elevation", "zoom")

#: View flags that set one key: flag → (scene key, converter).
SIMPLE = {
    "spp": ("image.spp", lambda n, v: integer(n, v, lo=1)),
    "eye": ("camera.eye", lambda n, v: vector(n, v, 3)),
    "look_at": ("camera.look_at", lambda n, v: vector(n, v, 3)),
    "up": ("camera.up", lambda n, v: vector(n, v, 3)),
    "fov": ("camera.fov", number),
    "orbit": ("camera.orbit", number),
    "elevation": ("camera.elevation", number),
    "zoom": ("camera.zoom", number),
    "value_range": ("transfer.value_range", lambda n, v: vector(n, v, 2)),
    "opacity_points": ("transfer.opacity_points", lambda n, v: points(n, v, 2)),
    "step": ("render.step", number),
    "sampling_rate": ("render.sampling_rate", number),
    "early_termination": ("render.early_termination", number),
    "opacity_scale": ("render.opacity_scale", number),
    "background": ("render.background", lambda n, v: vector(n, v, 3)),
    "seed": ("render.seed", lambda n, v: integer(n, v, lo=0)),
    "iso_opacity": ("render.iso_opacity", number),
    "log": ("render.log_scale", boolean),
    "packets": ("render.packets", boolean),
    "clip": ("render.clip", box),
    # Any light setting adds the [light] table, turning the light on (as the CLI).
    "light_dir": ("light.direction", lambda n, v: vector(n, v, 3)),
    "light_pos": ("light.position", lambda n, v: vector(n, v, 3)),
    "light_intensity": ("light.intensity", number),
    "ambient": ("light.ambient", number),
    "free_flight": ("light.free_flight", lambda n, v: choice(n, v, ("marching", "delta"))),
    "noise": ("light.noise", lambda n, v: choice(n, v, ("blue", "white"))),
    "shadows": ("light.shadows", boolean),
}

#: Flags with their own rules (see :func:`view`).
SPECIAL = (
    "size", "camera", "orthographic", "colormap", "colormap_file", "opacity", "linear", "iso",
    "iso_only", "no_packets", "shade",
)

VIEW_FLAGS = tuple(SIMPLE) + SPECIAL

#: Library setting names → the keyword they come from (for error messages).
FIELD_TO_FLAG = {
    "image size": "size", "image.spp": "spp", "camera": "camera", "camera.ortho_height": "orthographic",
    "camera.orbit": "orbit", "camera.elevation": "elevation", "camera.zoom": "zoom",
    "transfer.value_range": "value_range", "transfer.colormap_file": "colormap_file",
    "render.step": "step", "render.sampling_rate": "sampling_rate",
    "render.early_termination": "early_termination", "render.opacity_scale": "opacity_scale",
    "render.iso": "iso", "render.iso (--iso)": "iso", "render.iso_opacity": "iso_opacity",
    "render.clip": "clip", "light.direction": "light_dir", "light.ambient": "ambient",
    "light.shadows": "shadows", "light.position": "light_pos", "light.intensity": "light_intensity",
    "light (--shade)": "shade", "particles.species": "species", "amr": "cells",
}


def unknown(where, name, known):
    """The TypeError for an unknown keyword, with the closest known one."""
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return TypeError(f"{where}() got an unexpected keyword argument {name!r}{hint}")


def view(where, flags, desc=None):
    """The scene tables ``flags`` set, merged into ``desc`` (a new dict when None)."""
    d = {} if desc is None else desc
    for name, v in flags.items():
        if v is None:
            continue
        if name in SIMPLE:
            key, conv = SIMPLE[name]
            set_in(d, key, conv(name, v))
        elif name == "size":
            w, h = size(name, v)
            set_in(d, "image.width", w)
            set_in(d, "image.height", h)
        elif name == "camera":
            cam = v.to_dict() if hasattr(v, "to_dict") else v
            if not isinstance(cam, dict):
                raise TypeError(f"camera: expected a voxless.Camera or a dict, got {type(v).__name__}")
            for k in cam:
                if k not in CAMERA_KEYS:
                    raise unknown("Camera", k, CAMERA_KEYS)
            # A camera replaces the whole table: what it leaves unset is the default.
            d["camera"] = {k: cam.get(k) for k in CAMERA_KEYS}
        elif name == "orthographic":
            if v is True or v is False:
                set_in(d, "camera.projection", "orthographic" if v else "perspective")
            else:
                set_in(d, "camera.projection", "orthographic")
                set_in(d, "camera.ortho_height", number(name, v))
        elif name == "colormap":
            if isinstance(v, str):
                set_in(d, "transfer.colormap", v)
                set_in(d, "transfer.colormap_points", None)
                if "colormap_file" not in flags:
                    set_in(d, "transfer.colormap_file", None)
            else:
                set_in(d, "transfer.colormap_points", points(name, v, 4))
                set_in(d, "transfer.colormap", None)
                set_in(d, "transfer.colormap_file", None)
        elif name == "colormap_file":
            # The file replaces the colours; colormap= then picks a preset in it.
            set_in(d, "transfer.colormap_file", path(name, v))
            set_in(d, "transfer.colormap_points", None)
            if "colormap" not in flags:
                set_in(d, "transfer.colormap", None)
        elif name == "opacity":
            if isinstance(v, str):
                set_in(d, "transfer.opacity", v)
                set_in(d, "transfer.opacity_points", None)
            else:
                set_in(d, "transfer.opacity_points", points(name, v, 2))
                set_in(d, "transfer.opacity", None)
        elif name == "linear":
            set_in(d, "render.log_scale", not boolean(name, v))
        elif name == "iso":
            values = [v] if isinstance(v, (Real, np.number)) else v
            if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
                raise TypeError(f"iso: expected a number or a list of numbers, got {type(v).__name__}")
            set_in(d, "render.iso", [number(f"iso[{i}]", x) for i, x in enumerate(values)])
        elif name == "iso_only":
            set_in(d, "render.volume", not boolean(name, v))
        elif name == "no_packets":
            set_in(d, "render.packets", not boolean(name, v))
        elif name == "shade":
            if boolean(name, v):
                d.setdefault("light", {})
            else:
                d["light"] = None
        else:
            raise unknown(where, name, VIEW_FLAGS)
    return d


# ---- the data: what load() reads --------------------------------------------

PARTICLE_FLAGS = {
    "attribute": ("attribute", file_or_column),
    "radius": ("radius", number),
    "radii": ("radii", file_or_column),
    "weights": ("weights", file_or_column),
    "group": ("group", string),
    "part_type": ("part_type", lambda n, v: integer(n, v, lo=0)),
    "species": ("species", lambda n, v: str(v) if isinstance(v, (Integral, np.integer)) else string(n, v)),
    "kernel": ("kernel", lambda n, v: choice(n, v, KERNELS)),
    "kappa": ("kappa", number),
    "sigma": ("sigma", number),
    "cluster": ("cluster", lambda n, v: integer(n, v, lo=1)),
    "classification": ("classification", lambda n, v: choice(n, v, ("post", "pre"))),
    "attribute_range": ("attribute_range", lambda n, v: vector(n, v, 2)),
}
TET_FLAGS = {
    "lagrangian": ("lagrangian", lambda n, v: integer(n, v, lo=1)),
    "snapshot": ("snapshot", lambda n, v: integer(n, v, lo=0)),
    "box": ("box_size", number),
    "particle_mass": ("particle_mass", number),
    "tet_mode": ("mode", lambda n, v: choice(n, v, ("exact", "kbuffer"))),
    "k": ("k", lambda n, v: integer(n, v, lo=1)),
    "layers": ("layers", lambda n, v: integer(n, v, lo=1)),
    "lod": ("lod_pixels", number),
}
AMR_FLAGS = {
    "origin": ("origin", lambda n, v: vector(n, v, 3)),
    "cell_size": ("cell_size", number),
    "field": ("field", string),
    "color_field": ("color_field", string),
    "reconstruction": ("reconstruction", lambda n, v: choice(n, v, ("basis", "nearest"))),
}
KERNELS = ("gaussian3", "gaussian", "cubic-spline", "cubic", "m4")


def table(flags, spec):
    """The table ``spec`` makes of the ``flags`` it knows (converted)."""
    return {key: conv(name, flags[name]) for name, (key, conv) in spec.items() if flags.get(name) is not None}


def relabel(err):
    """A library error re-labelled with the keyword its setting came from:
    ``early_termination (render.early_termination): 2 is outside (0, 1]``."""
    field = getattr(err, "field", None)
    flag = FIELD_TO_FLAG.get(field) if field else None
    text = str(err)
    if flag is None or flag == field:
        return err
    rest = text[len(field) + 2 :] if text.startswith(field + ": ") else text
    new = VoxlessError(f"{flag} ({field}): {rest}")
    new.field = field
    return new
