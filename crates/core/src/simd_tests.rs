//! The lane types against each other, bit for bit, and `exp` against
//! `wide`'s and f64's.

use super::*;

/// Edge cases: signed zeros, subnormals, the normal extremes, infinities,
/// NaN, rounding ties, values outside the i32 range.
const EDGES: [f32; 24] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    2.5,
    -2.5,
    3.0,
    1e-40,
    -1e-40,
    f32::from_bits(1),
    f32::MIN_POSITIVE,
    1e30,
    -1e30,
    f32::MAX,
    f32::MIN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NAN,
    -f32::NAN,
    7.999_999,
    3e9,
    -3e9,
    0.1,
];

/// What `gather` reads: `TABLE[i] = 10 + i`.
const TABLE: [f32; 5] = [10.0, 11.0, 12.0, 13.0, 14.0];

/// Every (a, b) pair of [`EDGES`], eight lanes at a time.
fn pairs() -> Vec<([f32; LANES], [f32; LANES])> {
    let all: Vec<(f32, f32)> = EDGES
        .iter()
        .flat_map(|&a| EDGES.iter().map(move |&b| (a, b)))
        .collect();
    all.chunks(LANES)
        .map(|c| {
            let mut a = [0.0; LANES];
            let mut b = [0.0; LANES];
            for (k, &(x, y)) in c.iter().enumerate() {
                (a[k], b[k]) = (x, y);
            }
            (a, b)
        })
        .collect()
}

/// Every operation of `L` on the pairs, as named bit patterns.
struct AllOps;

impl WithLanes for AllOps {
    type Output = (Simd, Vec<(String, [u32; LANES])>);

    #[inline(always)]
    fn run<L: Lanes>(self) -> Self::Output {
        let bits = |v: L| v.to_array().map(f32::to_bits);
        let mut out = Vec::new();
        for (i, (a, b)) in pairs().into_iter().enumerate() {
            let (x, y) = (L::from_array(a), L::from_array(b));
            let m = x.lt(y);
            let mut stored = vec![0.0f32; LANES + 3];
            x.store(&mut stored, 2);
            let loaded = L::load(&stored, 2);
            let trunc = x.trunc_i32().map(|v| v as u32);
            let mut mask = [0u32; LANES];
            mask[0] = m.bitmask();
            mask[1] = m.any() as u32;
            for (name, v) in [
                ("add", bits(x + y)),
                ("sub", bits(x - y)),
                ("mul", bits(x * y)),
                (
                    "mul_add",
                    bits(x.mul_add(y, L::from_array(b).permute(L::iota()))),
                ),
                ("mul_add cancels", bits(x.mul_add(y, L::splat(0.0) - x * y))),
                ("div", bits(x / y)),
                ("and", bits(x & y)),
                ("or", bits(x | y)),
                ("and_not", bits(x.and_not(y))),
                ("min", bits(x.min(y))),
                ("max", bits(x.max(y))),
                ("sqrt", bits(x.sqrt())),
                ("abs", bits(x.abs())),
                ("lt", bits(x.lt(y))),
                ("le", bits(x.le(y))),
                ("gt", bits(x.gt(y))),
                ("ge", bits(x.ge(y))),
                ("select", bits(m.select(x, y))),
                ("shl23", bits(x.shl23())),
                ("shr23", bits(x.shr23())),
                ("permute", bits(y.permute(x.shr23()))),
                (
                    "permute bits",
                    bits(x.permute(L::from_bits(b.map(f32::to_bits)))),
                ),
                ("exp", bits(x.exp())),
                ("splat", bits(L::splat(a[i % LANES]))),
                ("from_bits", bits(L::from_bits(b.map(f32::to_bits)))),
                ("load/store", bits(loaded)),
                ("trunc_i32", trunc),
                ("gather", bits(L::gather(&TABLE, x))),
                ("gather empty", bits(L::gather(&[], x))),
                ("trunc", bits(x.trunc())),
                ("add_product_f64", {
                    let mut acc = [0.25f64; LANES];
                    L::add_product_f64(&mut acc, x, y);
                    L::add_product_f64(&mut acc, y, x);
                    acc.map(|v| (v.to_bits() ^ (v.to_bits() >> 32)) as u32)
                }),
                ("add_f64_halves", {
                    let (mut lo, mut hi) = ([0.25f64; 4], [-1.5f64; 4]);
                    L::add_f64_halves(&mut lo, &mut hi, x);
                    L::add_f64_halves(&mut hi, &mut lo, y);
                    let v: [f64; LANES] = std::array::from_fn(|k| [lo, hi][k / 4][k % 4]);
                    v.map(|v| (v.to_bits() ^ (v.to_bits() >> 32)) as u32)
                }),
                ("quotient_f64", {
                    // Sums as the reconstruction forms them, and the
                    // edge cases themselves as denominators (zeros,
                    // negatives, NaN, infinities).
                    let num = a.map(|v| v as f64 * 3.0 + 0.1);
                    let den = b.map(|v| v as f64);
                    bits(L::quotient_f64(&num, &den))
                }),
                ("bitmask/any", mask),
            ] {
                out.push((format!("{name} #{i}"), v));
            }
        }
        for n in 0..=LANES + 1 {
            out.push((format!("first({n})"), bits(L::first(n))));
        }
        out.push(("iota".into(), bits(L::iota())));
        (L::BACKEND, out)
    }
}

#[test]
fn resolve_never_gives_auto_and_clamps_avx2() {
    for s in Simd::ALL {
        let r = s.resolve();
        assert_ne!(r, Simd::Auto);
        assert!(r.available());
        if s == Simd::Portable {
            assert_eq!(r, Simd::Portable);
        }
    }
    assert_eq!(Simd::Auto.resolve(), Simd::Avx2.resolve());
    assert_eq!(Simd::Avx2.resolve() == Simd::Avx2, Simd::Avx2.available());
    assert_eq!(Simd::default(), Simd::Auto);
}

#[test]
fn dispatch_runs_the_resolved_backend() {
    for s in Simd::ALL {
        assert_eq!(dispatch(s, AllOps).0, s.resolve(), "{s:?}");
    }
}

#[test]
fn avx2_lanes_equal_portable_lanes_bit_for_bit() {
    if !Simd::Avx2.available() {
        eprintln!("notice: no AVX2 on this CPU; only the portable lanes run");
        return;
    }
    let (_, portable) = dispatch(Simd::Portable, AllOps);
    let (_, avx) = dispatch(Simd::Avx2, AllOps);
    assert_eq!(portable.len(), avx.len());
    // The sign and payload of a NaN (inf − inf, say) are not specified by
    // IEEE 754 and differ between the compiler's scalar code and the vector
    // unit; any NaN equals any NaN, every other bit must match.
    let canonical = |v: &[u32]| -> Vec<u32> {
        v.iter()
            .map(|&b| {
                if f32::from_bits(b).is_nan() {
                    0x7fc0_0000
                } else {
                    b
                }
            })
            .collect()
    };
    for ((name, p), (_, a)) in portable.iter().zip(&avx) {
        assert_eq!(
            canonical(&p[..]),
            canonical(&a[..]),
            "{name}: portable {p:08x?} vs avx2 {a:08x?}"
        );
    }
}

#[test]
fn the_quotient_of_f64_sums_is_the_scalar_one() {
    // `(n / d) as f32` where `d > 0`, NaN elsewhere: the reconstruction's
    // `finish_values` on every lane (the backends agree with the portable
    // lanes in the test above).
    let num = [1.0, -2.5, 1e300, 7.0, 0.0, 3.0, 1.0, f64::NAN];
    let den = [3.0, 0.1, 1e-300, 0.0, 2.0, -1.0, f64::NAN, 1.0];
    let got = PortableLanes::quotient_f64(&num, &den).to_array();
    for k in 0..LANES {
        if den[k] > 0.0 {
            let want = (num[k] / den[k]) as f32;
            assert!(
                got[k].to_bits() == want.to_bits() || (got[k].is_nan() && want.is_nan()),
                "lane {k}"
            );
        } else {
            assert!(got[k].is_nan(), "lane {k}: no weight, no value");
        }
    }
}

#[test]
fn lane_semantics_are_the_documented_ones() {
    let l = |a: [f32; LANES]| PortableLanes::from_array(a);
    let nan = f32::NAN;
    let x = l([nan, 1.0, nan, -0.0, 0.0, 2.0, 3.0, -1.0]);
    let y = l([1.0, nan, nan, 0.0, -0.0, 2.0, 1.0, 5.0]);
    // min/max: the second operand on NaN (and on equal values, ±0); x86's
    // `minps`, which other targets need not follow.
    #[cfg(target_arch = "x86_64")]
    {
        let min = Lanes::min(x, y).to_array().map(f32::to_bits);
        let want = [1.0, nan, nan, 0.0, -0.0, 2.0, 1.0, -1.0].map(f32::to_bits);
        assert_eq!(min[..2], want[..2]);
        assert!(f32::from_bits(min[2]).is_nan());
        assert_eq!(min[3..], want[3..]);
        let max = Lanes::max(x, y).to_array().map(f32::to_bits);
        let want = [1.0, nan, nan, 0.0, -0.0, 2.0, 3.0, 5.0].map(f32::to_bits);
        assert_eq!(max[..2], want[..2]);
        assert_eq!(max[3..], want[3..]);
    }
    // Ordered comparisons: false on NaN.
    assert_eq!(x.lt(y).bitmask(), 0b1000_0000);
    assert_eq!(x.le(y).bitmask(), 0b1011_1000);
    assert_eq!(x.gt(y).bitmask(), 0b0100_0000);
    assert_eq!(x.ge(y).bitmask(), 0b0111_1000);
    assert_eq!(PortableLanes::first(3).bitmask(), 0b111);
    assert_eq!(PortableLanes::first(99).bitmask(), 0xFF);
    let t = l([2.9, -2.9, 1e10, nan, 0.0, -0.0, 7.5, -1e10]).trunc_i32();
    #[cfg(target_arch = "x86_64")]
    assert_eq!(t, [2, -2, i32::MIN, i32::MIN, 0, 0, 7, i32::MIN]);
    assert_eq!([t[0], t[1], t[4], t[6]], [2, -2, 0, 7]);
    // gather: truncated, clamped into the table, NaN and negatives at 0.
    let g = PortableLanes::gather(&TABLE, l([0.0, 1.9, 4.0, 4.5, 99.0, -0.7, -5.0, nan]));
    assert_eq!(
        g.to_array(),
        [10.0, 11.0, 14.0, 14.0, 14.0, 10.0, 10.0, 10.0]
    );
    assert_eq!(PortableLanes::gather(&[], g).to_array(), [0.0; LANES]);
    assert_eq!(
        l([-3.0, -0.0, 0.0, 4.0, f32::NEG_INFINITY, 1.0, 1.0, 1.0])
            .abs()
            .to_array(),
        [3.0, 0.0, 0.0, 4.0, f32::INFINITY, 1.0, 1.0, 1.0]
    );
}

/// Distance in units in the last place between two finite non-negative
/// floats.
fn ulps(a: f32, b: f32) -> u32 {
    a.to_bits().abs_diff(b.to_bits())
}

/// `exp` of the dense sweep `lo..hi`, eight at a time.
struct ExpSweep(Vec<f32>);

impl WithLanes for ExpSweep {
    type Output = Vec<f32>;
    #[inline(always)]
    fn run<L: Lanes>(self) -> Vec<f32> {
        self.0
            .chunks_exact(LANES)
            .flat_map(|c| L::load(c, 0).exp().to_array())
            .collect()
    }
}

fn sweep(lo: f32, hi: f32, n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| lo + (hi - lo) * i as f32 / (n - 1) as f32)
        .collect()
}

#[test]
fn exp_is_within_two_ulp_of_wides_and_the_same_on_every_backend() {
    // Every normal result: x from ln 2^−126 up.
    let xs = sweep(EXP_MIN, 88.3, 1 << 20);
    let ours = dispatch(Simd::Portable, ExpSweep(xs.clone()));
    let mut worst = (0, 0.0f32);
    let mut worst_f64 = (0, 0.0f32);
    for (c, e) in xs.chunks_exact(LANES).zip(ours.chunks_exact(LANES)) {
        let w = wide::f32x8::exp(wide::f32x8::new(c.try_into().unwrap())).to_array();
        for k in 0..LANES {
            let d = ulps(e[k], w[k]);
            if d > worst.0 {
                worst = (d, c[k]);
            }
            let d = ulps(e[k], (c[k] as f64).exp() as f32);
            if d > worst_f64.0 {
                worst_f64 = (d, c[k]);
            }
        }
    }
    assert!(
        worst.0 <= 2,
        "{} ulp from wide's exp at {}",
        worst.0,
        worst.1
    );
    assert!(
        worst_f64.0 <= 2,
        "{} ulp from f64 exp at {}",
        worst_f64.0,
        worst_f64.1
    );
    // Subnormal results flush to zero (documented).
    let below = sweep(-110.0, -87.3366, 1 << 12);
    let flushed = dispatch(Simd::Portable, ExpSweep(below.clone()));
    assert!(
        flushed.iter().all(|&e| e == 0.0),
        "no flush below ln 2^-126"
    );
    if Simd::Avx2.available() {
        let avx = dispatch(Simd::Avx2, ExpSweep(below));
        assert!(avx.iter().all(|&e| e == 0.0), "no flush on avx2");
        let avx = dispatch(Simd::Avx2, ExpSweep(xs.clone()));
        let same = ours
            .iter()
            .zip(&avx)
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "exp differs between backends");
    } else {
        eprintln!("notice: no AVX2 on this CPU; exp checked on the portable lanes only");
    }
    // Special values.
    let special = [
        0.0,
        -0.0,
        f32::NEG_INFINITY,
        f32::INFINITY,
        f32::NAN,
        -87.4,
        89.0,
        1.0,
    ];
    let e = dispatch(Simd::Portable, ExpSweep(special.to_vec()));
    assert_eq!(e[0], 1.0);
    assert_eq!(e[1], 1.0);
    assert_eq!(e[2], 0.0);
    assert_eq!(e[3], f32::INFINITY);
    assert!(e[4].is_nan());
    assert_eq!(e[5], 0.0);
    assert_eq!(e[6], f32::INFINITY);
    assert!(ulps(e[7], std::f32::consts::E) <= 1);
}

#[test]
fn scalar_exp_gives_the_bits_of_the_lanes() {
    let mut xs = sweep(-100.0, 90.0, 1 << 18);
    xs.extend(sweep(-1e-3, 1e-3, 1 << 12));
    xs.extend([
        0.0,
        -0.0,
        f32::NEG_INFINITY,
        f32::INFINITY,
        f32::NAN,
        EXP_MIN,
        -87.4,
        88.38,
        89.0,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
    ]);
    xs.resize(xs.len().next_multiple_of(LANES), 1.0);
    let lanes = dispatch(Simd::Portable, ExpSweep(xs.clone()));
    for (x, l) in xs.iter().zip(&lanes) {
        let e = exp(*x);
        assert!(
            e.to_bits() == l.to_bits() || (e.is_nan() && l.is_nan()),
            "exp({x}): scalar {e}, lanes {l}"
        );
    }
}
