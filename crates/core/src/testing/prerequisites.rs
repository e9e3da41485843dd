//! Tests that need what a machine may lack: one rule for all of them. A
//! missing prerequisite skips the test with a printed notice, so a user's
//! clone passes; where CI installed it, CI sets the prerequisite's
//! `VOXLESS_REQUIRE_*` variable to `1`, and a missing prerequisite fails
//! the test instead — a test CI can run never passes by skipping.
//!
//! | variable | prerequisite |
//! |---|---|
//! | `VOXLESS_REQUIRE_DATA` | the real simulation outputs in `../shared/data` beside the checkout |
//! | `VOXLESS_REQUIRE_MPI` | `mpirun` (Open MPI) |
//! | `VOXLESS_REQUIRE_BROWSER` | `chromium` and `chromedriver` |
//! | `VOXLESS_REQUIRE_HDF5` | a build with the `hdf5` feature |
//! | `VOXLESS_REQUIRE_YT` | `$VOXLESS_PYTHON` (else `python3`) importing numpy, h5py and yt |

use std::path::PathBuf;

/// Whether a test may go on: `present` says whether `what` is there. When
/// it is not, prints a notice and returns `false` (the test skips) —
/// unless the environment variable `require` is `1`, which makes the
/// absence a failure.
pub fn prerequisite(present: bool, require: &str, what: &str) -> bool {
    if present {
        return true;
    }
    if std::env::var(require).is_ok_and(|v| v == "1") {
        panic!("{what} is missing, and {require}=1 says it must be there");
    }
    eprintln!("notice: {what} is missing; skipping (with {require}=1 this fails)");
    false
}

/// `../shared/data/<sub>` beside the checkout — the real simulation outputs
/// tests use when present — or `None` when it is absent (see
/// [`prerequisite`]: `VOXLESS_REQUIRE_DATA`).
pub fn shared_data(sub: &str) -> Option<PathBuf> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(sub);
    let what = format!("the shared data {}", path.display());
    prerequisite(path.exists(), "VOXLESS_REQUIRE_DATA", &what).then_some(path)
}
