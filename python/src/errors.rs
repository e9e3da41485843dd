//! Library errors as Python exceptions.
//!
//! - A missing file is `FileNotFoundError`, another operating-system failure
//!   `OSError` (both name the path).
//! - Everything else the library refuses — bad data, a setting out of range,
//!   an unknown colormap — is `voxless.VoxlessError`, a `ValueError`, with the
//!   library's message (which names the file, array or setting). A setting's
//!   scene-file name is also in the exception's `field` attribute, so the
//!   Python layer can name the keyword argument it came from.

use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use voxless::SceneError;
use voxless::io::IoError;

create_exception!(
    voxless,
    VoxlessError,
    PyValueError,
    "Input voxless cannot use: bad data, a setting out of range, an unknown name. \
     The message names the array, file or setting; `field` holds a setting's \
     scene-file name (or None)."
);

/// The Python exception for a library error.
pub fn scene(py: Python<'_>, e: SceneError) -> PyErr {
    let message = e.to_string();
    match &e {
        SceneError::Io(IoError::Io { source, .. })
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            PyFileNotFoundError::new_err(message)
        }
        SceneError::Io(IoError::Io { .. }) => PyOSError::new_err(message),
        SceneError::Setting { field, .. } => with_field(py, message, Some(field)),
        _ => with_field(py, message, None),
    }
}

/// A [`VoxlessError`] with its `field` attribute.
pub fn with_field(py: Python<'_>, message: String, field: Option<&str>) -> PyErr {
    let err = VoxlessError::new_err(message);
    // Setting an attribute on a fresh exception instance cannot fail in
    // practice; if it did, the error still carries its message.
    let _ = err.value(py).setattr("field", field);
    err
}

/// A [`VoxlessError`] naming no setting.
pub fn value(py: Python<'_>, message: impl Into<String>) -> PyErr {
    with_field(py, message.into(), None)
}
