/// Why a particle set or its settings cannot be used. Indices are positions
/// in the input arrays (before any reordering), so users can find the row.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParticleError {
    #[error("no particles")]
    Empty,
    #[error("particle {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinitePosition {
        index: usize,
        x: f32,
        y: f32,
        z: f32,
    },
    #[error("{what} has {got} values but there are {expected} particles")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("particle {index} has radius {value}; radii must be finite and > 0")]
    BadRadius { index: usize, value: f32 },
    #[error("global radius {value} must be finite and > 0")]
    BadGlobalRadius { value: f32 },
    #[error("particle {index} has {what} {value}; it must be finite")]
    NonFiniteValue {
        index: usize,
        what: &'static str,
        value: f32,
    },
    #[error("particle {index} has weight {value}; weights must be finite and >= 0")]
    BadWeight { index: usize, value: f32 },
    #[error("cluster size {value} is outside 1..=16")]
    BadClusterSize { value: usize },
    #[error("kernel parameter {name} = {value} must be finite and > 0")]
    BadKernelParameter { name: &'static str, value: f32 },
    #[error("{what} given, but the particles have no attribute")]
    NeedsAttribute { what: &'static str },
    #[error(
        "radius too large: the median support radius {support} exceeds the extent of the data ({extent}), so every sample would sum nearly every one of the {count} particles; use a smaller radius"
    )]
    HugeRadius {
        support: f32,
        extent: f32,
        count: usize,
    },
    #[error("periodic box [{lo:?}, {hi:?}] is not a box: every side must be finite and > 0")]
    BadBox { lo: [f32; 3], hi: [f32; 3] },
    #[error(
        "particle {index}'s support radius {support} reaches more than 3 boxes (side {size}) beyond the periodic box; use a smaller radius"
    )]
    SupportBeyondBox {
        index: usize,
        support: f32,
        size: f32,
    },
    #[error(
        "neighbours N = {n}: needs 2 ≤ N ≤ the particle count ({count}), the particle itself counted"
    )]
    BadNeighbours { n: usize, count: usize },
    #[error(
        "particle {index} has {others} other particle(s) at its own position, so its distance to its N-th neighbour is 0; use a larger N or give radii"
    )]
    CoincidentNeighbours { index: usize, others: usize },
    #[error("too many particles ({count}); at most {max} per volume")]
    TooMany { count: usize, max: usize },
    /// The work was cancelled (through its `Control`).
    #[error("cancelled")]
    Cancelled,
    /// The device summing a projection (the GPU backend) failed.
    #[error("{0}")]
    Device(String),
}
