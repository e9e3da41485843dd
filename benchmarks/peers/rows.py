"""The benchmark rows: for each, the data it needs, the programs it runs (the
first is the reference every other one is compared with), and how answers
are compared. Commands are built from the shared scene constants in
common.py, so voxless and its peers see the same camera, transfer function,
kernel and image size."""

import os

import common as C

HERE = os.path.dirname(os.path.abspath(__file__))


def _cam(c):
    return ["--eye", *map(str, c["eye"]), "--look-at", *map(str, c["look_at"]),
            "--up", *map(str, c["up"]), "--fov", str(c["fov"])]


def _tf(s):
    return ["--colormap", "viridis", "--opacity", "linear",
            "--value-range", *map(str, s["value_range"]),
            "--opacity-scale", str(s["opacity_scale"])]


def _size(s):
    return ["--size", *map(str, s["size"])]


def voxless(args_fn):
    """A voxless run: args_fn(data) -> CLI arguments (without -o)."""
    return dict(kind="voxless", args=args_fn)


def worker(script, task):
    return dict(kind="worker", script=os.path.join(HERE, script), task=task)


def _sph_render(d):
    s, p = C.SPH_RENDER, os.path.join(d, C.SPH_NPY)
    return (["render", "--particles", os.path.join(p, "positions.npy"),
             "--kernel", "gaussian", "--sigma", "3", "--radius", str(s["radius"]), "--spp", "1"]
            + _size(s) + _cam(s["camera"]) + _tf(s))


def _sph_project(d):
    s, p = C.SPH_PROJECT, os.path.join(d, C.SPH_NPY)
    return ["project", "--particles", os.path.join(p, "positions.npy"),
            "--radii", os.path.join(p, "h.npy"), "--weights", os.path.join(p, "mass.npy"),
            "--kernel", "cubic-spline", "--normal", *map(str, s["normal"]),
            "--north", *map(str, s["north"]), "--center", *map(str, s["center"]),
            "--width", *map(str, s["width"])] + _size(s)


def _amr_render(d):
    s = C.AMR_RENDER
    return (["render", *C.amr_voxless_input(d), "--spp", "1"]
            + _size(s) + _cam(s["camera"]) + _tf(s))


def _amr_render_one_per_cell(d):
    # voxless's default is two samples per finest cell; 0.5 takes one.
    return _amr_render(d) + ["--sampling-rate", "0.5"]


def _amr_project(recon):
    def f(d):
        s = C.AMR_PROJECT
        return ["project", *C.amr_voxless_input(d), "--axis", s["axis"],
                "--reconstruction", recon] + _size(s)
    return f


def _tets(d):
    t = C.TETS
    return ["project", "--particles", os.path.join(d, C.NBODY), "--lagrangian", str(t["n"]),
            "--box", str(t["box"]), "--axis", t["axis"]] + _size(t)


ROWS = [
    dict(id=1, title="SPH volume render 512², 1 spp (dam break, Gaussian kernel)",
         needs=[os.path.join(C.SPH_NPY, "positions.npy")], output="png",
         programs=[("voxless", voxless(_sph_render)),
                   ("OSPRay particle", worker("peer_ospray.py", "particles"))]),
    dict(id=2, title="SPH column density 1024×360 (dam break, cubic spline)",
         needs=[os.path.join(C.SPH_NPY, f) for f in ("positions.npy", "h.npy", "mass.npy", "rho.npy")],
         output="npy", pixel_area=(C.SPH_PROJECT["width"][0] / C.SPH_PROJECT["size"][0]) ** 2,
         programs=[("voxless", voxless(_sph_project)),
                   ("yt", worker("peer_yt.py", "sph_project")),
                   ("sarracen", worker("peer_others.py", "sarracen_project"))]),
    dict(id=3, title=f"AMR volume render 512², 1 spp ({C.AMR_FRAME_NAME})",
         needs=[C.AMRCLAW], output="png",
         programs=[("voxless", voxless(_amr_render)),
                   ("OSPRay amr", worker("peer_ospray.py", "amr")),
                   ("VTK", worker("peer_others.py", "vtk_amr")),
                   ("yt", worker("peer_yt.py", "amr_render"))]),
    dict(id=4, title=f"AMR column density 512² down z ({C.AMR_FRAME_NAME})",
         needs=[C.AMRCLAW], output="npy", pixel_area=(2.0 / 512) ** 2,
         programs=[("voxless basis", voxless(_amr_project("basis"))),
                   ("voxless nearest", voxless(_amr_project("nearest"))),
                   ("yt", worker("peer_yt.py", "amr_project"))]),
    dict(id=6, title="AMR volume render 512², 1 spp, voxless at one sample per finest cell",
         needs=[C.AMRCLAW], output="png",
         programs=[("voxless --sampling-rate 0.5", voxless(_amr_render_one_per_cell)),
                   ("OSPRay amr", worker("peer_ospray.py", "amr"))]),
    dict(id=5, title="Tessellation column density 1024² (JaxPM 64³, a = 1)",
         needs=[C.NBODY], output="npy", pixel_area=(C.TETS["box"] / C.TETS["size"][0]) ** 2,
         programs=[("voxless tets", voxless(_tets)),
                   ("pynbody SPH", worker("peer_others.py", "pynbody_tets"))]),
]
