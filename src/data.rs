//! Where ember's own data lives: the scenes it ships (`scenes/`, the course's
//! included) and the reference renders its tests and benchmarks compare with
//! (`tests/data/references/`). Found at run time, never compiled in, so an
//! installed binary does not look for the build machine's folders.

use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// The variable naming the data folder.
pub const DATA_VAR: &str = "EMBER_DATA";

/// A folder given on the command line (`--data`), which wins over the variable.
static GIVEN: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();

/// Makes `dir` the data folder for the rest of the process (the CLI's `--data`).
pub fn set_root(dir: PathBuf) {
    let _ = GIVEN.set(dir);
}

/// What marks a folder as ember's data folder (a clone of the repository).
const MARKER: &str = "scenes/cs184/sky/CBbunny.dae";

/// The folder holding `scenes/` and `tests/data/references/`: the one `set_root` was
/// given, else `$EMBER_DATA`, else the first folder at or above the current directory,
/// or above the running executable (`target/release/ember` inside a clone), that has
/// the course's scenes.
pub fn root() -> Result<PathBuf> {
    let given = GIVEN.get().map(|d| (d.clone(), "--data"));
    let var = std::env::var_os(DATA_VAR).map(|d| (PathBuf::from(d), DATA_VAR));
    if let Some((dir, from)) = given.or(var) {
        if !dir.join(MARKER).is_file() {
            bail!(
                "{from} {}: not ember's data folder (no {MARKER} there)",
                dir.display()
            );
        }
        return Ok(dir);
    }
    let starts = [
        std::env::current_dir().ok(),
        std::env::current_exe()
            .ok()
            .and_then(|e| e.canonicalize().ok()),
    ];
    starts
        .iter()
        .flatten()
        .find_map(|start| find_above(start))
        .ok_or_else(|| {
            anyhow::anyhow!(
                "cannot find ember's scenes (looked above the current directory and the \
                 executable for {MARKER}): run from a clone of the repository, or set \
                 {DATA_VAR} (or --data) to one"
            )
        })
}

fn find_above(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .find(|dir| dir.join(MARKER).is_file())
        .map(Path::to_path_buf)
}

/// A scene the project ships, by its path under `scenes/` (`cs184/sky/CBbunny.dae`).
pub fn scene(rel: &str) -> Result<PathBuf> {
    Ok(root()?.join("scenes").join(rel))
}

/// The folder of the Mitsuba 3 reference renders and their `manifest.json`.
pub fn references() -> Result<PathBuf> {
    Ok(root()?.join("tests/data/references"))
}
