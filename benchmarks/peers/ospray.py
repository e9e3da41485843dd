"""A small ctypes binding to the OSPRay 3.x C API (the libraries that the
`ovito` wheel bundles) and the two scenes the benchmark renders with it: an
Open VKL `particle` volume and an `amr` volume, both through the `scivis`
renderer.

Enum values are OSPRay 3's `OSPEnums.h`; the shared libraries carry an
$ORIGIN rpath, so loading `libospray.so.3` by full path is enough and
`ospLoadModule("cpu")` finds `libospray_module_cpu.so.<version>` beside it.
"""

import ctypes as C
import glob
import os
import time

import numpy as np

# OSPDataType (OSPEnums.h, OSPRay 2/3)
OSP_BOOL = 250
OSP_DATA = 0x8000000 + 100
OSP_INSTANCE = 0x8000000 + 108
OSP_VOLUMETRIC_MODEL = 0x8000000 + 115
OSP_STRING = 1500
OSP_UCHAR = 2500
OSP_INT = 4000
OSP_VEC2I, OSP_VEC3I = 4001, 4002
OSP_FLOAT = 6000
OSP_VEC2F, OSP_VEC3F, OSP_VEC4F = 6001, 6002, 6003
OSP_BOX3I = 8002
OSP_BOX1F = 10000
# OSPFrameBufferFormat / channels
OSP_FB_SRGBA = 2
OSP_FB_RGBA32F = 3
OSP_FB_COLOR = 1
# OSPAMRMethod
OSP_AMR_CURRENT, OSP_AMR_FINEST, OSP_AMR_OCTANT = 0, 1, 2

_NUMPY_TYPES = {  # (dtype, components) -> OSPDataType
    ("float32", 1): OSP_FLOAT,
    ("float32", 3): OSP_VEC3F,
    ("float32", 4): OSP_VEC4F,
    ("int32", 1): OSP_INT,
    ("int32", 6): OSP_BOX3I,  # box3i = (lower xyz, upper xyz), inclusive
}


def find_library(hint=None):
    """libospray.so.3: OSPRAY_LIB, then the ovito wheel of this interpreter."""
    cands = [hint, os.environ.get("OSPRAY_LIB")]
    try:
        import ovito  # noqa: F401  (only to locate the wheel)

        base = os.path.dirname(ovito.__file__)
        cands += glob.glob(os.path.join(base, "**", "libospray.so.3*"), recursive=True)
    except Exception:
        pass
    for c in cands:
        if c and os.path.exists(c) and "module" not in os.path.basename(c):
            return c
    raise RuntimeError("libospray.so.3 not found: pip install ovito (it bundles OSPRay 3) "
                       "or set OSPRAY_LIB")


def version():
    """OSPRay version string, from the module file name beside libospray."""
    lib = find_library()
    mods = glob.glob(os.path.join(os.path.dirname(lib), "libospray_module_cpu.so.*"))
    return mods[0].rsplit(".so.", 1)[1] if mods else "3.x"


class OSPRay:
    """The library, initialised once per process with a thread count."""

    def __init__(self, threads, lib_path=None):
        os.environ["OSPRAY_NUM_THREADS"] = str(threads)
        lib = C.CDLL(find_library(lib_path), mode=C.RTLD_GLOBAL)
        P, I, U64, I64, F = C.c_void_p, C.c_int, C.c_uint64, C.c_int64, C.c_float
        sigs = {
            "ospInit": (I, [P, P]),
            "ospLoadModule": (I, [C.c_char_p]),
            "ospNewDevice": (P, [C.c_char_p]),
            "ospDeviceSetParam": (None, [P, C.c_char_p, I, P]),
            "ospDeviceCommit": (None, [P]),
            "ospSetCurrentDevice": (None, [P]),
            "ospDeviceGetLastErrorMsg": (C.c_char_p, [P]),
            # OSPRay 3 added a deleter callback and its user pointer (NULL here).
            "ospNewSharedData": (P, [P, I, U64, I64, U64, I64, U64, I64, P, P]),
            "ospNewData": (P, [I, U64, U64, U64]),
            "ospCopyData": (None, [P, P, U64, U64, U64]),
            "ospNewVolume": (P, [C.c_char_p]),
            "ospNewVolumetricModel": (P, [P]),
            "ospNewTransferFunction": (P, [C.c_char_p]),
            "ospNewGroup": (P, []),
            "ospNewInstance": (P, [P]),
            "ospNewWorld": (P, []),
            "ospNewCamera": (P, [C.c_char_p]),
            "ospNewRenderer": (P, [C.c_char_p]),
            "ospNewFrameBuffer": (P, [I, I, I, C.c_uint32]),
            "ospSetParam": (None, [P, C.c_char_p, I, P]),
            "ospSetObject": (None, [P, C.c_char_p, P]),
            "ospCommit": (None, [P]),
            "ospRelease": (None, [P]),
            "ospRenderFrameBlocking": (F, [P, P, P, P]),
            "ospMapFrameBuffer": (P, [P, I]),
            "ospUnmapFrameBuffer": (None, [P, P]),
            "ospShutdown": (None, []),
        }
        for name, (res, args) in sigs.items():
            fn = getattr(lib, name)
            fn.restype, fn.argtypes = res, args
        self.lib = lib
        self._keep = []  # numpy buffers OSPRay may still point at
        # The device type lives in a module; it must be loaded before ospNewDevice.
        if lib.ospLoadModule(b"cpu") != 0:
            raise RuntimeError("ospLoadModule(cpu) failed")
        dev = lib.ospNewDevice(b"cpu")
        if not dev:
            raise RuntimeError("ospNewDevice(cpu) failed (is libospray_module_cpu beside it?)")
        n = C.c_int(threads)
        lib.ospDeviceSetParam(dev, b"numThreads", OSP_INT, C.byref(n))
        lib.ospDeviceCommit(dev)
        lib.ospSetCurrentDevice(dev)
        self.dev = dev

    def error(self):
        msg = self.lib.ospDeviceGetLastErrorMsg(self.dev)
        return msg.decode() if msg else ""

    # --- parameters ---------------------------------------------------------
    def set(self, obj, name, typ, value):
        """Set a by-value parameter: `value` is a scalar or a sequence."""
        ctype = {OSP_INT: C.c_int, OSP_BOOL: C.c_int, OSP_UCHAR: C.c_uint8}.get(typ, C.c_float)
        vals = list(value) if hasattr(value, "__len__") else [value]
        buf = (ctype * len(vals))(*vals)
        self.lib.ospSetParam(obj, name.encode(), typ, buf)

    def set_obj(self, obj, name, child):
        self.lib.ospSetObject(obj, name.encode(), child)

    def data(self, array, typ=None):
        """A copied OSPData of a numpy array (1D of scalars or of vectors)."""
        a = np.ascontiguousarray(array)
        comps = 1 if a.ndim == 1 else a.shape[1]
        typ = typ or _NUMPY_TYPES[(str(a.dtype), comps)]
        shared = self.lib.ospNewSharedData(a.ctypes.data, typ, a.shape[0], 0, 1, 0, 1, 0,
                                           None, None)
        out = self.lib.ospNewData(typ, a.shape[0], 1, 1)
        self.lib.ospCopyData(shared, out, 0, 0, 0)
        self.lib.ospRelease(shared)
        self.lib.ospCommit(out)
        return out

    def data3d(self, grid):
        """A copied 3D float OSPData of a (nz, ny, nx) array, x fastest."""
        g = np.ascontiguousarray(grid, dtype=np.float32)
        nz, ny, nx = g.shape
        shared = self.lib.ospNewSharedData(g.ctypes.data, OSP_FLOAT, nx, 0, ny, 0, nz, 0,
                                           None, None)
        out = self.lib.ospNewData(OSP_FLOAT, nx, ny, nz)
        self.lib.ospCopyData(shared, out, 0, 0, 0)
        self.lib.ospRelease(shared)
        self.lib.ospCommit(out)
        return out

    def object_array(self, handles, typ=OSP_DATA):
        """An OSPData of object handles of one type (e.g. the AMR volume's
        block.data: OSP_DATA); OSPRay ignores arrays of the wrong type."""
        arr = (C.c_void_p * len(handles))(*handles)
        self._keep.append(arr)
        shared = self.lib.ospNewSharedData(C.cast(arr, C.c_void_p), typ, len(handles),
                                           0, 1, 0, 1, 0, None, None)
        self.lib.ospCommit(shared)
        return shared

    # --- scene --------------------------------------------------------------
    def transfer_function(self, colors_linear, opacities, value_range):
        tf = self.lib.ospNewTransferFunction(b"piecewiseLinear")
        self.set_obj(tf, "color", self.data(np.asarray(colors_linear, np.float32)))
        self.set_obj(tf, "opacity", self.data(np.asarray(opacities, np.float32)))
        self.set(tf, "value", OSP_BOX1F, value_range)
        self.lib.ospCommit(tf)
        return tf

    def world_of(self, volume, tf, density_scale):
        model = self.lib.ospNewVolumetricModel(volume)
        self.set_obj(model, "transferFunction", tf)
        self.set(model, "densityScale", OSP_FLOAT, density_scale)
        self.lib.ospCommit(model)
        group = self.lib.ospNewGroup()
        self.set_obj(group, "volume", self.object_array([model], OSP_VOLUMETRIC_MODEL))
        self.lib.ospCommit(group)
        inst = self.lib.ospNewInstance(group)
        self.lib.ospCommit(inst)
        world = self.lib.ospNewWorld()
        self.set_obj(world, "instance", self.object_array([inst], OSP_INSTANCE))
        self.lib.ospCommit(world)
        return world

    def render(self, world, cam, size, sampling_rate, background=(0, 0, 0)):
        """Render one 1-spp frame; returns (seconds, sRGB uint8 H×W×4, top row first)."""
        w, h = size
        camera = self.lib.ospNewCamera(b"perspective")
        self.set(camera, "position", OSP_VEC3F, cam["eye"])
        d = np.subtract(cam["look_at"], cam["eye"])
        self.set(camera, "direction", OSP_VEC3F, d / np.linalg.norm(d))
        self.set(camera, "up", OSP_VEC3F, cam["up"])
        self.set(camera, "fovy", OSP_FLOAT, cam["fov"])
        self.set(camera, "aspect", OSP_FLOAT, w / h)
        self.lib.ospCommit(camera)
        ren = self.lib.ospNewRenderer(b"scivis")
        self.set(ren, "pixelSamples", OSP_INT, 1)
        self.set(ren, "volumeSamplingRate", OSP_FLOAT, sampling_rate)
        self.set(ren, "backgroundColor", OSP_VEC4F, (*background, 0.0))
        self.set(ren, "aoSamples", OSP_INT, 0)
        self.set(ren, "shadows", OSP_BOOL, 0)
        self.set(ren, "maxPathLength", OSP_INT, 1)
        self.lib.ospCommit(ren)
        fb = self.lib.ospNewFrameBuffer(w, h, OSP_FB_SRGBA, OSP_FB_COLOR)
        self.lib.ospCommit(fb)
        t0 = time.perf_counter()
        self.lib.ospRenderFrameBlocking(fb, ren, camera, world)
        secs = time.perf_counter() - t0
        ptr = self.lib.ospMapFrameBuffer(fb, OSP_FB_COLOR)
        img = np.ctypeslib.as_array(C.cast(ptr, C.POINTER(C.c_uint8)), shape=(h, w, 4)).copy()
        self.lib.ospUnmapFrameBuffer(ptr, fb)
        return secs, img[::-1]  # OSPRay's row 0 is the bottom



def particle_volume(osp, positions, radius, weights, support_factor=3.0):
    """Open VKL `particle` volume: Σ w·exp(−d²/2r²), cut at support_factor·r."""
    vol = osp.lib.ospNewVolume(b"particle")
    osp.set_obj(vol, "particle.position", osp.data(positions.astype(np.float32)))
    osp.set_obj(vol, "particle.radius",
                osp.data(np.full(len(positions), radius, np.float32)))
    osp.set_obj(vol, "particle.weight", osp.data(weights.astype(np.float32)))
    osp.set(vol, "radiusSupportFactor", OSP_FLOAT, support_factor)
    osp.set(vol, "clampMaxCumulativeValue", OSP_FLOAT, 0.0)
    osp.lib.ospCommit(vol)
    return vol


def amr_volume(osp, grids, origin, finest_dx, method=OSP_AMR_OCTANT, widths=None):
    """Open VKL `amr` volume from AMR grids (dicts with level (0 = coarsest),
    lo (cell index of the lower corner in that level's index space) and data
    (nz, ny, nx)). box3i upper bounds are inclusive; cellWidth is per level
    in units of gridSpacing (the finest cell): `widths`, or ratio 2 a level."""
    nlev = max(g["level"] for g in grids) + 1
    if widths is None:
        widths = [2.0 ** (nlev - 1 - l) for l in range(nlev)]
    widths = np.array(widths, np.float32)
    bounds = np.array([[*g["lo"], *(np.add(g["lo"], g["data"].shape[::-1]) - 1)]
                       for g in grids], np.int32)
    levels = np.array([g["level"] for g in grids], np.int32)
    blocks = [osp.data3d(g["data"]) for g in grids]
    vol = osp.lib.ospNewVolume(b"amr")
    osp.set(vol, "gridOrigin", OSP_VEC3F, origin)
    osp.set(vol, "gridSpacing", OSP_VEC3F, (finest_dx,) * 3)
    osp.set(vol, "method", OSP_INT, method)
    osp.set_obj(vol, "cellWidth", osp.data(widths))
    osp.set_obj(vol, "block.bounds", osp.data(bounds, OSP_BOX3I))
    osp.set_obj(vol, "block.level", osp.data(levels))
    osp.set_obj(vol, "block.data", osp.object_array(blocks))
    osp.lib.ospCommit(vol)
    return vol
