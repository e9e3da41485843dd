#!/usr/bin/env bash
# CPU and GPU renders of the same scenes in one run, interleaved: the dam
# break (23,760 SPH particles, cubic spline, coloured by speed) and, when it
# has been generated, the 16.7M-particle refined JaxPM box; 1024², 1 spp,
# the same camera, transfer function and settings (the CLI's defaults).
# Prints, per set and device: the load + BVH build time, the render's
# milliseconds per frame (median of REPS), the whole process, the GPU
# buffers, and the largest difference between the CPU and GPU images.
#
#   bash benchmarks/gpu/run.sh               # from the project's root
#   REPS=5 SIZE=2048 bash benchmarks/gpu/run.sh
#
# The 16.7M set: python3 tools/refine_lagrangian.py (see docs/benchmarks.md)
# writes target/bench_scale/pos256.npy; BIG=path overrides it.
# On Mesa's software Vulkan (lavapipe) the GPU column is a correctness run on
# the CPU, not GPU speed; its 128 MiB buffer limit refuses the 16.7M set
# (the error names the limit).
set -u
cd "$(dirname "$0")/../.."
REPS=${REPS:-3}
SIZE=${SIZE:-1024}
DATA=${DATA:-../shared/data}
BIG=${BIG:-target/bench_scale/pos256.npy}
cargo build --release -q --features gpu || { echo "the build failed"; exit 1; }
BIN=target/release/voxless
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

echo "# $(date -u +%Y-%m-%d), $(nproc) cores; adapters:"
$BIN info --devices | sed 1d
sets=()
dam=$DATA/sph-dam-break/npy_01000
if [ -f "$dam/positions.npy" ]; then
    sets+=("dam break|--particles $dam/positions.npy --radii $dam/h.npy --weights $dam/mass.npy --kernel cubic-spline --attribute $dam/speed.npy")
else
    echo "note: $dam is missing: the dam break is skipped"
fi
if [ -f "$BIG" ]; then
    sets+=("16.7M particles|--particles $BIG")
else
    echo "note: $BIG is missing: the 16.7M set is skipped (python3 tools/refine_lagrangian.py makes it)"
fi

printf "%-16s %-4s %10s %12s %10s %10s %s\n" set dev "load s" "render ms" "process s" "GPU MiB" "notes"
for entry in "${sets[@]}"; do
    name=${entry%%|*}
    flags=${entry#*|}
    for dev in cpu gpu; do : > "$OUT/$dev.times"; done
    for rep in $(seq "$REPS"); do
        for dev in cpu gpu; do
            # shellcheck disable=SC2086
            /usr/bin/time -f "%e" -o "$OUT/t" $BIN render $flags --size "$SIZE" "$SIZE" \
                --device $dev -o "$OUT/$dev.png" >"$OUT/$dev.log" 2>&1
            rc=$?
            load=$(sed -n 's/^loaded .* in \([0-9.]*\)s.*/\1/p' "$OUT/$dev.log" | tail -1)
            ms=$(sed -n 's/^rendered .* in \([0-9.]*\)s → .*/\1/p' "$OUT/$dev.log" | tail -1)
            mib=$(sed -n 's/^rendered .*(\([0-9.]*\) MiB of buffers).*/\1/p' "$OUT/$dev.log" | tail -1)
            if [ $rc -ne 0 ]; then
                echo "$name $dev: $(grep -m1 '^error' "$OUT/$dev.log")" >"$OUT/$dev.err"
            fi
            echo "${load:-nan} ${ms:-nan} $(cat "$OUT/t" | tail -1) ${mib:--}" >>"$OUT/$dev.times"
        done
    done
    diff=$(python3 - "$OUT" <<'PY'
import sys, zlib, struct
def rgb(path):
    # A minimal PNG reader for the CLI's 8-bit RGB/RGBA output (no filters
    # beyond the five standard ones).
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    i, idat, w = 8, b"", 0
    while i < len(data):
        n, kind = struct.unpack(">I4s", data[i:i + 8])
        body = data[i + 8:i + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            ch = {2: 3, 6: 4}[ctype]
        elif kind == b"IDAT":
            idat += body
        i += 12 + n
    raw, out, prev, stride = zlib.decompress(idat), [], bytearray(w * ch), w * ch
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - ch] if x >= ch else 0
            b = prev[x]
            c = prev[x - ch] if x >= ch else 0
            p = a + b - c
            pr = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else (b if abs(p - b) <= abs(p - c) else c)
            line[x] = (line[x] + [0, a, b, (a + b) // 2, pr][f]) & 255
        out += line
        prev = line
    return out
try:
    a, b = rgb(f"{sys.argv[1]}/cpu.png"), rgb(f"{sys.argv[1]}/gpu.png")
    print(f"max diff {max(abs(x - y) for x, y in zip(a, b))}/255")
except Exception as e:
    print("no image to compare")
PY
)
    for dev in cpu gpu; do
        python3 - "$OUT/$dev.times" "$name" "$dev" "$diff" "$( [ -f "$OUT/$dev.err" ] && cat "$OUT/$dev.err")" <<'PY'
import sys, statistics
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
med = lambda k: statistics.median(float(r[k]) for r in rows)
mib = rows[-1][3]
note = sys.argv[5] or (sys.argv[4] if sys.argv[3] == "gpu" else "")
print(f"{sys.argv[2]:<16} {sys.argv[3]:<4} {med(0):>10.2f} {1e3 * med(1):>12.1f} {med(2):>10.2f} {mib:>10} {note}")
PY
        rm -f "$OUT/$dev.err"
    done
done
