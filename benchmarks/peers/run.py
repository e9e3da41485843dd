"""Benchmark voxless against peer renderers on the same data, camera,
transfer function and image size; print a markdown ratio table.

    python benchmarks/peers/run.py --data ../shared/data --out results.md

Each row runs its programs interleaved (rep 1: voxless, peer A, peer B, …;
rep 2: …), every one in its own process (peak RSS from wait4), with the
same thread count. See README.md for what each row matches.
"""

import argparse
import datetime
import os
import platform
import re
import statistics
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402
from rows import ROWS  # noqa: E402

VOXLESS_TIMES = (re.compile(r"loaded .* in ([0-9.]+)s"),
                 re.compile(r"(?:rendered|projected) .* in ([0-9.]+)s"))


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--voxless", default=os.path.join(C.REPO, "target", "release", "voxless"),
                    help="voxless binary (default: target/release/voxless)")
    ap.add_argument("--data", default=os.path.join(C.REPO, "..", "shared", "data"),
                    help="data directory (default: ../shared/data beside the repo)")
    ap.add_argument("--out", help="write the markdown table here too")
    ap.add_argument("--images", default=os.path.join(C.HERE, "out"),
                    help="where every run's image / column (.npy + .png) goes")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=os.cpu_count(),
                    help="threads for every program (default: all cores)")
    ap.add_argument("--rows", default="1,2,3,4,5,6", help="comma-separated row numbers")
    ap.add_argument("--peers", help="comma-separated peer names to run beside voxless "
                    "(default: every peer of each row)")
    ap.add_argument("--python", default=sys.executable,
                    help="interpreter with the peers installed (default: this one)")
    return ap.parse_args()


def command(prog, a, out):
    if prog["kind"] == "voxless":
        return [a.voxless] + prog["args"](a.data) + ["-o", out]
    return [a.python, prog["script"], prog["task"], "--data", a.data, "--out", out,
            "--threads", str(a.threads)]


def run_once(row, name, prog, a, rep, env):
    slug = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")
    out = os.path.join(a.images, f"row{row['id']}-{slug}-rep{rep}.{row['output']}")
    log = out.rsplit(".", 1)[0] + ".log"
    rc, wall, rss, text = C.run_measured(command(prog, a, out), env, log)
    rec = dict(wall=wall, rss=rss, out=out, ok=rc == 0 and os.path.exists(out))
    if prog["kind"] == "voxless":
        m = [r.search(text) for r in VOXLESS_TIMES]
        rec["setup"] = float(m[0].group(1)) if m[0] else None
        rec["compute"] = float(m[1].group(1)) if m[1] else None
    else:
        res = C.worker_result(text) or {}
        rec["setup"], rec["compute"] = res.get("setup_s"), res.get("compute_s")
        rec["version"] = res.get("version")
    if not rec["ok"]:
        tail = [ln for ln in text.strip().splitlines() if ln.strip()][-1:] or ["(no output)"]
        rec["error"] = f"exit {rc}: {tail[0][:160]}"
        print(f"    {name}: FAILED ({rec['error']}); log: {os.path.relpath(log)}")
    else:
        print(f"    {name}: wall {wall:.2f} s, setup {fmt(rec['setup'])} s, "
              f"compute {fmt(rec['compute'])} s, peak {rss:.0f} MB")
    if rec["ok"] and row["output"] == "npy":
        column_png(out)
    return rec


def column_png(path):
    """A log-scaled picture of a column-density .npy, for people to look at."""
    col = np.load(path).astype(np.float64)
    pos = col[col > 0]
    if pos.size == 0:
        return
    lo, hi = np.percentile(np.log10(pos), [1, 99.9])
    x = np.clip((np.log10(np.maximum(col, 1e-300)) - lo) / max(hi - lo, 1e-12), 0, 1)
    x[col <= 0] = 0
    rgb = C.linear_to_srgb8(C.viridis_linear()[(x * 255).astype(int)])
    C.save_png(path[:-4] + ".png", rgb)


def agreement(row, ref, rec):
    """How far this program's answer is from the reference's (rep 1 of each)."""
    if not (ref["ok"] and rec["ok"]):
        return "—"
    if row["output"] == "png":
        return f"MAD {C.image_mad(ref['out'], rec['out']):.2f}/255"
    a, b = np.load(ref["out"]), np.load(rec["out"])
    if a.shape != b.shape:
        return f"shape {b.shape} ≠ {a.shape}"
    dsum, l1, s_ref, s_oth = C.column_compare(a, b, row["pixel_area"])
    return f"Σ {s_oth:.6g} (rel. {dsum:+.1e}), L1 {l1:.1e}"


def fmt(v, digits=2):
    return "—" if v is None else f"{v:.{digits}f}"


def median(recs, key):
    vals = [r[key] for r in recs if r["ok"] and r.get(key) is not None]
    return statistics.median(vals) if vals else None


def ratio(vox, peer):
    return "—" if (vox is None or not peer) else f"{vox / peer:.2f}"


def table(results, a):
    lines = ["| row | program | setup s | render/compute s | process wall s | "
             "ratio voxless/peer (compute) | ratio voxless/peer (wall) | peak RSS MB | agreement with voxless |",
             "|---|---|---:|---:|---:|---:|---:|---:|---|"]
    for row, progs in results:
        ref_name, ref_recs = progs[0]
        ref_c, ref_w = median(ref_recs, "compute"), median(ref_recs, "wall")
        for i, (name, recs) in enumerate(progs):
            c, w, s = median(recs, "compute"), median(recs, "wall"), median(recs, "setup")
            rss = max((r["rss"] for r in recs if r["ok"]), default=None)
            if not any(r["ok"] for r in recs):
                err = next((r["error"] for r in recs if "error" in r), "failed")
                lines.append(f"| {row['id']} | {name} | failed: {err.replace('|', '/')} ||||||| |")
                continue
            agree = agreement(row, ref_recs[0], recs[0]) if i else (
                "reference" if row["output"] == "png" else agreement(row, ref_recs[0], recs[0]))
            rc = "1.00" if i == 0 else ratio(ref_c, c)
            rw = "1.00" if i == 0 else ratio(ref_w, w)
            lines.append(f"| {row['id']} | {name} | {fmt(s)} | {fmt(c, 3)} | {fmt(w)} | {rc} | {rw} | "
                         f"{fmt(rss, 0)} | {agree} |")
    return "\n".join(lines)


def header(a, versions):
    try:
        vox = os.popen(f"'{a.voxless}' --version").read().strip()
    except OSError:
        vox = "voxless"
    pk = ", ".join(f"{k} {v}" for k, v in versions.items() if v)
    return "\n".join([
        f"# voxless against peers ({datetime.datetime.now().isoformat(timespec='minutes')})",
        "",
        f"- CPU: {C.cpu_model()}, {os.cpu_count()} cores; {a.threads} threads for every program; "
        f"{platform.system()} {platform.release()}",
        f"- {vox}; Python {C.python_version()}; {pk}",
        f"- Interleaved repetitions: {a.reps}; medians. Setup = load + build (for peers: from "
        "process start, imports and a discarded first frame included where noted in README.md); "
        "render/compute = the timed frame or projection; process wall = the whole process. "
        "Ratio < 1: voxless faster.",
        "- Agreement: images, mean abs difference of the sRGB PNGs in 1/255; columns, Σ column × "
        "pixel area (and its difference relative to voxless's) and L1 = Σ|Δ| / Σ|voxless|.",
        "",
        "",
    ])


def main():
    a = parse_args()
    a.voxless = os.path.abspath(a.voxless)
    a.data = os.path.abspath(a.data)
    if not os.access(a.voxless, os.X_OK):
        sys.exit(f"voxless binary not found at {a.voxless}: run `cargo build --release` "
                 "in the repository root first (or pass --voxless PATH)")
    if not os.path.isdir(a.data):
        sys.exit(f"data directory {a.data} not found (pass --data DIR; see README.md)")
    os.makedirs(a.images, exist_ok=True)
    env = C.thread_env(a.threads)
    env["LP_NUM_THREADS"] = str(a.threads)  # Mesa llvmpipe (VTK's offscreen GL)
    wanted = {int(x) for x in a.rows.split(",")}
    results = []
    for row in (r for r in ROWS if r["id"] in wanted):
        missing = [n for n in row["needs"] if not os.path.exists(os.path.join(a.data, n))]
        if missing:
            print(f"row {row['id']} skipped: missing {', '.join(missing)} under {a.data}")
            continue
        print(f"row {row['id']}: {row['title']}")
        if a.peers:
            keep = {p.strip() for p in a.peers.split(",")}
            row = dict(row, programs=[p for i, p in enumerate(row["programs"])
                                      if i == 0 or p[0] in keep])
        recs = {name: [] for name, _ in row["programs"]}
        for rep in range(1, a.reps + 1):
            print(f"  rep {rep}")
            for name, prog in row["programs"]:
                recs[name].append(run_once(row, name, prog, a, rep, env))
        results.append((row, [(name, recs[name]) for name, _ in row["programs"]]))

    versions = C.package_versions(["numpy", "yt", "sarracen", "pynbody", "vtk", "ovito"])
    try:
        import ospray

        versions["OSPRay"] = ospray.version()
    except Exception:
        pass
    titles = "\n".join(f"{row['id']}. {row['title']}" for row, _ in results)
    md = header(a, versions) + titles + "\n\n" + table(results, a) + "\n"
    print()
    print(md)
    if a.out:
        with open(a.out, "w") as f:
            f.write(md)
        print(f"written to {a.out}")


if __name__ == "__main__":
    main()
