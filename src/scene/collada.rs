//! COLLADA (.dae) loader for the CS184/CMU462 subset (spec §1-6).
//!
//! The document is parsed once with roxmltree; the visual scene is walked
//! iteratively in document order and flattened into a `Scene`. Every problem
//! becomes either a one-line `LoadError` (`FILE: <element>: what is wrong`)
//! or, where the spec has a safe default, an entry in `Scene::warnings`.

mod builder;
mod camera;
mod effects;
mod lights;
mod mesh;
mod transform;
mod xml;

use super::Scene;
use std::path::Path;

/// Files larger than this are refused before reading (roxmltree indexes with u32).
const MAX_FILE_BYTES: u64 = 1 << 30;

#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{file}: {msg}")]
    Invalid { file: String, msg: String },
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
}

impl LoadError {
    fn invalid(file: &str, msg: impl Into<String>) -> Self {
        LoadError::Invalid {
            file: file.to_string(),
            msg: msg.into(),
        }
    }
}

/// Loads a scene file; messages name the file as `path` displays.
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    let file = path.display().to_string();
    let io = |source| LoadError::Io {
        file: file.clone(),
        source,
    };
    let size = std::fs::metadata(path).map_err(io)?.len();
    if size > MAX_FILE_BYTES {
        return Err(LoadError::invalid(
            &file,
            format!("file is {size} bytes; the limit is {MAX_FILE_BYTES}"),
        ));
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        LoadError::invalid(
            &file,
            format!("not a text file (invalid UTF-8 at byte {at})"),
        )
    })?;
    parse(&text, &file)
}

/// Parses COLLADA text; `file_label` prefixes every message.
pub fn parse(text: &str, file_label: &str) -> Result<Scene, LoadError> {
    if text.trim().is_empty() {
        return Err(LoadError::invalid(file_label, "file is empty"));
    }
    if let Some(at) = xml::too_deep_at(text, xml::MAX_XML_DEPTH) {
        let (line, col) = xml::line_col(text, at);
        return Err(LoadError::invalid(
            file_label,
            format!(
                "line {line}, column {col}: elements are nested deeper than {} levels",
                xml::MAX_XML_DEPTH
            ),
        ));
    }
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
        let what = e.to_string().replace(['\n', '\r'], " ");
        LoadError::invalid(file_label, format!("not well-formed XML: {what}"))
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        return Err(LoadError::invalid(
            file_label,
            format!(
                "<{}>: root element is not <COLLADA>; not a COLLADA file",
                xml::clip(root.tag_name().name())
            ),
        ));
    }
    builder::build(file_label, &doc)
}
