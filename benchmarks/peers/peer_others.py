"""VTK, sarracen and pynbody workers:
`python peer_others.py TASK --data DIR --out FILE --threads N`.

Tasks:
  vtk_amr           the AMRClaw frame painted coarse-to-fine onto its finest
                    80³ lattice (what vtkAMRVolumeMapper does internally), as
                    point data at the cell centres (trilinear between them),
                    vtkSmartVolumeMapper in an offscreen EGL window
  sarracen_project  interpolate_3d_proj of the dam break, cubic spline
  pynbody_tets      pynbody SPH column density of the 64³ JaxPM particles
                    (equal masses; its own smoothing lengths from 32 neighbours)
"""

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

T0 = time.perf_counter()


def vtk_amr(a):
    # EGL directly: the default X window class warns when there is no display.
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import vtk
    from vtk.util import numpy_support as ns

    s = C.AMR_RENDER
    grid, lo, dx = C.amr_to_uniform(C.amr_grids(a.data))
    img = vtk.vtkImageData()
    img.SetDimensions(*grid.shape[::-1])
    img.SetSpacing(dx, dx, dx)
    img.SetOrigin(*(lo + dx / 2))
    arr = ns.numpy_to_vtk(grid.ravel(), deep=1)
    arr.SetName("density")
    img.GetPointData().SetScalars(arr)

    vmin, vmax = s["value_range"]
    ctf, otf = vtk.vtkColorTransferFunction(), vtk.vtkPiecewiseFunction()
    # Linear colours: the readback is sRGB-encoded below, as voxless does.
    for i, c in enumerate(C.viridis_linear()):
        ctf.AddRGBPoint(vmin + (vmax - vmin) * i / 255, *c)
    # VTK's opacity a holds for a unit distance u: 1 − (1 − a)^(dt/u). With
    # a = 1 − exp(−o·κ·u) that is voxless's 1 − exp(−o·κ·dt) exactly.
    unit = dx
    for x in np.linspace(0.0, 1.0, 65):
        otf.AddPoint(vmin + (vmax - vmin) * x, 1 - np.exp(-x * s["opacity_scale"] * unit))
    otf.AddPoint(vmax + 1e3 * (vmax - vmin), 1 - np.exp(-s["opacity_scale"] * unit))
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetScalarOpacityUnitDistance(unit)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    mapper = vtk.vtkSmartVolumeMapper()
    mapper.SetInputData(img)
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetSampleDistance(dx / 2)  # voxless: two samples per finest cell
    vol = vtk.vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtk.vtkRenderer()
    ren.AddVolume(vol)
    ren.SetBackground(0, 0, 0)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    w, h = s["size"]
    win.SetSize(w, h)
    cam, c = ren.GetActiveCamera(), s["camera"]
    cam.SetPosition(*c["eye"])
    cam.SetFocalPoint(*c["look_at"])
    cam.SetViewUp(*c["up"])
    cam.SetViewAngle(c["fov"])  # vertical, as voxless's --fov
    ren.ResetCameraClippingRange()
    win.Render()  # first frame: context, shaders, 3D texture upload
    setup = time.perf_counter() - T0
    t0 = time.perf_counter()
    win.Render()
    secs = time.perf_counter() - t0
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    rgb = ns.vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).reshape(h, w, 3)[::-1]
    C.save_png(a.out, C.linear_to_srgb8(rgb / 255.0))
    C.emit(setup_s=setup, compute_s=secs, version=vtk.vtkVersion.GetVTKVersion(),
           window=win.GetClassName(), mapper_mode=mapper.GetLastUsedRenderMode())


def sarracen_project(a):
    import pandas as pd
    import sarracen
    from sarracen.kernels import CubicSplineKernel

    d = os.path.join(a.data, C.SPH_NPY)
    pos, h, m = (np.load(os.path.join(d, f)).astype(np.float64)
                 for f in ("positions.npy", "h.npy", "mass.npy"))
    # target "one" with rho = 1: Σ m/ρ·1·W = Σ m·W, the column density.
    df = pd.DataFrame({"x": pos[:, 0], "y": pos[:, 1], "z": pos[:, 2], "h": h, "m": m,
                       "rho": np.ones(len(m)), "one": np.ones(len(m))})
    sdf = sarracen.SarracenDataFrame(df, params={})
    sdf.kernel = CubicSplineKernel()
    p = C.SPH_PROJECT
    nx, ny = p["size"]
    (cx, _, cz), (w, hh) = p["center"], p["width"]
    setup = time.perf_counter() - T0
    t0 = time.perf_counter()
    # Image axes x and z: the column runs along y, as voxless's --normal 0 -1 0.
    img = sarracen.interpolate.interpolate_3d_proj(
        sdf, "one", x="x", y="z", x_pixels=nx, y_pixels=ny, kernel=CubicSplineKernel(),
        xlim=(cx - w / 2, cx + w / 2), ylim=(cz - hh / 2, cz + hh / 2),
        normalize=False, hmin=False)
    secs = time.perf_counter() - t0
    np.save(a.out, np.asarray(img, np.float64)[::-1].astype(np.float32))  # row 0 at the bottom
    C.emit(setup_s=setup, compute_s=secs, version=sarracen.__version__)


def pynbody_tets(a):
    import pynbody

    pynbody.config["number_of_threads"] = a.threads
    t = C.TETS
    pos = np.load(os.path.join(a.data, C.NBODY)).astype(np.float64)
    n = len(pos)
    box = t["box"]
    sim = pynbody.new(dm=n)
    # Centred on the box (pynbody images are centred on the origin).
    sim["pos"] = pos - box / 2
    sim["pos"].units = "Mpc"
    # voxless's default particle mass: the mean density is 1 (overdensity units).
    sim["mass"] = np.full(n, box ** 3 / n)
    sim["mass"].units = "Msol"
    sim.properties["boxsize"] = pynbody.units.Unit(f"{box} Mpc")
    setup = time.perf_counter() - T0
    t0 = time.perf_counter()
    # The smoothing lengths and densities (k-d tree, 32 neighbours) are part
    # of what pynbody must do to make the image.
    img = pynbody.sph.render_image(sim, "rho", width=box, resolution=t["size"][0],
                                   out_units="Msol Mpc^-2", approximate_fast=False)
    secs = time.perf_counter() - t0
    col = np.asarray(img, np.float64)[::-1]  # pynbody: row 0 at y min
    np.save(a.out, col.astype(np.float32))
    C.emit(setup_s=setup, compute_s=secs, version=pynbody.__version__)


def main():
    C.worker_main({t: globals()[t] for t in ("vtk_amr", "sarracen_project", "pynbody_tets")})


if __name__ == "__main__":
    main()
