//! The community models in `../shared/models`, beside the checkout (where
//! `.ci/run`'s checkout has them). A test that needs one fails when it is
//! missing, so that no check passes by not running; on a machine without
//! them, `IBEAM_NO_SHARED_MODELS=1` lets those tests pass without their
//! model checks, each saying so on stderr.
//!
//! Standalone (no other helper of `tests/common`), so that a test crate
//! can take just this file with `#[path = "../common/models.rs"] mod models;`.

use std::path::{Path, PathBuf};

/// The environment variable that, set to `1`, lets tests pass without the
/// shared models.
pub const NO_SHARED_MODELS: &str = "IBEAM_NO_SHARED_MODELS";

/// `../shared/models/NAME` when it exists; `None` (with a note on stderr)
/// when it does not and [`NO_SHARED_MODELS`] is `1`; otherwise a panic
/// that says what is missing and how to opt out.
pub fn shared_model(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/models")
        .join(name);
    if path.exists() {
        return Some(path);
    }
    if std::env::var(NO_SHARED_MODELS).is_ok_and(|v| v == "1") {
        eprintln!(
            "{} is absent and {NO_SHARED_MODELS}=1: its checks did not run",
            path.display()
        );
        return None;
    }
    panic!(
        "{} is missing: check the repository out beside ../shared (as CI does), \
         or set {NO_SHARED_MODELS}=1 to run the tests without the shared models",
        path.display()
    );
}
