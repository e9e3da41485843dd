"""Volumes: particles, AMR cells and tessellations from numpy arrays or files.

A :class:`Volume` is built once (a BVH over particles, bricks over AMR cells,
tets over a Lagrangian grid) and then rendered, projected and sampled as
often as you like, from several threads at once. Keyword arguments are the
``voxless`` CLI's flags with ``-`` as ``_``; every default (camera framing the
data, value range, step, …) is the library's, the same as the CLI's.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, fields
from typing import Optional, Sequence

import numpy as np

from . import _options as opt
from . import _voxless
from .image import Fields, Image, Projection, Slice

AXES = {"x": 0, "y": 1, "z": 2, 0: 0, 1: 1, 2: 2}


@dataclass
class Camera:
    """A camera, as the scene file's ``[camera]`` table (world coordinates).

    Unset fields take the library's defaults: the eye frames the data from
    the +z side, looking at its centre, with y up and a 30° field of view.
    ``projection`` is ``"perspective"`` or ``"orthographic"`` (then
    ``ortho_height`` is the view's world height); ``orbit`` and ``elevation``
    (degrees) and ``zoom`` act on the eye the rest gives.
    """

    eye: Optional[Sequence[float]] = None
    look_at: Optional[Sequence[float]] = None
    up: Optional[Sequence[float]] = None
    fov: Optional[float] = None
    projection: Optional[str] = None
    ortho_height: Optional[float] = None
    orbit: Optional[float] = None
    elevation: Optional[float] = None
    zoom: Optional[float] = None

    def to_dict(self):
        """The ``[camera]`` table (unset fields as None)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _call(fn, *args, **kwargs):
    """Calls the native module with the caller's working directory (relative paths are relative to it)."""
    return fn(*args, os.getcwd(), **kwargs)


def _array1(name, v, n, dtype=np.float32):
    """A 1-D array of ``n`` values (a scalar is repeated ``n`` times)."""
    if v is None:
        return None
    try:
        a = np.asarray(v, dtype=dtype)
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name}: expected numbers ({e})") from None
    if a.ndim == 0:
        a = np.full(n, a, dtype=dtype)
    if a.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D array of {n} values, got shape {a.shape}")
    if len(a) != n:
        raise ValueError(f"{name}: {len(a)} values for {n} positions")
    return np.ascontiguousarray(a)


def _positions(name, v):
    """An N×3 array: float32 stays float32, anything else becomes float64."""
    try:
        a = np.asarray(v)
        if a.dtype != np.float32:
            a = a.astype(np.float64)
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name}: expected an N×3 array of numbers ({e})") from None
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected an N×3 array, got shape {a.shape}")
    return np.ascontiguousarray(a)


class Volume:
    """One volume (particles, AMR cells or a phase-space tessellation).

    Make one with :class:`Particles`, :class:`AmrCells`, :class:`Tessellation`
    or :func:`load`. The keyword arguments given then (camera, colormap, …)
    are this volume's default view; each call can override them.
    """

    def __init__(self, native):
        self._native = native

    # ---- what the volume is ------------------------------------------------

    @property
    def kind(self) -> str:
        """``"particles"``, ``"AMR cells"``, ``"phase-space tessellation"`` or ``"multi-material particles"``."""
        return self._native.kind

    @property
    def bounds(self):
        """World bounds as ``(lo, hi)`` numpy arrays (float64)."""
        lo, hi = self._native.bounds
        return np.array(lo), np.array(hi)

    @property
    def origin(self):
        """World position of the volume's float32 coordinates' origin (float64 input is recentred on it)."""
        return np.array(self._native.origin)

    @property
    def scale(self):
        """World length of one unit of the float32 coordinates (a power of two; 1 for data of everyday extent)."""
        return self._native.scale

    @property
    def value_range(self):
        """The data's value range (the transfer function's default)."""
        return self._native.value_range

    @property
    def total_mass(self):
        """∫ field dV when the data kind knows it exactly (what a projection conserves), else None."""
        return self._native.total_mass

    @property
    def smoothing_lengths(self):
        """Each particle's radius parameter: float32, world units, in the input's row order.

        The smoothing length h of the SPH kernels (support 2h for the cubic
        spline), the support of ``gaussian3``, σ of ``gaussian`` — given as
        ``radii``/``radius``, estimated from the spacing, or found from the
        neighbours (``neighbours=N``: the support reaches the N-th nearest
        neighbour, periodic distances in a ``box``). Particle volumes only;
        others raise :class:`voxless.VoxlessError`.
        """
        return self._native.smoothing_lengths

    @property
    def notes(self):
        """Defaults chosen from the data (a radius from the particle spacing, …)."""
        return list(self._native.notes)

    @property
    def desc(self) -> dict:
        """The scene description this volume was made with (a dict like a TOML scene)."""
        return self._native.desc

    def columns(self, gradient=False):
        """The names of the columns :meth:`sample` returns."""
        return list(self._native.columns(gradient))

    def __repr__(self):
        lo, hi = self.bounds
        return f"<voxless.Volume {self.kind}, bounds {lo.tolist()}..{hi.tolist()}>"

    # ---- render, project, sample ----------------------------------------------

    def render(self, scene=None, **view) -> Image:
        """Renders the volume: an :class:`Image`, H×W×4 float32 premultiplied linear RGBA.

        ``scene`` is an optional dict of view tables (``camera``, ``image``,
        ``transfer``, ``render``, ``light``) as in a TOML scene; keywords are
        the CLI's render flags: ``size=(w, h)``, ``spp``, ``camera=Camera(…)``
        or ``eye``/``look_at``/``up``/``fov``/``orthographic=HEIGHT``/
        ``orbit``/``elevation``/``zoom``; ``colormap`` (a name or
        ``[[x, r, g, b], …]``), ``colormap_file``, ``opacity`` (a preset or
        ``[[x, a], …]``), ``value_range``, ``log``/``linear``; ``step``,
        ``sampling_rate``, ``early_termination``, ``opacity_scale``,
        ``background``, ``seed``, ``iso``, ``iso_opacity``, ``iso_only``,
        ``clip``, ``no_packets``; ``shade``, ``light_dir``, ``shadows``,
        ``light_pos``, ``light_intensity``, ``ambient``, ``free_flight``,
        ``noise``; ``device``: ``"cpu"`` (the default), ``"gpu"`` (the GPU
        backend: a package built with the ``gpu`` feature; an error naming
        what is missing otherwise) or ``"auto"`` (the GPU when there is one
        and it does the render, else the CPU, with a note). The GIL is
        released while it renders; Ctrl-C cancels it (``KeyboardInterrupt``).
        """
        device = view.pop("device", None)
        tables, flags = opt.split("render", view)
        rgba, background, notes = _call(
            self._native.render, opt.merge(_scene_view(scene), tables), flags, device=device
        )
        return Image.wrap(rgba, background=tuple(background), notes=notes)

    def project(
        self,
        size=None,
        axis=None,
        normal=None,
        north=None,
        center=None,
        width=None,
        bounds=None,
        depth=None,
        pixels=None,
        device=None,
    ) -> Projection:
        """Column density ∫ field dt per pixel: a :class:`Projection`, H×W float32, row 0 at the top.

        Along ``axis`` (``"x"``, ``"y"``, ``"z"``; the default) the image axes
        are (y, z), (x, z), (x, y) and the image covers ``bounds`` (``(lo,
        hi)`` or six numbers; default: the data's bounds); along ``normal``
        (off-axis) the image's up is ``north`` and it is centred on
        ``center`` and ``width`` (one number or ``(w, h)``) wide, by default
        covering the data. Every line is integrated through all the data, or
        over a slab ``depth`` thick centred on the image plane.
        ``Projection.mass()`` (``sum(pixels) * pixel_area``) equals the total
        mass when the image covers the data. ``pixels``: ``"centre"`` (the
        default: the column through each pixel's centre) or, for particles,
        ``"area"`` (the column averaged over each pixel, so kernels smaller
        than a pixel keep their mass too; not with ``depth``). ``device``:
        ``"cpu"`` (the default), ``"gpu"`` or ``"auto"``, as for
        :meth:`render` (particle splats are summed on the GPU).
        """
        flags = {} if size is None else opt.split("project", {"size": size})[1]
        plane = _plane(axis, normal, north, center, width, bounds, depth)
        column, geometry = self._native.project(flags, **plane, pixels=pixels, device=device)
        return Projection.wrap(column, geometry)

    def slice(
        self, size=None, axis=None, normal=None, north=None, center=None, width=None, quantity=None, pixels="centre"
    ) -> Slice:
        """The field on a plane: a :class:`Slice`, H×W float32, row 0 at the top.

        Exactly :meth:`sample` at the pixel centres (``pixels="area"``: the
        mean over each pixel's square by a 4×4 Gauss–Legendre rule). The
        geometry is :meth:`project`'s: the plane through ``center`` (default:
        the data's centre) across ``axis`` or ``normal`` (with ``north``),
        ``width`` wide. ``quantity`` is one of :meth:`columns` (``density``,
        ``attribute``, ``streams``, an AMR field; default density, or the AMR
        field the volume was made with). A plane beside the data raises.
        """
        flags = {} if size is None else opt.split("slice", {"size": size})[1]
        if axis is not None and (not isinstance(axis, (str, int)) or axis not in AXES):
            raise ValueError(f"axis: {axis!r} is not 'x', 'y' or 'z'")
        if pixels not in ("centre", "center", "area"):
            raise ValueError(f"pixels: {pixels!r} is not 'centre' or 'area'")
        if width is not None and np.ndim(width) == 0:
            width = (width, width)
        values, name, geometry = self._native.slice(
            flags,
            axis=None if axis is None else AXES[axis],
            normal=None if normal is None else opt.vector("normal", normal, 3),
            north=None if north is None else opt.vector("north", north, 3),
            center=None if center is None else opt.vector("center", center, 3),
            width=None if width is None else opt.vector("width", width, 2),
            quantity=None if quantity is None else str(quantity),
            area=pixels == "area",
        )
        return Slice.wrap(values, name, geometry)

    def movie(self, path, frames=None, camera_path=None, fps=24, quality=80, keep_frames=False, scene=None, **view):
        """Renders a camera path into a movie (``.mp4``, ``.webm`` or ``.gif``, through ffmpeg).

        ``camera_path`` is a list of keyframes, each a dict with ``frame``,
        ``eye``, ``look_at`` and optionally ``up``, ``fov``,
        ``orthographic`` (as ``[[camera.keyframes]]`` in a scene file; default:
        the scene's). ``frames`` is ``(first, last)`` (inclusive; default: the
        first to the last keyframe). The path is interpolated smoothly
        (positions through every keyframe, orientation by slerp); an
        interrupted movie resumes from its frames on disk (``PATH.frames/``).
        Other keywords are :meth:`render`'s. Returns the number of frames.
        """
        tables, flags = opt.split("render", view)
        tables = opt.merge(_scene_view(scene), tables)
        if camera_path is not None:
            keys = [dict(k) for k in camera_path]
            camera = dict(tables.get("camera", {}))
            camera["keyframes"] = keys
            tables["camera"] = camera
        keys = tables.get("camera", {}).get("keyframes")
        if frames is None:
            if not keys:
                raise ValueError("movie: give camera_path (two or more keyframes) or frames=(first, last)")
            frames = (int(keys[0]["frame"]), int(np.ceil(keys[-1]["frame"])))
        first, last = (int(f) for f in frames)
        n, _, notes = self._native.movie(
            tables,
            flags,
            os.getcwd(),
            os.fspath(path),
            first,
            last,
            fps=float(fps),
            quality=int(quality),
            keep_frames=bool(keep_frames),
        )
        return n

    def sample(self, points, gradient=False) -> Fields:
        """The fields at world ``points`` (N×3): :class:`Fields`, N×k float32 with ``.columns``.

        Particles: density, [attribute], [∂/∂x, ∂/∂y, ∂/∂z of the density with
        ``gradient``]; AMR: every field, then their gradients; tessellations:
        density and stream count. Rows outside AMR data are NaN.
        """
        p = _positions("points", points).astype(np.float64, copy=False)
        values, columns = self._native.sample(p, opt.boolean("gradient", gradient))
        return Fields.wrap(values, columns)

    def describe(self, scene=None, **view) -> dict:
        """What a render with this view would use: size, camera, value range, scale, notes."""
        tables, flags = opt.split("describe", view)
        return _call(self._native.describe, opt.merge(_scene_view(scene), tables), flags)


def _scene_view(scene):
    if scene is None:
        return {}
    if not isinstance(scene, dict):
        raise TypeError(f"scene: expected a dict of scene tables, got {type(scene).__name__}")
    return {k: (dict(v) if isinstance(v, dict) else v) for k, v in scene.items()}


class Particles(Volume):
    """Particles from arrays.

    ``positions`` N×3: float32 is used as it is; float64 (or any other
    numeric type) is recentred on its bounding box's centre in float64
    before it becomes float32, so data far from the origin keeps its digits.
    ``radii``, ``weights`` (masses for the SPH kernels), ``attribute``
    (colour) and ``types`` (species numbers) are per-particle arrays of N
    values (a scalar is repeated). Data flags: ``radius`` (one radius; the
    default is estimated from the spacing), ``kernel`` (``"gaussian3"``,
    ``"gaussian"``, or an SPH kernel with radius h: ``"cubic-spline"`` and
    ``"wendland-c2"``/``"-c4"``/``"-c6"`` with support 2h,
    ``"quartic-spline"`` 2.5h, ``"quintic-spline"`` 3h), ``kappa``,
    ``sigma``, ``cluster``, ``classification``, ``attribute_range``,
    ``species`` (keep only these ``types``); ``box`` a periodic box, its
    side ``L`` (the box ``[0, L)³``) or its corners (six numbers ``x0, y0,
    z0, x1, y1, z1`` or ``(lo, hi)``): the field then sums every periodic
    image, and positions just outside the box are wrapped in (``wrap=True``
    wraps data spanning more than one box); ``neighbours`` N: radii from
    the neighbours, each particle's support reaching its N-th nearest
    neighbour (itself counted; periodic distances in a ``box``; instead of
    ``radii``/``radius``; see :attr:`Volume.smoothing_lengths`);
    ``materials`` a list of ``[[particles.materials]]`` tables. Any other
    keyword is a view flag (see :meth:`Volume.render`): this volume's
    default view.
    """

    def __init__(self, positions, radii=None, weights=None, attribute=None, types=None, *, materials=None, **kwargs):
        tables, flags = opt.split("Particles", kwargs, opt.CONSTRUCTOR_FLAGS["Particles"])
        p = _positions("positions", positions)
        n = len(p)
        if materials is not None:
            tables["particles"] = {"materials": materials}
        native = _call(
            _voxless.particles,
            p,
            _array1("radii", radii, n),
            _array1("weights", weights, n),
            _array1("attribute", attribute, n),
            _array1("types", types, n),
            tables,
            flags,
        )
        super().__init__(native)


class AmrCells(Volume):
    """Block-structured AMR leaf cells from arrays.

    ``cells`` N×4 integers ``(x, y, z, level)``: the lower corner in
    finest-cell units and the level (0 finest, width 2^level); ``fields`` a
    dict of name → N values (one array: the field ``"value"``); ``origin``
    the world position of cell coordinate 0 (float64); ``cell_size`` the
    world width of a finest cell. Data flags: ``field`` (opacity, default the
    first), ``color_field``, ``reconstruction`` (``"basis"``,
    ``"nearest"`` or ``"octant"``). Other keywords are view flags.
    """

    def __init__(self, cells, fields, origin=(0.0, 0.0, 0.0), cell_size=1.0, **kwargs):
        tables, flags = opt.split("AmrCells", kwargs, opt.CONSTRUCTOR_FLAGS["AmrCells"])
        try:
            c = np.asarray(cells)
        except (TypeError, ValueError) as e:
            raise TypeError(f"cells: expected an N×4 integer array ({e})") from None
        if c.ndim != 2 or c.shape[1] != 4:
            raise ValueError(f"cells: expected an N×4 array (x, y, z, level), got shape {c.shape}")
        if not np.issubdtype(c.dtype, np.integer):
            raise TypeError(f"cells: expected integers, got {c.dtype}")
        if c.size and (c.min() < np.iinfo(np.int32).min or c.max() > np.iinfo(np.int32).max):
            raise ValueError("cells: coordinates outside the int32 range")
        c = np.ascontiguousarray(c, dtype=np.int32)
        if isinstance(fields, np.ndarray) or not hasattr(fields, "items"):
            fields = {"value": fields}
        if not fields:
            raise ValueError("fields: give at least one field")
        for k in fields:
            if not isinstance(k, str):
                raise TypeError(f"fields: names must be strings, got {type(k).__name__}")
        named = [(k, _array1(f"fields[{k!r}]", v, len(c))) for k, v in fields.items()]
        native = _call(
            _voxless.amr,
            c,
            named,
            opt.vector("origin", origin, 3),
            opt.number("cell_size", cell_size),
            tables,
            flags,
        )
        super().__init__(native)


class Tessellation(Volume):
    """The phase-space tessellation of N-body particles on a Lagrangian grid.

    ``positions`` N³×3 in Lagrangian order (``(i·N + j)·N + k``, k fastest)
    in the periodic box ``[0, box)³``; ``n`` = N (default: the cube root of
    the count). Data flags: ``particle_mass`` (default: total mass 1),
    ``tet_mode`` (``"exact"`` or ``"kbuffer"``), ``k``, ``layers``, ``lod``.
    Other keywords are view flags.
    """

    def __init__(self, positions, n=None, box=None, **kwargs):
        tables, flags = opt.split("Tessellation", kwargs, opt.CONSTRUCTOR_FLAGS["Tessellation"])
        p = np.ascontiguousarray(_positions("positions", positions), dtype=np.float32)
        if n is None:
            n = round(len(p) ** (1 / 3))
        n = opt.integer("n", n, lo=1)
        if box is None:
            raise TypeError("Tessellation() needs box=L, the periodic box size")
        native = _call(_voxless.tessellation, p, n, opt.number("box", box), tables, flags)
        super().__init__(native)


def load(source=None, *, frame=0, **kwargs) -> Volume:
    """Loads data the CLI reads: a file, a TOML scene file, or a scene dict.

    ``source`` is a particle file (``.npy``, CSV, VTK, XYZ, LAMMPS dump,
    ``.particles``; HDF5 when built with the ``hdf5`` feature), AMR output
    (an AMReX plotfile directory, an AMRClaw ``fort.qNNNN``, a ``.cells``
    file with ``scalars=[…]``; with ``hdf5``: FLASH, an Enzo parameter file,
    Athena++ ``.athdf``), N-body positions
    with ``lagrangian=N`` and ``box=L`` (a tessellation), a ``.toml`` scene,
    or a scene dict. Keywords are the CLI's flags (``attribute="speed"``,
    ``radii="h.npy"``, ``kernel=…``, ``amr=``, ``cells=``, ``scalars=``, ``amrclaw=``,
    …) applied over the scene as on the command line; view flags become the
    volume's default view. For particles, ``box`` (a side ``L`` or the
    corners) makes the box periodic (default: the box the file states as
    periodic — SWIFT/Gadget ``BoxSize``, LAMMPS ``pp`` bounds, extended-XYZ
    ``Lattice`` with ``pbc``; ``no_box=True`` ignores it), ``wrap=True``
    wraps data spanning more than one box, and ``neighbours=N`` sizes each
    particle's kernel to reach its N-th nearest neighbour (the default for
    snapshot particle types without smoothing lengths: 32). ``frame`` picks
    a frame of a time series.
    """
    tables, flags, base = _source("load", source, kwargs)
    frame = opt.integer("frame", frame, lo=0)
    return Volume(_call(_voxless.load, tables, flags, base, frame=frame))


def _source(where, source, kwargs):
    """``source`` (a file, a ``.toml`` scene or a scene dict) and the keyword
    flags as ``(tables, flags, base)``, ``base`` the directory the scene's
    paths are relative to."""
    tables, base = {}, os.getcwd()
    if isinstance(source, dict):
        tables = source
        source = None
    elif source is not None and os.fspath(source).endswith(".toml"):
        scene = os.path.abspath(opt.path("source", source))
        tables = _voxless.read_scene(scene)
        base = os.path.dirname(scene)
        source = None
    sugar, flags = opt.split(where, kwargs, opt.DATA_FLAGS)
    if source is not None:
        key = _voxless.data_flag_for(os.fspath(opt.path("source", source)))
        if key in flags:
            raise TypeError(f"{where}() got the data twice: source and {key}=")
        flags[key] = os.fspath(source)
    return opt.merge(tables, sugar), flags, base


def project(
    source=None,
    *,
    frame=0,
    axis=None,
    normal=None,
    north=None,
    center=None,
    width=None,
    bounds=None,
    depth=None,
    pixels=None,
    device=None,
    **kwargs,
) -> Projection:
    """Projects ``source`` (see :func:`load`) without building a volume: a :class:`Projection`.

    Particles whose files are read by row range (``.npy``; Gadget binary,
    Tipsy and HDF5 snapshots) with known radii (a ``radius``, ``radii``, or
    the snapshot's smoothing lengths) are streamed from the files in chunks
    and splatted, so memory holds the image and a chunk whatever the number
    of particles (``geometry["chunks"]`` says how many); any other data is
    loaded and projected as ``load(source, ...).project(...)``. The image is
    the CLI's ``voxless project`` one. The projection arguments are
    :meth:`Volume.project`'s (``size`` among the keywords); the other
    keywords are :func:`load`'s.

    >>> import numpy as np, voxless
    >>> np.save("pos.npy", np.random.default_rng(1).random((100_000, 3), np.float32))
    >>> p = voxless.project("pos.npy", radius=0.01, box=1, axis="z", size=(256, 256))
    >>> p.shape, p.chunks, round(p.mass() / p.total_mass, 3)
    ((256, 256), 2, 1.0)
    """
    tables, flags, base = _source("project", source, kwargs)
    frame = opt.integer("frame", frame, lo=0)
    plane = _plane(axis, normal, north, center, width, bounds, depth)
    column, geometry = _call(
        _voxless.project_file, tables, flags, base, frame=frame, **plane, pixels=pixels, device=device
    )
    return Projection.wrap(column, geometry)


def _plane(axis, normal, north, center, width, bounds, depth):
    """A projection's plane and slab as the native module takes them (checked)."""
    if axis is not None and (not isinstance(axis, (str, int)) or axis not in AXES):
        raise ValueError(f"axis: {axis!r} is not 'x', 'y' or 'z'")
    if width is not None and np.ndim(width) == 0:
        width = (width, width)
    return dict(
        axis=None if axis is None else AXES[axis],
        normal=None if normal is None else opt.vector("normal", normal, 3),
        north=None if north is None else opt.vector("north", north, 3),
        center=None if center is None else opt.vector("center", center, 3),
        width=None if width is None else opt.vector("width", width, 2),
        bounds=None if bounds is None else opt.box("bounds", bounds),
        depth=None if depth is None else opt.number("depth", depth),
    )


def render(source=None, *, frame=0, **kwargs) -> Image:
    """Loads ``source`` (see :func:`load`: a file, a ``.toml`` scene or a scene dict) and renders it."""
    return load(source, frame=frame, **kwargs).render()
