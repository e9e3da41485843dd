"""OSPRay worker: `python peer_ospray.py {particles|amr} --data DIR --out X.png --threads N`.

Runs in its own process so that its peak RSS is its own. Setup = reading the
data and committing volume + world (Open VKL builds its acceleration
structures there); the first frame is rendered and thrown away (lazy
initialisation), the second is timed and saved.
"""

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402
import ospray as O  # noqa: E402


def particles(osp, data):
    s = C.SPH_RENDER
    pos = np.load(os.path.join(data, C.SPH_NPY, "positions.npy"))
    vol = O.particle_volume(osp, pos, s["radius"], np.ones(len(pos), np.float32))
    return vol, s


def amr(osp, data):
    s = C.AMR_RENDER
    grids = C.amr_grids(data)
    finest = min(g["dx"] for g in grids)
    blocks = [dict(level=g["level"],
                   lo=tuple(int(round(x / g["dx"])) for x in g["lower"]),
                   data=g["data"]) for g in grids]
    # Octant: Open VKL's smooth reconstruction across levels, the nearest
    # counterpart of voxless's basis (tent) reconstruction.
    # Each level's cell in finest cells; a level with no blocks (FLASH's
    # covered root) gets ratio 2 from the one below it.
    widths = {g["level"]: g["dx"] / finest for g in grids}
    top = max(widths)
    vol = O.amr_volume(osp, blocks, (0.0, 0.0, 0.0), finest, O.OSP_AMR_OCTANT,
                       [widths.get(l, 2.0 ** (top - l)) for l in range(top + 1)])
    return vol, s


def render(a):
    """Set-up, a first frame thrown away, and the timed frame of `a.task`."""
    t0 = time.perf_counter()
    osp = O.OSPRay(a.threads)
    vol, s = (particles if a.task == "particles" else amr)(osp, a.data)
    tf = osp.transfer_function(C.viridis_linear(), np.linspace(0.0, 1.0, 256), s["value_range"])
    # densityScale multiplies the TF opacity in exp(−opacity·densityScale·dt),
    # the same law as voxless's opacity scale.
    world = osp.world_of(vol, tf, s["opacity_scale"])
    first, _ = osp.render(world, s["camera"], s["size"], sampling_rate=1.0)
    setup = time.perf_counter() - t0
    secs, img = osp.render(world, s["camera"], s["size"], sampling_rate=1.0)
    err = osp.error()
    if err:
        print("ospray:", err, file=sys.stderr)
    C.save_png(a.out, img)
    C.emit(setup_s=setup, compute_s=secs, first_frame_s=first, version=O.version())


def main():
    C.worker_main({"particles": render, "amr": render})


if __name__ == "__main__":
    main()
