// Emission–absorption through a particle volume, one thread per pixel
// sample: the CPU's sample lattice (voxless_render::device::LatticeRay),
// Φ and Θ by a point query of the volume's BVH at each cell's midpoint,
// classification through the transfer function's knots, opacity corrected
// for the segment length, early termination (voxless_render's `march`).

struct Params {
    width: u32,
    height: u32,
    n_particles: u32,
    cluster: u32,
    n_nodes: u32,
    // 0 Gaussians, 1 cubic spline, 2 M5, 3 M6, 4 Wendland C2, 5 C4, 6 C6.
    kernel: u32,
    // 0 no attribute, 1 Θ (post-classification), 2 colours (pre).
    mode: u32,
    light_on: u32,
    early: f32,
    opacity_scale: f32,
    v_lo: f32,
    v_span: f32,
    a_lo: f32,
    a_span: f32,
    log_scale: u32,
    ambient: f32,
    light: vec3<f32>,
    knots: u32,
};

// (origin, t0), (direction, dt), (lo, hi, -, -).
struct Ray {
    o: vec4<f32>,
    d: vec4<f32>,
    span: vec4<f32>,
};

struct Particle {
    x: f32, y: f32, z: f32, support2: f32, shape: f32, amp: f32,
};

struct Node {
    min_x: f32, min_y: f32, min_z: f32,
    max_x: f32, max_y: f32, max_z: f32,
    index: u32,
    leaf: u32,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> rays: array<Ray>;
@group(0) @binding(2) var<storage, read> particles: array<Particle>;
@group(0) @binding(3) var<storage, read> attr: array<f32>;
@group(0) @binding(4) var<storage, read> nodes: array<Node>;
@group(0) @binding(5) var<storage, read> lut: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out: array<vec4<f32>>;
// Per pixel: the next lattice cell to walk, or DONE.
@group(0) @binding(7) var<storage, read_write> next_cell: array<u32>;
// How many rays stopped for want of budget (the host dispatches again).
@group(0) @binding(8) var<storage, read_write> pending: atomic<u32>;

const DONE: u32 = 0xffffffffu;

// Loop iterations this invocation has run (every loop counts: the march,
// the BVH walk, a leaf's particles). Mesa's llvmpipe/lavapipe ends every
// loop of an invocation once 65,535 iterations in all have run (one
// limiter per shader function, not per loop), which cut long dense rays
// short (the limiter is shared by a SIMD group of eight invocations, so the
// budget there is an eighth of it); so an invocation stops at BUDGET,
// saves where its ray is, and the next dispatch goes on from there. On
// hardware GPUs the same split keeps each dispatch short (no driver
// watchdog). Set per adapter (march.rs).
var<private> work: u32 = 0u;
override BUDGET: u32 = 262144u;


fn tp(k: f32, q: f32) -> f32 {
    return max(k - q, 0.0);
}

// e^x as the CPU's lanes compute it (voxless_core::simd::exp: a degree-6
// polynomial on the reduced argument, the exponent put in by bits), so
// Gaussian kernels and opacities get the CPU's bits where the inputs agree.
fn exp_cpu(x0: f32) -> f32 {
    let flush = x0 < -87.33654;
    let x = clamp(x0, -87.33654, 89.0);
    // The CPU rounds by adding and subtracting 2²³ + 127; a shader compiler
    // may fold that away, so `round` (to nearest, ties to even: the same).
    let n = round(x * 1.442695);
    let r = (x - n * 0.6933594) - n * -0.00021219444;
    var p = 0.00019875691;
    p = p * r + 0.0013981999;
    p = p * r + 0.008333452;
    p = p * r + 0.041665796;
    p = p * r + 0.16666666;
    p = p * r + 0.5;
    let e = (p * r * r + r) + 1.0;
    let v = e * bitcast<f32>(u32(i32(n) + 127) << 23u);
    return select(v, 0.0, flush);
}

// w(q) of the SPH kernels (σ and 1/h³ are in the amplitude), in the
// arithmetic of the CPU's lanes (kernel::sph `w_simd`, the cubic spline's
// `cubic_parts`). Written without early returns, as the rest of the shader.
fn sph_w(kind: u32, q: f32) -> f32 {
    var w = 0.0;
    if (kind == 1u) {
        let inner = 1.0 + q * q * (0.75 * q - 1.5);
        let t = 2.0 - q;
        let outer = 0.25 * t * t * t;
        w = select(select(0.0, outer, q < 2.0), inner, q < 1.0);
    } else if (kind == 2u) {
        let a = tp(2.5, q);
        let b = tp(1.5, q);
        let c = tp(0.5, q);
        w = (a * a) * (a * a) - 5.0 * ((b * b) * (b * b)) + 10.0 * ((c * c) * (c * c));
    } else if (kind == 3u) {
        let a = tp(3.0, q);
        let b = tp(2.0, q);
        let c = tp(1.0, q);
        w = (a * a) * (a * a) * a - 6.0 * ((b * b) * (b * b) * b) + 15.0 * ((c * c) * (c * c) * c);
    } else if (kind == 4u) {
        let t = tp(1.0, 0.5 * q);
        let t2 = t * t;
        w = t2 * t2 * (1.0 + 2.0 * q);
    } else if (kind == 5u) {
        let t = tp(1.0, 0.5 * q);
        let t2 = t * t;
        w = t2 * t2 * t2 * (1.0 + q * (3.0 + q * (35.0 / 12.0)));
    } else {
        let t = tp(1.0, 0.5 * q);
        let t2 = t * t;
        let t4 = t2 * t2;
        w = t4 * t4 * (1.0 + q * (4.0 + q * (6.25 + q * 4.0)));
    }
    return w;
}

// w'(q)/q (its limit w''(0) at q = 0).
fn sph_dw_over_q(kind: u32, q: f32) -> f32 {
    var g = 0.0;
    if (kind == 1u) {
        if (q < 1.0) {
            g = 2.25 * q - 3.0;
        } else if (q < 2.0) {
            let t = 2.0 - q;
            g = -0.75 * t * t / q;
        }
    } else if (kind == 2u) {
        if (q <= 0.0) {
            g = -30.0;
        } else {
            let a = tp(2.5, q);
            let b = tp(1.5, q);
            let c = tp(0.5, q);
            g = (-4.0 * a * a * a + 20.0 * b * b * b - 40.0 * c * c * c) / q;
        }
    } else if (kind == 3u) {
        if (q <= 0.0) {
            g = -120.0;
        } else {
            let a = pow(tp(3.0, q), 4.0);
            let b = pow(tp(2.0, q), 4.0);
            let c = pow(tp(1.0, q), 4.0);
            g = (-5.0 * a + 30.0 * b - 75.0 * c) / q;
        }
    } else if (kind == 4u) {
        g = -5.0 * pow(tp(1.0, 0.5 * q), 3.0);
    } else if (kind == 5u) {
        g = -(14.0 / 3.0) * pow(tp(1.0, 0.5 * q), 5.0) * (1.0 + 2.5 * q);
    } else {
        g = -5.5 * pow(tp(1.0, 0.5 * q), 7.0) * (1.0 + q * (3.5 + q * 4.0));
    }
    return g;
}

struct Field {
    density: f32,
    attr_sum: f32,
    color: vec3<f32>,
    grad: vec3<f32>,
    covered: bool,
};

fn contains(n: Node, p: vec3<f32>) -> bool {
    return p.x >= n.min_x && p.x <= n.max_x && p.y >= n.min_y && p.y <= n.max_y
        && p.z >= n.min_z && p.z <= n.max_z;
}

// Φ, Θ's numerator, the pre-classified colour sum and ∇Φ at p: the
// particles of every BVH leaf whose box holds p, depth first, left child
// first (the CPU's order). One flat loop without `continue` (lavapipe
// miscompiled nested loops with `continue` under divergence: rays of one
// workgroup got each other's sums).
fn field(p: vec3<f32>) -> Field {
    var f = Field(0.0, 0.0, vec3<f32>(0.0), vec3<f32>(0.0), false);
    var stack: array<u32, 128>;
    var sp = 0u;
    var i = 0u;
    var more = P.n_nodes > 0u;
    while (more) {
        work++;
        let nd = nodes[i];
        var pop = true;
        if (contains(nd, p)) {
            if (nd.leaf != 0u) {
                let first = nd.index * P.cluster;
                let end = min(first + P.cluster, P.n_particles);
                for (var j = first; j < end; j++) {
                    work++;
                    let q = particles[j];
                    let d = p - vec3<f32>(q.x, q.y, q.z);
                    let d2 = dot(d, d);
                    if (d2 <= q.support2) {
                        f.covered = true;
                        var v = 0.0;
                        var g = 0.0;
                        if (P.kernel == 0u) {
                            v = q.amp * exp_cpu(-q.shape * d2);
                            g = -2.0 * q.shape * v;
                        } else {
                            let qq = sqrt(d2) * q.shape;
                            v = q.amp * sph_w(P.kernel, qq);
                            if (P.light_on != 0u) {
                                g = q.amp * q.shape * q.shape * sph_dw_over_q(P.kernel, qq);
                            }
                        }
                        f.density += v;
                        if (P.light_on != 0u) { f.grad += d * g; }
                        if (P.mode == 1u) {
                            f.attr_sum += v * attr[j];
                        } else if (P.mode == 2u) {
                            f.color += v * vec3<f32>(attr[3u * j], attr[3u * j + 1u], attr[3u * j + 2u]);
                        }
                    }
                }
            } else {
                // The left child next, the right one later.
                if (sp < 128u) {
                    stack[sp] = i + nd.index;
                    sp++;
                }
                i++;
                pop = false;
            }
        }
        if (pop) {
            if (sp == 0u) {
                more = false;
            } else {
                sp--;
                i = stack[sp];
            }
        }
    }
    return f;
}

fn normalize_range(v: f32, lo: f32, span: f32) -> f32 {
    if (span > 0.0) { return clamp((v - lo) / span, 0.0, 1.0); }
    return 0.0;
}

// The transfer function at normalised x: (r, g, b, opacity).
fn classify(x: f32) -> vec4<f32> {
    let last = f32(P.knots - 1u);
    let f = clamp(x, 0.0, 1.0) * last;
    let i = min(u32(f), P.knots - 2u);
    let s = clamp(f - f32(i), 0.0, 1.0);
    return lut[i] * (1.0 - s) + lut[i + 1u] * s;
}

fn shade(g: vec3<f32>) -> f32 {
    let l = length(g);
    if (!(l > 0.0)) { return 1.0; }
    return P.ambient + (1.0 - P.ambient) * abs(dot(g / l, P.light));
}

// The workgroup's shape, set per adapter (march.rs): 8×8 on GPUs; one
// column of 64 on software rasterisers (lavapipe's vectorised rows of
// pixels differ from the CPU in the last bits; a column is the CPU's bit
// for bit in the tests).
override WX: u32 = 8u;
override WY: u32 = 8u;

@compute @workgroup_size(WX, WY)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= P.width || id.y >= P.height) { return; }
    let at = id.y * P.width + id.x;
    var k = next_cell[at];
    if (k == DONE) { return; }
    let ray = rays[at];
    let t0 = ray.o.w;
    let dt = ray.d.w;
    let lo = ray.span.x;
    let hi = ray.span.y;
    let o = ray.o.xyz;
    let dir = ray.d.xyz;
    // This ray's lattice cells (a bound: no walk runs away on a bad step).
    var cells = 0u;
    if (lo < hi && dt > 0.0) {
        cells = u32(min((hi - t0) / dt + 2.0, 1.0e8));
    }
    // Where the previous dispatch left the ray (zero at the start).
    let held = out[at];
    var color = held.rgb;
    var alpha = held.a;
    var done = true;
    loop {
        if (k >= cells) {
            break;
        }
        if (work >= BUDGET) {
            // Out of budget: the next dispatch goes on from cell k.
            done = false;
            break;
        }
        work++;
        let b0 = max(t0 + f32(k) * dt, lo);
        let b1 = min(t0 + f32(k + 1u) * dt, hi);
        k++;
        if (b0 >= hi) {
            break;
        }
        if (b1 > b0) {
            let len = b1 - b0;
            let m = b0 + 0.5 * len;
            let f = field(o + dir * m);
            if (f.covered) {
                var x: f32;
                if (P.log_scale != 0u) {
                    x = select(0.0, normalize_range(log(f.density) / log(10.0), P.v_lo, P.v_span), f.density > 0.0);
                } else {
                    x = normalize_range(f.density, P.v_lo, P.v_span);
                }
                let co = classify(x);
                var c = co.rgb;
                if (f.density > 0.0) {
                    if (P.mode == 1u) {
                        c = classify(normalize_range(f.attr_sum / f.density, P.a_lo, P.a_span)).rgb;
                    } else if (P.mode == 2u) {
                        c = f.color / f.density;
                    }
                }
                if (co.a > 0.0) {
                    let a = 1.0 - exp_cpu(-co.a * P.opacity_scale * len);
                    if (P.light_on != 0u) { c = c * shade(f.grad); }
                    color += c * ((1.0 - alpha) * a);
                    alpha += (1.0 - alpha) * a;
                    if (alpha >= P.early) {
                        break;
                    }
                }
            }
        }
    }
    out[at] = vec4<f32>(color, alpha);
    if (done) {
        next_cell[at] = DONE;
    } else {
        next_cell[at] = k;
        atomicAdd(&pending, 1u);
    }
}
