"""Every bad input raises a Python exception naming what is wrong — never a crash."""

import numpy as np
import pytest
import voxless

POS = np.random.default_rng(1).random((200, 3))


@pytest.fixture(scope="module")
def vol():
    return voxless.Particles(POS, radius=0.1)


CASES = [
    # (what, exception, text the message must contain)
    (lambda v: voxless.Particles(np.zeros((5, 2))), ValueError, "positions"),
    (lambda v: voxless.Particles("abc"), TypeError, "positions"),
    (lambda v: voxless.Particles([[1, 2, "x"]]), TypeError, "positions"),
    (lambda v: voxless.Particles(POS, radii=np.ones(3)), ValueError, "radii"),
    (lambda v: voxless.Particles(POS, weights=np.ones((200, 2))), ValueError, "weights"),
    (lambda v: voxless.Particles(POS, kernel="cubic-splin"), ValueError, "kernel"),
    (lambda v: voxless.Particles(POS, radius=-1.0), ValueError, "radius"),
    (lambda v: voxless.Particles(POS, radius="big"), ValueError, "radius"),
    (lambda v: voxless.Particles(POS, radii=np.full(200, np.nan)), ValueError, "radi"),
    (lambda v: voxless.Particles(POS * np.nan), ValueError, "particle"),
    (lambda v: voxless.Particles(POS, lagrangian=8), TypeError, "lagrangian"),
    (lambda v: voxless.Particles(POS, colourmap="magma"), TypeError, "colormap"),
    (lambda v: voxless.Particles(POS, colormap="no-such-map"), ValueError, "no-such-map"),
    (lambda v: voxless.AmrCells(np.zeros((3, 3)), np.ones(3)), ValueError, "cells"),
    (lambda v: voxless.AmrCells(np.zeros((3, 4), int), np.ones(2)), ValueError, "fields"),
    (lambda v: voxless.AmrCells(np.zeros((3, 4)) + 0.5, np.ones(3)), TypeError, "cells"),
    (lambda v: voxless.AmrCells(np.zeros((2, 4), int), np.ones(2)), ValueError, "cell"),
    (lambda v: voxless.AmrCells(np.zeros((1, 4), int), np.ones(1), cell_size=0), ValueError, "cell"),
    (lambda v: voxless.Tessellation(POS[:27], n=3), TypeError, "box"),
    (lambda v: voxless.Tessellation(POS[:27], n=4, box=1.0), ValueError, "positions"),
    (lambda v: voxless.load("no-such-file.npy"), FileNotFoundError, "no-such-file.npy"),
    (lambda v: voxless.load("no-such-scene.toml"), FileNotFoundError, "no-such-scene.toml"),
    (lambda v: voxless.load({"particles": {"fil": "x.npy"}}), ValueError, "fil"),
    (lambda v: voxless.load(), ValueError, "particles"),
    (lambda v: v.render(size=(0, 10)), ValueError, "size"),
    (lambda v: v.render(size=(10, 10, 10)), ValueError, "size"),
    (lambda v: v.render(eye=(1, 2)), ValueError, "eye"),
    (lambda v: v.render(fov="wide"), ValueError, "fov"),
    (lambda v: v.render(kernel="gaussian"), TypeError, "kernel"),
    (lambda v: v.render(colormap=[[0, 1]]), ValueError, "colormap"),
    (lambda v: v.render(early_termination=2.0), ValueError, "early_termination"),
    (lambda v: v.render(camera=voxless.Camera(fov=-5)), ValueError, "fov"),
    (lambda v: v.render(camera=5), TypeError, "camera"),
    (lambda v: v.render(iso=0.001, iso_only=True), ValueError, "iso"),
    (lambda v: v.render(log=True, linear=True), ValueError, "log"),
    (lambda v: v.render(scene={"particles": {}}), ValueError, "particles"),
    (lambda v: v.render(colormap_file="missing.json"), ValueError, "missing.json"),
    (lambda v: v.project(axis="w"), ValueError, "axis"),
    (lambda v: v.project(normal=(0, 0, 0)), ValueError, "normal"),
    (lambda v: v.project(normal=(0, 0, 1), axis="z"), ValueError, "normal"),
    (lambda v: v.project(normal=(0, 0, 1), north=(0, 0, 2)), ValueError, "north"),
    (lambda v: v.project(width=-1.0), ValueError, "width"),
    (lambda v: v.project(bounds=(1, 1, 1, 0, 0, 0)), ValueError, "bounds"),
    (lambda v: v.project(depth=float("nan")), ValueError, "depth"),
    (lambda v: v.sample(np.zeros((4, 2))), ValueError, "points"),
    (lambda v: v.sample(np.full((2, 3), np.inf)), ValueError, "points"),
    (lambda v: v.sample(POS, gradient="yes"), TypeError, "gradient"),
]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_bad_input_raises(vol, case):
    call, exc, text = CASES[case]
    with pytest.raises(exc) as info:
        call(vol)
    assert text in str(info.value), str(info.value)


def test_library_errors_carry_the_setting():
    with pytest.raises(voxless.VoxlessError) as info:
        voxless.Particles(POS, radius=0.1).render(early_termination=2.0)
    assert isinstance(info.value, ValueError)
    assert info.value.field == "render.early_termination"
