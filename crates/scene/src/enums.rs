//! The closed choices of a scene, typed: serde names them in TOML (kebab
//! case, with the aliases users type) and, with the `clap` feature, clap
//! lists them in `--help` and rejects anything else before any work starts.

use serde::{Deserialize, Serialize};

/// Declares a fieldless enum with serde names, aliases, a `name()` and
/// (feature `clap`) a `ValueEnum` with the same names and aliases.
macro_rules! choice {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $( $(#[doc = $doc:literal])* $variant:ident = $text:literal $(| $alias:literal)* ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
        #[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
        pub enum $name {
            $(
                $(#[doc = $doc])*
                #[serde(rename = $text $(, alias = $alias)*)]
                #[cfg_attr(feature = "clap", value(name = $text $(, alias = $alias)*))]
                $variant,
            )+
        }

        impl $name {
            /// The name used in scene files and on the command line.
            pub fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $text,)+
                }
            }
            /// Every choice, in declaration order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

choice! {
    /// The radial basis function of each particle.
    pub enum KernelName {
        /// A Gaussian truncated at 3σ (radius = support).
        Gaussian3 = "gaussian3",
        /// κ·k·exp(−d²/2r²) truncated at σ·r (radius = standard deviation).
        Gaussian = "gaussian",
        /// The SPH M4 cubic spline (radius = smoothing length h, support 2h).
        CubicSpline = "cubic-spline" | "cubic" | "m4",
        /// The SPH M5 quartic spline (radius = h, support 2.5h).
        QuarticSpline = "quartic-spline" | "quartic" | "m5",
        /// The SPH M6 quintic spline (radius = h, support 3h).
        QuinticSpline = "quintic-spline" | "quintic" | "m6",
        /// Wendland C2 (radius = h, support 2h as in PHANTOM).
        WendlandC2 = "wendland-c2",
        /// Wendland C4 (radius = h, support 2h as in PHANTOM).
        WendlandC4 = "wendland-c4",
        /// Wendland C6 (radius = h, support 2h as in PHANTOM).
        WendlandC6 = "wendland-c6",
    }
}

choice! {
    /// How a particle attribute becomes colour.
    pub enum ClassificationName {
        /// Average the attribute, then colour-map it.
        Post = "post",
        /// Colour-map each particle's attribute, then average the colours.
        Pre = "pre",
    }
}

choice! {
    /// How an AMR field is reconstructed between cell centres.
    pub enum ReconstructionName {
        /// Tent basis functions: smooth and seam-free across levels.
        Basis = "basis",
        /// The value of the cell containing the point.
        Nearest = "nearest",
        /// Trilinear on the dual grid in level-aware octant boxes (Open
        /// VKL's `octant`): crack-free iso-surfaces across levels.
        Octant = "octant",
    }
}

choice! {
    /// How a tessellation's crossing events become colour.
    pub enum TetModeName {
        /// Every event sorted: exact.
        Exact = "exact",
        /// The first k events exactly, the rest in depth layers (bounded memory).
        Kbuffer = "kbuffer" | "k-buffer",
    }
}

choice! {
    /// How a projection of particles or a tessellation integrates each
    /// pixel.
    pub enum PixelsName {
        /// The column averaged over the pixel's square: the projected mass
        /// is the same at every resolution.
        Area = "area",
        /// The column along the line through the pixel's centre.
        Centre = "centre" | "center",
    }
}

choice! {
    /// How free-flight distances of single scattering are sampled.
    pub enum FreeFlightName {
        /// Stochastic ray marching (one random number per distance).
        Marching = "marching",
        /// Delta tracking with interval majorants (unbiased).
        Delta = "delta" | "delta-tracking",
    }
}

choice! {
    /// Where the free flights' random numbers come from.
    pub enum NoiseName {
        /// Spatiotemporal blue noise.
        Blue = "blue",
        /// Independent (white) noise.
        White = "white",
    }
}

choice! {
    /// Which data frame a camera path's frame shows.
    pub enum FollowName {
        /// The last data frame numbered at or before the path frame.
        Hold = "hold",
        /// The data frame numbered nearest to the path frame.
        Nearest = "nearest",
        /// The data frames spread evenly over the path's frames.
        Stretch = "stretch",
    }
}

choice! {
    /// The camera projection.
    pub enum ProjectionName {
        Perspective = "perspective",
        Orthographic = "orthographic" | "ortho",
    }
}

/// A particle species: a `type` number (LAMMPS, XYZ) or an element symbol
/// (XYZ). TOML may give it as a number (`species = 7`) or a string.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(from = "SpeciesRepr", into = "String")]
pub struct Species(pub String);

#[derive(Deserialize)]
#[serde(untagged)]
enum SpeciesRepr {
    Number(i64),
    Text(String),
}

impl From<SpeciesRepr> for Species {
    fn from(r: SpeciesRepr) -> Self {
        match r {
            SpeciesRepr::Number(n) => Species(n.to_string()),
            SpeciesRepr::Text(s) => Species(s),
        }
    }
}

impl From<Species> for String {
    fn from(s: Species) -> String {
        s.0
    }
}

impl From<&str> for Species {
    fn from(s: &str) -> Self {
        Species(s.to_string())
    }
}

impl std::fmt::Display for Species {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

choice! {
    /// A coordinate axis.
    pub enum AxisName {
        X = "x",
        Y = "y",
        Z = "z",
    }
}
