"""yt worker: `python peer_yt.py TASK --data DIR --out FILE --threads N`.

Tasks:
  sph_project  column density of the dam break: yt.load_particles (smoothing
               length 2h: yt's cubic kernel reaches its smoothing length,
               voxless's and PHANTOM's reach 2h) + yt.off_axis_projection
  amr_render   yt.create_scene of the AMRClaw frame (yt.load_amr_grids)
  amr_project  ds.proj of the AMRClaw density down z, 512² FRB

Outputs are written in voxless's orientation (row 0 at the top, columns
west to east): yt indexes images [x, y].
"""

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def sph_project(a):
    import yt

    yt.set_log_level(50)
    d = os.path.join(a.data, C.SPH_NPY)
    pos, h, m, rho = (np.load(os.path.join(d, f)).astype(np.float64)
                      for f in ("positions.npy", "h.npy", "mass.npy", "rho.npy"))
    lo, hi = pos.min(0) - 1, pos.max(0) + 1
    data = {("io", f"particle_position_{ax}"): pos[:, i] for i, ax in enumerate("xyz")}
    data.update({("io", "particle_mass"): m, ("io", "smoothing_length"): 2.0 * h,
                 ("io", "density"): rho})
    ds = yt.load_particles(data, length_unit="cm", mass_unit="g", bbox=np.stack([lo, hi], 1))
    ad = ds.all_data()
    ad["io", "density"]  # read the fields outside the timing
    setup = time.perf_counter() - T0
    p = C.SPH_PROJECT
    w, hgt = p["width"]
    depth = 10.0  # the whole line of sight
    t0 = time.perf_counter()
    img = yt.off_axis_projection(ad, p["center"], p["normal"], (w, hgt, depth), p["size"],
                                 ("gas", "density"), north_vector=p["north"])
    secs = time.perf_counter() - t0
    col = np.asarray(img, np.float64).T[::-1]
    np.save(a.out, col.astype(np.float32))
    C.emit(setup_s=setup, compute_s=secs, version=yt.__version__)


def amr_dataset(data):
    """AMRClaw grids as a yt stream dataset. yt checks that each grid's
    left edge is one of its parent level's cell edges *exactly* (as floats
    from np.linspace), so the edges are snapped to those values."""
    import yt

    if C.AMR_FORMAT != "amrclaw":
        # FLASH's octree has no level-0 block covering the domain; yt reads
        # those files itself (amr.sh), and the format sweep runs OSPRay alone.
        raise SystemExit(f"peer_yt's AMR rows read AMRClaw grids, not {C.AMR_FORMAT}")
    grids = C.amr_grids(data)
    coarse = min(grids, key=lambda g: g["level"])
    dom_n = np.array(coarse["shape"])  # the level-0 grid covers the domain here
    dom_lo = np.array(coarse["lower"])
    dom_hi = dom_lo + dom_n * coarse["dx"]
    gd = []
    for g in split_by_parent(grids, dom_lo):
        lvl, dims = g["level"], np.array(g["shape"])
        idx = np.rint((np.array(g["lower"]) - dom_lo) / g["dx"]).astype(int)
        if lvl > 0:
            n_parent = dom_n * 2 ** (lvl - 1)
            left = np.array([np.linspace(dom_lo[i], dom_hi[i], n_parent[i], endpoint=False)[idx[i] // 2]
                             for i in range(3)])
        else:
            left = dom_lo + idx * g["dx"]
        gd.append(dict(left_edge=left, right_edge=left + dims * g["dx"], level=lvl,
                       dimensions=dims, density=g["data"].transpose(2, 1, 0).astype(np.float64)))
    bbox = np.stack([dom_lo, dom_hi], 1)
    return yt.load_amr_grids(gd, dom_n, bbox=bbox, length_unit=1.0), dom_lo, dom_hi


def split_by_parent(grids, dom_lo):
    """Cut every grid along the boxes of the level above it. yt's stream
    frontend gives a grid one parent; AMRClaw grids often straddle two, and
    the second parent then keeps the cells the child covers (yt counted
    222,373 cells instead of the 216,089 leaves, +10 % mass)."""
    def box(g):
        lo = np.rint((np.array(g["lower"]) - dom_lo) / g["dx"]).astype(int)
        return lo, lo + np.array(g["shape"])

    out = []
    for g in grids:
        if g["level"] == 0:
            out.append(g)
            continue
        lo, hi = box(g)
        for p in (p for p in grids if p["level"] == g["level"] - 1):
            plo, phi = (2 * b for b in box(p))  # parent box in this level's cells
            a, b = np.maximum(lo, plo), np.minimum(hi, phi)
            if (b <= a).any():
                continue
            s = g["data"][a[2] - lo[2]:b[2] - lo[2], a[1] - lo[1]:b[1] - lo[1], a[0] - lo[0]:b[0] - lo[0]]
            out.append(dict(level=g["level"], dx=g["dx"], shape=tuple(b - a),
                            lower=tuple(dom_lo + a * g["dx"]), data=np.ascontiguousarray(s)))
    return out


def amr_render(a):
    import yt

    yt.set_log_level(50)
    ds, lo, hi = amr_dataset(a.data)
    s = C.AMR_RENDER
    vmin, vmax = s["value_range"]
    cam_d = s["camera"]
    sc = yt.create_scene(ds, ("gas", "density"))
    src = sc[0]
    src.log_field = False
    src.set_use_ghost_zones(False)
    # yt composites rgba = dt·e + max(1 − dt·α, 0)·rgba per sample (grey
    # opacity), dt in code length: e = colour·o·κ and α = o·κ approximate
    # voxless's 1 − exp(−o·κ·dt) for small dt.
    tf = yt.ColorTransferFunction((vmin, vmax), grey_opacity=True, nbins=256)
    o = np.linspace(0.0, 1.0, 256) * s["opacity_scale"]
    cols = C.viridis_linear()
    for i in range(3):
        tf.funcs[i].y[:] = cols[:, i] * o
    tf.funcs[3].y[:] = o
    src.set_transfer_function(tf)
    cam = sc.camera
    cam.set_lens("perspective")
    cam.resolution = s["size"]
    cam.position = ds.arr(cam_d["eye"], "code_length")
    cam.focus = ds.arr(cam_d["look_at"], "code_length")
    cam.north_vector = np.array(cam_d["up"], float)
    # yt's perspective lens: ray = east·x·w0 + north·y·w1 + normal·w2, so the
    # vertical field of view is 2·atan(w1 / 2w2).
    dist = float(np.linalg.norm(np.subtract(cam_d["eye"], cam_d["look_at"])))
    wid = 2 * dist * np.tan(np.radians(cam_d["fov"] / 2))
    cam.width = ds.arr([wid * s["size"][0] / s["size"][1], wid, dist], "code_length")
    setup = time.perf_counter() - T0
    t0 = time.perf_counter()
    im = sc.render()
    secs = time.perf_counter() - t0
    rgb = np.asarray(im)[..., :3].transpose(1, 0, 2)
    C.save_png(a.out, C.linear_to_srgb8(rgb))
    C.emit(setup_s=setup, compute_s=secs, version=yt.__version__)


def amr_project(a):
    import yt

    yt.set_log_level(50)
    ds, lo, hi = amr_dataset(a.data)
    ds.all_data()["gas", "density"]
    setup = time.perf_counter() - T0
    nx, ny = C.AMR_PROJECT["size"]
    t0 = time.perf_counter()
    proj = ds.proj(("gas", "density"), "z")
    frb = proj.to_frb(ds.arr(hi[0] - lo[0], "code_length"), (ny, nx),
                      center=ds.arr((lo + hi) / 2, "code_length"),
                      height=ds.arr(hi[1] - lo[1], "code_length"))
    col = np.asarray(frb["gas", "density"], np.float64)  # [row (y), col (x)], row 0 at y min
    secs = time.perf_counter() - t0
    np.save(a.out, col[::-1].astype(np.float32))
    C.emit(setup_s=setup, compute_s=secs, version=yt.__version__)


def main():
    C.worker_main({t: globals()[t] for t in ("sph_project", "amr_render", "amr_project")})


T0 = time.perf_counter()  # setup counts from the start of the process (imports)

if __name__ == "__main__":
    main()
