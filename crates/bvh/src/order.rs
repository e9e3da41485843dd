//! Space-filling-curve keys: Morton (Z-order) and Hilbert, 21 bits per axis.
//!
//! Both map a point quantised to a 2^21 lattice over some bounds to a 63-bit
//! key; sorting by the key puts points that are close in space close in memory.
//! Hilbert order has no long jumps (consecutive keys are face-adjacent cells),
//! which makes runs of consecutive particles compact clusters; Morton order is
//! cheaper and its bit prefixes define the LBVH hierarchy.

use voxless_core::{Aabb, Vec3};

/// Bits per axis of the lattice.
pub const KEY_BITS: u32 = 21;

/// Quantises `p` to the 2^21 lattice over `bounds` (clamped; NaN → 0).
pub fn quantize(p: Vec3, bounds: &Aabb) -> [u32; 3] {
    let max = ((1u32 << KEY_BITS) - 1) as f32;
    let e = bounds.extent();
    let q = |v: f32, lo: f32, len: f32| {
        let s = if len > 0.0 { (v - lo) / len } else { 0.0 };
        // `as u32` saturates and maps NaN to 0.
        (s * max).clamp(0.0, max) as u32
    };
    [
        q(p.x, bounds.min.x, e.x),
        q(p.y, bounds.min.y, e.y),
        q(p.z, bounds.min.z, e.z),
    ]
}

/// Spreads the low 21 bits of `v` so that two zero bits follow each.
fn spread_bits(v: u32) -> u64 {
    let mut x = (v as u64) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Morton key of a lattice point (x in the highest bit of each triple).
pub fn morton(c: [u32; 3]) -> u64 {
    (spread_bits(c[0]) << 2) | (spread_bits(c[1]) << 1) | spread_bits(c[2])
}

/// Hilbert key of a lattice point (Skilling's transpose algorithm, "Programming
/// the Hilbert curve", AIP Conf. Proc. 707, 2004), 21 bits per axis.
pub fn hilbert(c: [u32; 3]) -> u64 {
    let mut x = c;
    let m = 1u32 << (KEY_BITS - 1);
    // Undo excess work: walk bits from the top, inverting or exchanging the
    // low bits so each sub-cube is visited in curve orientation.
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    // Gray encode.
    x[1] ^= x[0];
    x[2] ^= x[1];
    let mut t = 0;
    let mut q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for v in x.iter_mut() {
        *v ^= t;
    }
    // The transposed form holds the key's bits spread over the three axes,
    // most significant first: interleave them.
    morton(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keys of an 8³ sub-lattice: the Hilbert curve must visit every cell once
    /// and step only between face neighbours.
    #[test]
    fn hilbert_is_a_face_adjacent_bijection() {
        let shift = KEY_BITS - 3;
        let mut cells: Vec<(u64, [u32; 3])> = Vec::new();
        for x in 0..8u32 {
            for y in 0..8u32 {
                for z in 0..8u32 {
                    cells.push((hilbert([x << shift, y << shift, z << shift]), [x, y, z]));
                }
            }
        }
        cells.sort();
        cells.dedup_by_key(|c| c.0);
        assert_eq!(cells.len(), 512);
        for w in cells.windows(2) {
            let d: u32 = (0..3).map(|a| w[0].1[a].abs_diff(w[1].1[a])).sum();
            assert_eq!(d, 1, "{:?} -> {:?}", w[0].1, w[1].1);
        }
    }

    #[test]
    fn morton_interleaves() {
        assert_eq!(morton([1, 0, 0]), 0b100);
        assert_eq!(morton([0, 1, 0]), 0b010);
        assert_eq!(morton([0, 0, 1]), 0b001);
        assert_eq!(morton([3, 3, 3]), 0b111111);
        let top = (1u32 << KEY_BITS) - 1;
        assert_eq!(morton([top, top, top]), (1u64 << 63) - 1);
    }
}
