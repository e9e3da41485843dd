#!/usr/bin/env python3
"""Generate the colormap lookup tables used by the voxless-transfer crate.

This script prints a Rust source file containing 256-entry sRGB colormap
tables (`[[f32; 3]; 256]`, values in [0, 1]):

* VIRIDIS, INFERNO, MAGMA, PLASMA -- the published perceptually uniform
  tables by Stéfan van der Walt and Nathaniel Smith, copied verbatim from
  matplotlib's listed colormaps (`matplotlib._cm_listed._<name>_data`).
* CIVIDIS -- the published table by Nuñez, Anderton and Renslow (2018),
  also copied verbatim from `matplotlib._cm_listed._cividis_data`.
* GRAY -- a linear ramp, i / 255 in every channel.
* COOL_WARM -- ParaView's "Cool to Warm" diverging map, computed here with
  Kenneth Moreland's Msh interpolation ("Diverging Color Maps for
  Scientific Visualization", 2009) between the sRGB endpoints
  (0.23137254902, 0.298039215686, 0.752941176471) and
  (0.705882352941, 0.0156862745098, 0.149019607843), sampled at s = i / 255.

The COOL_WARM table is validated against matplotlib's `coolwarm` (which was
derived from 33 knots of Moreland's table); see `validate_cool_warm` for the
exact checks and tolerances.  The midpoint must also be approximately
(0.865, 0.865, 0.865).  The script raises (and prints nothing) if a check fails.

Requirements: python3 with numpy and matplotlib (`pip install matplotlib numpy`).

Usage (from the repository root):

    python3 tools/gen_colormaps.py > crates/transfer/src/tables.rs
"""

import math
import sys

import matplotlib
import matplotlib._cm
import matplotlib._cm_listed as cm_listed
import numpy as np

N = 256

# ---------------------------------------------------------------------------
# Moreland's Msh colour space (sRGB -> linear RGB -> XYZ (D65) -> CIELAB -> Msh)
# ---------------------------------------------------------------------------

# D65 reference white.
XN, YN, ZN = 0.95047, 1.0, 1.08883

RGB_TO_XYZ = np.array(
    [
        [0.4124, 0.3576, 0.1805],
        [0.2126, 0.7152, 0.0722],
        [0.0193, 0.1192, 0.9505],
    ]
)
XYZ_TO_RGB = np.linalg.inv(RGB_TO_XYZ)


def srgb_to_linear(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def linear_to_srgb(c):
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1.0 / 2.4) - 0.055


def _lab_f(t):
    return t ** (1.0 / 3.0) if t > 0.008856 else 7.787 * t + 16.0 / 116.0


def _lab_finv(t):
    return t**3 if t > 0.20689 else (t - 16.0 / 116.0) / 7.787


def srgb_to_msh(rgb):
    lin = np.array([srgb_to_linear(c) for c in rgb])
    x, y, z = RGB_TO_XYZ @ lin
    fx, fy, fz = _lab_f(x / XN), _lab_f(y / YN), _lab_f(z / ZN)
    L = 116.0 * fy - 16.0
    a = 500.0 * (fx - fy)
    b = 200.0 * (fy - fz)
    m = math.sqrt(L * L + a * a + b * b)
    s = math.acos(L / m) if m > 0.001 else 0.0
    h = math.atan2(b, a) if s > 0.001 else 0.0
    return m, s, h


def msh_to_srgb(m, s, h):
    L = m * math.cos(s)
    a = m * math.sin(s) * math.cos(h)
    b = m * math.sin(s) * math.sin(h)
    fy = (L + 16.0) / 116.0
    fx = fy + a / 500.0
    fz = fy - b / 200.0
    xyz = np.array([XN * _lab_finv(fx), YN * _lab_finv(fy), ZN * _lab_finv(fz)])
    lin = XYZ_TO_RGB @ xyz
    return [min(1.0, max(0.0, linear_to_srgb(c))) for c in lin]


def adjust_hue(m_sat, s_sat, h_sat, m_unsat):
    """Moreland's hue spin for interpolating toward an unsaturated colour."""
    if m_sat >= m_unsat:
        return h_sat
    h_spin = s_sat * math.sqrt(m_unsat**2 - m_sat**2) / (m_sat * math.sin(s_sat))
    if h_sat > -math.pi / 3.0:
        return h_sat + h_spin
    return h_sat - h_spin


def interpolate_diverging(rgb1, rgb2, interp):
    """Moreland's diverging interpolation in Msh space, interp in [0, 1]."""
    m1, s1, h1 = srgb_to_msh(rgb1)
    m2, s2, h2 = srgb_to_msh(rgb2)
    # Insert a white midpoint when both ends are saturated and far apart in hue.
    if s1 > 0.05 and s2 > 0.05 and abs(h1 - h2) > math.pi / 3.0:
        m_mid = max(m1, m2, 88.0)
        if interp < 0.5:
            m2, s2, h2 = m_mid, 0.0, 0.0
            interp = 2.0 * interp
        else:
            m1, s1, h1 = m_mid, 0.0, 0.0
            interp = 2.0 * interp - 1.0
    # Spin the hue of an unsaturated end toward the saturated one.
    if s1 < 0.05 and s2 > 0.05:
        h1 = adjust_hue(m2, s2, h2, m1)
    elif s2 < 0.05 and s1 > 0.05:
        h2 = adjust_hue(m1, s1, h1, m2)
    m = (1.0 - interp) * m1 + interp * m2
    s = (1.0 - interp) * s1 + interp * s2
    h = (1.0 - interp) * h1 + interp * h2
    return msh_to_srgb(m, s, h)


COOL = (0.23137254902, 0.298039215686, 0.752941176471)
WARM = (0.705882352941, 0.0156862745098, 0.149019607843)


def cool_warm_table():
    return [interpolate_diverging(COOL, WARM, i / (N - 1)) for i in range(N)]


def validate_cool_warm(table):
    """Check COOL_WARM against matplotlib's `coolwarm`; raise on failure.

    matplotlib's `coolwarm` is a LinearSegmentedColormap built from 33 knots
    of Moreland's published table (s = k/32), linearly interpolated in sRGB
    between knots.  Three checks, all with a tolerance of 2/255 per channel:

    1. at the 33 knots, our Msh interpolation must reproduce matplotlib's
       (i.e. Moreland's published) values;
    2. at all 256 samples s = i/255, our Msh curve resampled the way
       matplotlib does it (33 knots, linear in between) must reproduce
       matplotlib's `coolwarm` -- this isolates the algorithm from
       matplotlib's coarse resampling;
    3. at all 256 samples, our table itself must agree with matplotlib's
       `coolwarm`.  Near s = 1 the green channel bends sharply, and the
       linear segment between the last two knots of matplotlib's table cuts
       the corner by up to ~4.6/255 (at i = 249..254).  So this direct check
       allows 5/255 and reports the exact figure.

    Also checks the midpoint is ~(0.865, 0.865, 0.865).
    """
    tol = 2.0 / 255.0
    cmap = matplotlib.colormaps["coolwarm"]
    seg = matplotlib._cm._coolwarm_data
    knots = np.array([row[0] for row in seg["red"]])
    knot_ref = np.array([[seg[ch][k][1] for ch in ("red", "green", "blue")]
                         for k in range(len(knots))])
    knot_ours = np.array([interpolate_diverging(COOL, WARM, s) for s in knots])
    knot_dev = float(np.max(np.abs(knot_ours - knot_ref)))
    if knot_dev > tol:
        raise AssertionError(
            f"COOL_WARM deviates from Moreland's table (matplotlib coolwarm knots) "
            f"by {knot_dev:.6f} (> 2/255)"
        )

    samples = np.linspace(0.0, 1.0, N)
    ref = cmap(samples)[:, :3]
    resampled = np.stack([np.interp(samples, knots, knot_ours[:, c]) for c in range(3)], axis=1)
    resampled_dev = float(np.max(np.abs(resampled - ref)))
    if resampled_dev > tol:
        raise AssertionError(
            f"COOL_WARM resampled on matplotlib's knots deviates from matplotlib "
            f"coolwarm by {resampled_dev:.6f} (> 2/255)"
        )

    dev = float(np.max(np.abs(np.array(table) - ref)))
    if dev > 5.0 / 255.0:
        raise AssertionError(
            f"COOL_WARM deviates from matplotlib coolwarm by {dev:.6f} (> 5/255)"
        )

    mid = interpolate_diverging(COOL, WARM, 0.5)
    if any(abs(c - 0.865) > 0.002 for c in mid):
        raise AssertionError(f"COOL_WARM midpoint {mid} is not ~(0.865, 0.865, 0.865)")
    return knot_dev, resampled_dev, dev, mid


# ---------------------------------------------------------------------------
# Output
# ---------------------------------------------------------------------------


def emit(out, name, doc, table):
    assert len(table) == N, name
    out.append(f"/// {doc}")
    out.append("#[allow(clippy::excessive_precision)]")
    out.append(f"pub const {name}: [[f32; 3]; {N}] = [")
    for r, g, b in table:
        for c in (r, g, b):
            assert 0.0 <= c <= 1.0, (name, c)
        out.append(f"    [{r:.8f}, {g:.8f}, {b:.8f}],")
    out.append("];")
    out.append("")


def main():
    listed = {
        name: [list(map(float, row)) for row in getattr(cm_listed, f"_{name}_data")]
        for name in ("viridis", "inferno", "magma", "plasma", "cividis")
    }
    gray = [[i / (N - 1)] * 3 for i in range(N)]
    cool_warm = cool_warm_table()
    knot_dev, resampled_dev, dev, mid = validate_cool_warm(cool_warm)
    print(
        f"gen_colormaps: COOL_WARM vs matplotlib coolwarm: at its 33 knots "
        f"{knot_dev:.6f} ({knot_dev * 255:.3f}/255); resampled on its knots "
        f"{resampled_dev:.6f} ({resampled_dev * 255:.3f}/255); direct, all 256 "
        f"samples {dev:.6f} ({dev * 255:.3f}/255); midpoint = "
        f"({mid[0]:.6f}, {mid[1]:.6f}, {mid[2]:.6f})",
        file=sys.stderr,
    )

    mpl = f"matplotlib {matplotlib.__version__}"
    out = [
        "// Generated by tools/gen_colormaps.py — do not edit by hand.",
        "// Regenerate with: python3 tools/gen_colormaps.py > crates/transfer/src/tables.rs",
        "//",
        f"// VIRIDIS: van der Walt & Smith published table, matplotlib._cm_listed._viridis_data ({mpl}).",
        f"// INFERNO: van der Walt & Smith published table, matplotlib._cm_listed._inferno_data ({mpl}).",
        f"// MAGMA: van der Walt & Smith published table, matplotlib._cm_listed._magma_data ({mpl}).",
        f"// PLASMA: van der Walt & Smith published table, matplotlib._cm_listed._plasma_data ({mpl}).",
        f"// CIVIDIS: Nuñez, Anderton & Renslow (2018) published table, matplotlib._cm_listed._cividis_data ({mpl}).",
        "// GRAY: linear ramp, i / 255 in every channel.",
        "// COOL_WARM: ParaView \"Cool to Warm\", Moreland (2009) Msh diverging interpolation between",
        "//     sRGB (0.23137254902, 0.298039215686, 0.752941176471) and",
        "//     (0.705882352941, 0.0156862745098, 0.149019607843), sampled at s = i / 255;",
        f"//     max deviation from matplotlib coolwarm: {knot_dev * 255:.2f}/255 at its 33 knots (Moreland's table),",
        f"//     {dev * 255:.2f}/255 over all 256 samples (matplotlib interpolates linearly between knots).",
        "//",
        "// All values are sRGB (gamma-encoded) in [0, 1].",
        "",
    ]
    emit(out, "VIRIDIS", "Viridis (van der Walt & Smith), 256 sRGB entries.", listed["viridis"])
    emit(out, "INFERNO", "Inferno (van der Walt & Smith), 256 sRGB entries.", listed["inferno"])
    emit(out, "MAGMA", "Magma (van der Walt & Smith), 256 sRGB entries.", listed["magma"])
    emit(out, "PLASMA", "Plasma (van der Walt & Smith), 256 sRGB entries.", listed["plasma"])
    emit(out, "CIVIDIS", "Cividis (Nuñez, Anderton & Renslow), 256 sRGB entries.", listed["cividis"])
    emit(out, "GRAY", "Linear gray ramp, i / 255 in every channel.", gray)
    emit(
        out,
        "COOL_WARM",
        "ParaView \"Cool to Warm\" diverging map (Moreland 2009, Msh interpolation), 256 sRGB entries.",
        cool_warm,
    )
    while out and out[-1] == "":
        out.pop()
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
