//! COLLADA (.dae) loader for the CS184/CMU462 subset (spec §1-6).

use super::Scene;
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{file}: {msg}")]
    Invalid { file: String, msg: String },
}

/// Loads a scene file.
pub fn load(_path: &Path) -> Result<Scene, LoadError> {
    todo!("collada loader")
}
