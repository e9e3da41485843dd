#!/usr/bin/env python3
"""Render the phase-space tessellation sub-block exported by
`voxless-bench tets --export-subblock DIR` with VTK's unstructured-grid volume
mappers, for the side-by-side comparison in docs/benchmarks.md.

Run manually (not in CI):

    pip install vtk numpy
    cargo run --release -p voxless-bench -- tets --export-subblock target/tets-sub
    python3 tools/vtk_tets.py target/tets-sub --out docs/tets-vtk.png

Inputs in DIR: vertices.npy (N×12 f32, four xyz per tet), density.npy (N),
tf.npy (256×4: linear RGB and opacity of voxless's transfer function at
x = i/255), view.json (camera, log10 value range, opacity scale),
voxless-rgba.npy (our exact render, linear premultiplied RGBA) and
streams.npy (per pixel, the most tets overlapping on its ray).

The tets are handed to VTK the way a VTK user would: one unstructured grid
whose tets share their vertices (duplicates merged, so the Lagrangian
connectivity is kept), with log10(density) as *cell* scalars (the density is
constant per tet). The colour and opacity functions sample voxless's transfer
function at 256 points over the same log10 range; the scalar-opacity unit
distance is 1 / opacity_scale, so a segment of length L at opacity a has
alpha 1 − exp(−a · opacity_scale · L) in both renderers. Same camera, size and
black background. VTK composites the linear colours into 8 bits per channel,
so the colours are scaled up for rendering (`--gain`; the image is linear in
them) and the result scaled back, then encoded as sRGB like voxless's PNGs.

Mappers: `raycast` (vtkUnstructuredGridVolumeRayCastMapper: Bunyk ray
casting, homogeneous ray integrator for cell scalars) and `pt`
(vtkProjectedTetrahedraMapper: cell-centre depth sort, then projected
tetrahedra). Neither sums overlapping tets: the density at a point covered
by several tets is the sum of theirs, which is what voxless integrates.

Prints the render times (first render, including VTK's set-up, and the
median of the following ones) and the difference to voxless's image, overall
and split by the number of overlapping tets (streams) along each pixel's ray.
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import vtk
from vtk.util import numpy_support as ns


def srgb(v):
    v = np.clip(v, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)


def build_grid(verts, dens, separate=False):
    """Unstructured grid of tets with shared (merged) vertices, or four own
    vertices per tet with `separate`, and cell scalars."""
    flat = verts.reshape(-1, 3)
    if separate:
        pts, inv = flat, np.arange(len(flat), dtype=np.int64)
    else:
        pts, inv = np.unique(flat, axis=0, return_inverse=True)
    inv = inv.reshape(-1).astype(np.int64)
    n = len(dens)
    points = vtk.vtkPoints()
    points.SetData(ns.numpy_to_vtk(np.ascontiguousarray(pts, dtype=np.float32), deep=True))
    offsets = ns.numpy_to_vtkIdTypeArray(np.arange(0, 4 * n + 1, 4, dtype=np.int64), deep=True)
    conn = ns.numpy_to_vtkIdTypeArray(np.ascontiguousarray(inv), deep=True)
    cells = vtk.vtkCellArray()
    cells.SetData(offsets, conn)
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points)
    grid.SetCells(vtk.VTK_TETRA, cells)
    s = ns.numpy_to_vtk(np.log10(dens).astype(np.float32), deep=True)
    s.SetName("log10_density")
    grid.GetCellData().SetScalars(s)
    return grid, len(pts)


def volume_property(tf, lo, hi, opacity_scale, gain):
    color = vtk.vtkColorTransferFunction()
    opacity = vtk.vtkPiecewiseFunction()
    for i, (r, g, b, a) in enumerate(tf):
        x = lo + (hi - lo) * i / (len(tf) - 1)
        color.AddRGBPoint(x, *(min(float(v) * gain, 1.0) for v in (r, g, b)))
        opacity.AddPoint(x, float(a))
    color.ClampingOn()
    opacity.ClampingOn()
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(1.0 / opacity_scale)
    prop.ShadeOff()
    prop.SetInterpolationTypeToLinear()
    return prop


def render(grid, prop, view, kind, repeats):
    size = int(view["size"])
    if kind == "raycast":
        mapper = vtk.vtkUnstructuredGridVolumeRayCastMapper()
        mapper.SetAutoAdjustSampleDistances(0)
        mapper.SetImageSampleDistance(1.0)
    elif kind == "pt":
        mapper = vtk.vtkProjectedTetrahedraMapper()
    elif kind == "zsweep":
        mapper = vtk.vtkUnstructuredGridVolumeZSweepMapper()
    else:
        raise SystemExit(f"unknown mapper {kind}")
    mapper.SetInputData(grid)
    mapper.SetScalarModeToUseCellData()
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    ren = vtk.vtkRenderer()
    ren.SetBackground(0, 0, 0)
    ren.AddVolume(volume)
    cam = ren.GetActiveCamera()
    cam.SetPosition(*view["eye"])
    cam.SetFocalPoint(*view["look_at"])
    cam.SetViewUp(*view["up"])
    cam.SetViewAngle(view["fov_y_deg"])
    d = np.linalg.norm(np.subtract(view["eye"], view["look_at"]))
    cam.SetClippingRange(1e-3 * d, 10 * d)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(0)
    win.SetSize(size, size)
    win.AddRenderer(ren)
    times = []
    for i in range(repeats + 1):
        if i > 0:
            # A tiny camera change so the mapper cannot reuse the last image.
            cam.Azimuth(1e-4 if i % 2 else -1e-4)
        t = time.perf_counter()
        win.Render()
        win.WaitForCompletion()
        times.append(time.perf_counter() - t)
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    img = grab.GetOutput()
    w, h, _ = img.GetDimensions()
    rgb = ns.vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, 3)[::-1]
    return rgb.astype(np.float32) / 255.0, times, win.GetClassName()


def write_png(path, rgb8):
    h, w, _ = rgb8.shape
    img = vtk.vtkImageData()
    img.SetDimensions(w, h, 1)
    arr = ns.numpy_to_vtk(np.ascontiguousarray(rgb8[::-1]).reshape(-1, 3), deep=True)
    img.GetPointData().SetScalars(arr)
    wr = vtk.vtkPNGWriter()
    wr.SetFileName(path)
    wr.SetInputData(img)
    wr.Write()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", help="directory written by `voxless-bench tets --export-subblock`")
    ap.add_argument("--out", default="docs/tets-vtk.png",
                    help="PNG for the ray-cast image; other mappers get -<mapper> appended")
    ap.add_argument("--mappers", default="raycast,pt", help="comma list of raycast, pt, zsweep")
    ap.add_argument("--repeats", type=int, default=2, help="timed renders after the first")
    ap.add_argument("--gain", type=float, default=0.0,
                    help="colour gain against 8-bit quantisation (0: 0.95 / brightest voxless pixel)")
    ap.add_argument("--separate", action="store_true",
                    help="give every tet its own four vertices (no shared faces)")
    a = ap.parse_args()

    view = json.load(open(os.path.join(a.dir, "view.json")))
    verts = np.load(os.path.join(a.dir, "vertices.npy"))
    dens = np.load(os.path.join(a.dir, "density.npy"))
    tf = np.load(os.path.join(a.dir, "tf.npy"))
    ours = np.load(os.path.join(a.dir, "voxless-rgba.npy"))
    streams = np.load(os.path.join(a.dir, "streams.npy"))
    ours_q = np.clip(ours[..., :3], 0, 1)
    ours8 = np.round(srgb(ours_q) * 255).astype(np.uint8)

    t = time.perf_counter()
    grid, npts = build_grid(verts, dens, a.separate)
    t_grid = time.perf_counter() - t
    lo, hi = view["log10_range"]
    # The image is dark (emission ≤ 0.3 in linear RGB) and VTK keeps 8 bits
    # per channel, which would swallow faint pixels: colours are scaled up by
    # `gain` for rendering (the image is linear in them) and back afterwards.
    gain = a.gain or min(0.95 / max(float(ours[..., :3].max()), 1e-6), 16.0)
    prop = volume_property(tf, lo, hi, view["opacity_scale"], gain)
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()}: {grid.GetNumberOfCells()} tets, "
          f"{npts} {'separate' if a.separate else 'shared'} points (grid built in {t_grid:.2f} s), "
          f"colour gain {gain:.2f}")
    print(f"voxless exact: {view['voxless_exact_s']:.3f} s "
          f"(first {view['voxless_first_s']:.3f} s)\n")
    lum = lambda x: x[..., 0] * 0.2126 + x[..., 1] * 0.7152 + x[..., 2] * 0.0722  # noqa: E731
    ours_l = lum(ours_q)
    groups = {
        "single stream (1)": streams == 1,
        "2 streams": streams == 2,
        "3+ streams": streams >= 3,
        "brightest 1 %": ours_l >= np.quantile(ours_l[streams > 0], 0.99),
    }
    print("| renderer | first render s | next renders s (median) | vs voxless | "
          "mean abs diff (sRGB 0–255) | mean luminance / voxless: 1 / 2 / 3+ streams / brightest 1 % |")
    print("|---|---:|---:|---:|---:|---|")
    print(f"| voxless exact | {view['voxless_first_s']:.2f} | {view['voxless_exact_s']:.2f} | "
          f"1.0 | 0 | 1 / 1 / 1 / 1 |")
    for kind in a.mappers.split(","):
        try:
            rgb, times, wclass = render(grid, prop, view, kind, a.repeats)
        except Exception as e:  # noqa: BLE001 — report and go on with the next mapper
            print(f"| {kind} | failed: {e} | | | | |")
            continue
        rgb = rgb / gain
        img8 = np.round(srgb(rgb) * 255).astype(np.uint8)
        out = a.out if kind == "raycast" else a.out.replace(".png", f"-{kind}.png")
        write_png(out, img8)
        diff = np.abs(img8.astype(np.float64) - ours8).mean()
        ratios = []
        for m in groups.values():
            if m.any():
                ratios.append(f"{lum(rgb)[m].mean() / max(ours_l[m].mean(), 1e-12):.2f}")
            else:
                ratios.append("—")
        nxt = float(np.median(times[1:])) if len(times) > 1 else float("nan")
        print(f"| VTK {kind} ({wclass}) | {times[0]:.2f} | {nxt:.2f} | "
              f"{nxt / view['voxless_exact_s']:.1f} | {diff:.1f} | {' / '.join(ratios)} |")
        print(f"wrote {out}", file=sys.stderr)
    share = {k: f"{100 * m.sum() / max((streams > 0).sum(), 1):.1f} %"
             for k, m in groups.items() if "streams" in k or "(1)" in k}
    print(f"\nCovered pixels by streams along the ray: {share}")


if __name__ == "__main__":
    main()
