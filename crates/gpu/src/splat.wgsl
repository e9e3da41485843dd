// Column densities of plain splats (voxless_particles::splat::PlainSplat):
// one workgroup per 16×16-pixel tile, one thread per pixel, over the
// splats binned to the tile, in order.

struct Params {
    width: u32,
    height: u32,
    tiles_x: u32,
    sph: u32,
    last: f32,
    p0: u32,
    p1: u32,
    p2: u32,
};

struct Splat {
    cx: f32,
    cy: f32,
    ax: f32,
    ay: f32,
    scale: f32,
    g_exp: f32,
    g_erf: f32,
    support2: f32,
    pw2: f32,
    ph2: f32,
    r0: u32,
    r1: u32,
    c0: u32,
    c1: u32,
    p0: u32,
    p1: u32,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(2) var<storage, read> start: array<u32>;
@group(0) @binding(3) var<storage, read> members: array<u32>;
@group(0) @binding(4) var<storage, read> table: array<f32>;
@group(0) @binding(5) var<storage, read_write> image: array<f32>;

// erf(x) for x ≥ 0: Abramowitz & Stegun 7.1.26, absolute error ≤ 1.5e-7.
fn erf_pos(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * x);
    let poly = ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t;
    return 1.0 - poly * exp(-x * x);
}

@compute @workgroup_size(16, 16)
fn main(@builtin(workgroup_id) g: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>) {
    let x = g.x * 16u + l.x;
    let y = g.y * 16u + l.y;
    let tile = g.y * P.tiles_x + g.x;
    let fx = f32(x) + 0.5;
    let fy = f32(y) + 0.5;
    var sum = 0.0;
    for (var k = start[tile]; k < start[tile + 1u]; k++) {
        let s = splats[members[k]];
        if (x < s.c0 || x >= s.c1 || y < s.r0 || y >= s.r1) {
            continue;
        }
        let dx = fx - s.cx;
        let dy = fy - s.cy;
        if (P.sph != 0u) {
            // The table position, as the CPU's lanes compute it.
            let t = dx * dx * s.ax + s.ay * dy * dy;
            if (t < P.last) {
                let at = min(t, P.last - 1.0);
                let i = u32(at);
                let f = at - f32(i);
                let lo = table[i];
                let hi = table[i + 1u];
                sum += (lo + (hi - lo) * f) * s.scale;
            }
        } else {
            // The truncated Gaussian's closed-form column.
            let b2 = dx * dx * s.pw2 + dy * dy * s.ph2;
            if (b2 < s.support2) {
                sum += s.scale * exp(-b2 * s.g_exp) * erf_pos(sqrt(s.support2 - b2) * s.g_erf);
            }
        }
    }
    if (x < P.width && y < P.height) {
        image[y * P.width + x] += sum;
    }
}
