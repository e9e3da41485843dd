"""voxless for yt data sets: ``off_axis_projection`` with yt's signature, and ``VoxlessSource`` for yt scenes.

Imported on first use (``voxless.yt``), so ``import voxless`` never imports yt.

**SPH particle data sets** (``ds._sph_ptypes``, e.g. ``yt.load_particles`` with
smoothing lengths, Gadget, SWIFT): yt's ``smoothing_length`` is the kernel's
full support; voxless's cubic-spline radius is h with support 2h, so each
particle becomes a voxless particle of radius ``smoothing_length / 2``. The
column of a field A is Σⱼ (mⱼ/ρⱼ) Aⱼ ∫ W dl — yt's SPH projection, with
voxless's exact chord integrals of the M4 kernel (yt tabulates them) — so a
particle's weight is ``m/ρ·A`` (negative weights are projected apart and
subtracted). As in yt, periodic coordinates are wrapped about the centre and
``depth`` keeps the particles whose centres lie within ``depth/2`` of the
image plane (all of them by default).

**AMR data sets** (grids or octs): the leaf cells from the data source's
``index`` fields (``x``, ``y``, ``z``, ``dx``, …; covered coarse cells are not
among them) become voxless AMR cells, integrated cell by cell
(``reconstruction="nearest"``, as yt's ``interpolated=False``) over the slab
``width[2]`` thick centred on ``center``, as yt's plane-parallel projection.

Images are yt's: ``ImageArray`` indexed ``[x, y]`` (the first index runs
east, the second north), in the field's units times yt's length unit.
"""

from __future__ import annotations

import numpy as np
from yt.data_objects.image_array import ImageArray
from yt.units.unit_object import Unit
from yt.visualization.volume_rendering.render_source import RenderSource
from yt.visualization.volume_rendering.utils import data_source_or_all

import voxless

__all__ = ["VoxlessSource", "off_axis_projection", "volume"]


def _code(ds, value, name, unit="code_length", n=None):
    """``value`` (a number, a sequence, a unyt array or a ``(value, unit)`` tuple) in code units, float64."""
    if isinstance(value, tuple) and len(value) == 2 and isinstance(value[1], str):
        value = ds.arr(value[0], value[1])
    if hasattr(value, "units"):
        v = np.asarray(value.to(unit).d, dtype=np.float64)
    else:
        try:
            v = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name}: expected numbers or a unyt quantity, got {type(value).__name__}") from None
    if n is not None:
        if v.ndim == 0:
            v = np.full(n, float(v))
        if v.shape != (n,):
            raise ValueError(f"{name}: expected {n} values, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: {v} has a non-finite value")
    return v


def _resolution(resolution):
    if np.ndim(resolution) == 0:
        resolution = (resolution, resolution)
    if len(resolution) != 2:
        raise ValueError(f"resolution: expected one number or (nx, ny), got {resolution!r}")
    return tuple(voxless._options.integer(f"resolution[{i}]", int(r) if float(r).is_integer() else r, lo=1)
                 for i, r in enumerate(resolution))


def _yt_north(normal):
    """yt's default north for ``off_axis_projection`` (the library's default too)."""
    return np.asarray(voxless.default_north(tuple(normal)))


def _is_sph(ds):
    return bool(getattr(ds, "_sph_ptypes", ()))


def _sph_ptype(data_source, item):
    """The particle type and position fields yt's off_axis_projection would use for ``item``."""
    ds = data_source.ds
    sph = ds._sph_ptypes
    fi = ds.field_info[item]
    ptype, ppos = sph[0], [f"particle_position_{a}" for a in "xyz"]
    ok = True
    if item[0] in ds.known_filters:
        ok = item[0] in sph
        ptype, ppos = item[0], ["x", "y", "z"]
    elif fi.is_alias:
        ok = fi.alias_name[0] in sph
        if item[0] != "gas":
            ptype = item[0]
    else:
        ok = fi.name[0] in sph or fi.name[0] == "gas"
    if not ok:
        raise ValueError(f"item: {item!r} is not a field of the SPH particles ({', '.join(sph)})")
    return ptype, ppos


def _particles(data_source, ptype, ppos, center=None):
    """Positions (code length, relative to ``center`` and wrapped where periodic), masses, densities, h."""
    ds = data_source.ds
    pos = np.column_stack([data_source[ptype, p].to("code_length").d for p in ppos]).astype(np.float64)
    mass = data_source[ptype, "mass"].to("code_mass").d
    dens = data_source[ptype, "density"].to("code_density").d
    hsml = data_source[ptype, "smoothing_length"].to("code_length").d
    if center is not None:
        pos -= center
        le = ds.domain_left_edge.to("code_length").d
        re = ds.domain_right_edge.to("code_length").d
        for a, periodic in enumerate(ds.periodicity):
            if periodic:
                # The nearest periodic image of every particle, as yt does.
                period = re[a] - le[a]
                pos[pos[:, a] < -0.5 * period, a] += period
                pos[pos[:, a] > 0.5 * period, a] -= period
    return pos, mass, dens, hsml


def _project_signed(pos, h, w, **view):
    """Σ w W through every pixel (voxless weights are ≥ 0: the negative part apart)."""
    keep = h > 0

    def one(weights):
        vol = voxless.Particles(pos[keep], radii=h[keep] / 2, weights=weights[keep], kernel="cubic-spline")
        return np.asarray(vol.project(**view), dtype=np.float64)

    if not np.any(keep):
        return np.zeros((view["size"][1], view["size"][0]))
    if np.all(w[keep] >= 0):
        return one(w)
    return one(np.maximum(w, 0)) - one(np.maximum(-w, 0))


def _leaf_cells(data_source):
    """Leaf cells of an AMR data source as voxless cells: (cells N×4, origin, finest cell size)."""
    ds = data_source.ds
    x = np.column_stack([data_source["index", a].to("code_length").d for a in "xyz"])
    d = np.column_stack([data_source["index", "d" + a].to("code_length").d for a in "xyz"])
    if len(x) == 0:
        raise ValueError("data_source: it holds no cells")
    if not (np.allclose(d[:, 0], d[:, 1], rtol=1e-6) and np.allclose(d[:, 0], d[:, 2], rtol=1e-6)):
        raise ValueError("data_source: voxless AMR cells are cubes; this data set's cells are not")
    h = d[:, 0]
    finest = h.min()
    level = np.rint(np.log2(h / finest)).astype(np.int64)
    if not np.allclose(finest * 2.0**level, h, rtol=1e-6):
        raise ValueError("data_source: cell widths are not the finest width times powers of two")
    origin = ds.domain_left_edge.to("code_length").d.astype(np.float64)
    corner = (x - 0.5 * d - origin) / finest
    ijk = np.rint(corner).astype(np.int64)
    if not np.allclose(ijk, corner, atol=1e-4):
        raise ValueError("data_source: cells are not aligned to the finest lattice")
    return np.column_stack([ijk, level]).astype(np.int32), origin, finest


def volume(data_source, field=("gas", "density"), **kwargs):
    """A :class:`voxless.Volume` of a yt data source, for :class:`VoxlessSource` or your own renders.

    SPH particles: density Σ m W (cubic spline, radius = smoothing_length / 2)
    with the particles' ``field`` as the colour attribute when it is not the
    density; a data set periodic along every axis gives a periodic volume
    (its domain is the box; pass ``box=`` to override). AMR: the leaf cells with ``field`` (basis reconstruction unless
    ``reconstruction="nearest"``). Keywords go to the voxless constructor.
    """
    data_source = data_source_or_all(data_source)
    ds = data_source.ds
    field = data_source._determine_fields([field])[0]
    if _is_sph(ds):
        ptype, ppos = _sph_ptype(data_source, field)
        pos, mass, _, hsml = _particles(data_source, ptype, ppos)
        attribute = None
        if field[1] != "density":
            attribute = data_source[field].d
        keep = hsml > 0
        if all(ds.periodicity) and "box" not in kwargs:
            # A periodic data set: the field sums every periodic image.
            le = ds.domain_left_edge.to("code_length").d
            re = ds.domain_right_edge.to("code_length").d
            kwargs["box"] = [*map(float, le), *map(float, re)]
        return voxless.Particles(
            pos[keep],
            radii=hsml[keep] / 2,
            weights=mass[keep],
            attribute=None if attribute is None else attribute[keep],
            kernel="cubic-spline",
            **kwargs,
        )
    cells, origin, finest = _leaf_cells(data_source)
    values = data_source[field].d
    return voxless.AmrCells(cells, {field[1]: values}, origin=origin, cell_size=finest, **kwargs)


def off_axis_projection(
    data_source,
    center,
    normal_vector,
    width,
    resolution,
    item,
    weight=None,
    volume=None,
    no_ghost=False,
    interpolated=False,
    north_vector=None,
    depth=None,
    num_threads=1,
    method="integrate",
):
    """yt's ``off_axis_projection`` computed by voxless (see the module docs): same arguments, same result.

    Returns an ``ImageArray`` of shape ``resolution`` indexed ``[x, y]``, in
    the field's units times yt's length unit (the weighted average's units
    with ``weight``). ``volume``, ``no_ghost`` and ``num_threads`` are
    accepted for compatibility and not used (voxless uses every core);
    ``interpolated=True`` and ``method="sum"`` are not supported, as in yt's
    SPH projections. A ``north_vector`` is made perpendicular to the normal
    (the image's up is its component across the view); yt's SPH projection
    equals this only for a perpendicular north (for others it turns the view
    away from ``normal_vector``).
    """
    if method != "integrate":
        raise NotImplementedError("method: voxless.yt.off_axis_projection integrates ('integrate')")
    if interpolated:
        raise NotImplementedError("interpolated: only interpolated=False is implemented, as in yt")
    data_source = data_source_or_all(data_source)
    ds = data_source.ds
    item = data_source._determine_fields([item])[0]
    if weight is not None:
        weight = data_source._determine_fields([weight])[0]
    center = _code(ds, center, "center", n=3)
    normal = _code(ds, normal_vector, "normal_vector", unit="dimensionless", n=3) if not hasattr(
        normal_vector, "units") else np.asarray(normal_vector, dtype=np.float64)
    if not np.linalg.norm(normal) > 0:
        raise ValueError("normal_vector: must not be zero")
    normal = normal / np.linalg.norm(normal)
    north = _yt_north(normal) if north_vector is None else np.asarray(north_vector, dtype=np.float64)
    width3 = _code(ds, width, "width", n=3)
    nx, ny = _resolution(resolution)
    length = ds.quan(1, "code_length").to(ds.unit_system["length"]).d
    view = dict(size=(nx, ny), normal=normal, north=north, width=(width3[0], width3[1]))

    if _is_sph(ds):
        ptype, ppos = _sph_ptype(data_source, item)
        pos, mass, dens, hsml = _particles(data_source, ptype, ppos, center)
        if depth is not None:
            # yt keeps the particles whose centres lie in the slab.
            half = 0.5 * float(_code(ds, depth, "depth"))
            along = pos @ normal
            sel = (along >= -half) & (along <= half)
            pos, mass, dens, hsml = pos[sel], mass[sel], dens[sel], hsml[sel]
            data_mask = sel
        else:
            data_mask = slice(None)
        finfo = ds.field_info[item]
        q = data_source[item].in_units(finfo.output_units).d[data_mask]
        volume_per_particle = mass / dens
        view.update(center=(0.0, 0.0, 0.0))
        if weight is None:
            image = _project_signed(pos, hsml, volume_per_particle * q, **view) * length
            units = Unit(finfo.units, registry=ds.unit_registry) * Unit(ds.unit_system["length"], registry=ds.unit_registry)
        else:
            w = data_source[weight].in_units(ds.field_info[weight].output_units).d[data_mask]
            num = _project_signed(pos, hsml, volume_per_particle * q * w, **view)
            den = _project_signed(pos, hsml, volume_per_particle * w, **view)
            image = np.divide(num, den, out=np.zeros_like(num), where=den != 0)
            units = Unit(finfo.units, registry=ds.unit_registry)
        kind = "SPH smoothed projection (voxless)"
    else:
        cells, origin, finest = _leaf_cells(data_source)
        values = data_source[item].d.astype(np.float64)
        view.update(center=center, depth=width3[2])

        def column(v):
            vol = voxless.AmrCells(cells, {"f": v}, origin=origin, cell_size=finest, reconstruction="nearest")
            return np.asarray(vol.project(**view), dtype=np.float64)

        item_units = Unit(ds._get_field_info(item).units, registry=ds.unit_registry)
        if weight is None:
            image = column(values) * length
            units = item_units * Unit(ds.unit_system["length"], registry=ds.unit_registry)
        else:
            w = data_source[weight].d.astype(np.float64)
            num, den = column(values * w), column(w)
            image = np.divide(num, den, out=np.zeros_like(num), where=den != 0)
            units = item_units
        kind = "AMR cell projection (voxless)"

    # voxless rows run north to south, columns west to east; yt indexes [x, y].
    buf = np.ascontiguousarray(image[::-1, :].T)
    east = np.cross(north, normal)
    info = {
        "field": item,
        "east_vector": east,
        "north_vector": north_vector,
        "normal_vector": normal_vector,
        "width": width,
        "depth": depth,
        "units": units,
        "type": kind,
    }
    return ImageArray(buf, units, registry=ds.unit_registry, info=info)


class VoxlessSource(RenderSource):
    """A voxless volume in a yt ``Scene``, next to yt's own sources.

    ``source`` is a :class:`voxless.Volume`, or a yt data source (then
    ``field`` picks the field, see :func:`volume`). ``view`` keywords are
    voxless render flags (``colormap``, ``opacity``, ``value_range``, ``log``,
    ``spp``, ``shade``, …). The scene's camera (position, focus, north,
    width, resolution; plane-parallel or perspective lens) becomes voxless's
    camera, and the render is composited over what the scene's sources
    before it drew (premultiplied "over"; the depth of opaque sources is
    not used).
    """

    def __init__(self, source, field=("gas", "density"), **view):
        super().__init__()
        if isinstance(source, voxless.Volume):
            self.volume, self.data_source, self.field = source, None, None
        else:
            self.data_source = data_source_or_all(source)
            self.field = self.data_source._determine_fields([field])[0]
            self.volume = volume(self.data_source, self.field)
        self.view = view
        self.current_image = None

    def _validate(self):
        if not isinstance(self.volume, voxless.Volume):
            raise TypeError("VoxlessSource: the volume must be a voxless.Volume")

    def camera_view(self, camera):
        """The voxless render keywords for a yt camera."""
        res = tuple(int(r) for r in camera.resolution)
        focus = camera.focus.to("code_length").d
        position = camera.position.to("code_length").d
        width = camera.width.to("code_length").d
        east, north, normal = (np.asarray(v, dtype=np.float64) for v in camera.unit_vectors)
        lens = type(camera.lens).__name__
        if lens == "PlaneParallelLens":
            cam = voxless.Camera(eye=focus - normal * width[2], look_at=focus, up=north,
                                 projection="orthographic", ortho_height=width[1])
            # yt's pixels cover width[0] × width[1]; voxless's are square: the
            # image's width follows from its height (resampled to yt's
            # resolution in render).
            size = (max(1, int(round(res[1] * width[0] / width[1]))), res[1])
        elif lens == "PerspectiveLens":
            # yt's perspective pixels are square, width[0] across at distance
            # width[2] from the eye.
            height = width[0] * res[1] / res[0]
            fov = float(np.degrees(2 * np.arctan(0.5 * height / width[2])))
            cam = voxless.Camera(eye=position, look_at=position + normal, up=north, fov=fov)
            size = res
        else:
            raise NotImplementedError(f"VoxlessSource: the {lens} is not supported (plane-parallel or perspective)")
        return dict(self.view, size=size, camera=cam)

    def render(self, camera, zbuffer=None):
        """Renders through ``camera`` and composites over ``zbuffer``'s image (yt's [east, north] layout)."""
        self._validate()
        img = np.asarray(self.volume.render(**self.camera_view(camera)), dtype=np.float64)
        nx = int(camera.resolution[0])
        if img.shape[1] != nx:
            # yt's pixels are not square here: resample the columns linearly.
            x = np.clip((np.arange(nx) + 0.5) * img.shape[1] / nx - 0.5, 0, img.shape[1] - 1)
            i0 = np.floor(x).astype(int)
            i1 = np.minimum(i0 + 1, img.shape[1] - 1)
            t = (x - i0)[None, :, None]
            img = img[:, i0] * (1 - t) + img[:, i1] * t
        # voxless: rows north → south, columns west → east; yt's scene image
        # is indexed [i, j] along (−east, −north) (it turns the image by 180°
        # when it saves it). Checked against yt's PointSource in the tests.
        ours = img.transpose(1, 0, 2)[::-1, ::-1, :]
        if zbuffer is not None and zbuffer.rgba.shape == ours.shape:
            behind = np.asarray(zbuffer.rgba, dtype=np.float64)
            ours = ours + (1.0 - ours[..., 3:4]) * behind
        self.current_image = ImageArray(ours, info={"imtype": "rendering"})
        if zbuffer is not None:
            zbuffer.rgba = self.current_image
        self.zbuffer = zbuffer
        return self.current_image

    def __repr__(self):
        return f"<VoxlessSource {self.volume!r}>"
