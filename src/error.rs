//! The library's error: every failure names the file (or the setting, or
//! the in-memory array) at fault.

use std::path::PathBuf;

use voxless_amr::AmrError;
use voxless_io::IoError;
use voxless_particles::ParticleError;
use voxless_tets::TetError;
use voxless_transfer::TransferError;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error(transparent)]
    Io(#[from] IoError),
    #[error("{path}: {message}")]
    Toml { path: PathBuf, message: String },
    /// Bad data in a file (or in an in-memory array, named like a file).
    #[error("{path}: {message}")]
    Data { path: PathBuf, message: String },
    #[error("{path}: {source}")]
    Particles {
        path: PathBuf,
        #[source]
        source: ParticleError,
    },
    #[error("{path}: {source}")]
    Amr {
        path: PathBuf,
        #[source]
        source: AmrError,
    },
    #[error("{path}: {source}")]
    Tets {
        path: PathBuf,
        #[source]
        source: TetError,
    },
    /// A setting that cannot be used (named as in the scene file; the CLI
    /// flag of the same name).
    #[error("{field}: {message}")]
    Setting { field: String, message: String },
    /// An output that cannot be written (checked before any work).
    #[error("output {path}: {message}")]
    Output { path: PathBuf, message: String },
    #[error("transfer function: {0}")]
    Transfer(#[from] TransferError),
    #[error(transparent)]
    ColormapFile(#[from] voxless_transfer::ImportError),
}

/// The library's error type.
pub type Error = SceneError;

impl SceneError {
    pub fn data(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        SceneError::Data {
            path: path.into(),
            message: message.into(),
        }
    }
    pub fn output(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        SceneError::Output {
            path: path.into(),
            message: message.into(),
        }
    }
    pub fn setting(field: &str, message: impl Into<String>) -> Self {
        SceneError::Setting {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Why work over the ranks of a communicator failed: the scene (the same
/// error one process gives), the ranks' communication, or a cancel.
#[derive(Debug, thiserror::Error)]
pub enum ParallelError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Comm(#[from] voxless_parallel::CommError),
    #[error("cancelled")]
    Cancelled,
}

impl From<voxless_parallel::WireError> for ParallelError {
    fn from(e: voxless_parallel::WireError) -> Self {
        ParallelError::Comm(e.into())
    }
}

impl From<voxless_core::Cancelled> for ParallelError {
    fn from(_: voxless_core::Cancelled) -> Self {
        ParallelError::Cancelled
    }
}
