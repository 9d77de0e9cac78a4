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
mod skin;
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

/// Where a scene's images are read from: files beside the `.dae`, or the
/// entries of a `.zae` archive.
pub(crate) trait Resources {
    /// The bytes of the image `uri` names (as `<init_from>` writes it), and the name
    /// to show for it; else why not, in a few words.
    fn read(&self, uri: &str) -> Result<(String, Vec<u8>), String>;
}

/// Images beside the scene file (relative URIs are relative to its folder).
struct Folder(std::path::PathBuf);

impl Resources for Folder {
    fn read(&self, uri: &str) -> Result<(String, Vec<u8>), String> {
        let rel = uri_path(uri);
        let path = self.0.join(&rel);
        match std::fs::read(&path) {
            Ok(bytes) => Ok((path.display().to_string(), bytes)),
            Err(e) => {
                // An absolute path from the author's machine: try the file's name here.
                let name = rel.rsplit('/').next().unwrap_or(&rel);
                let beside = self.0.join(name);
                match std::fs::read(&beside) {
                    Ok(bytes) if name != rel => Ok((beside.display().to_string(), bytes)),
                    _ => Err(format!("cannot read {}: {e}", path.display())),
                }
            }
        }
    }
}

/// A `.zae`: its entries by name, and the folder of its root `.dae` inside it.
struct Archive {
    entries: std::collections::HashMap<String, Vec<u8>>,
    dir: String,
}

impl Resources for Archive {
    fn read(&self, uri: &str) -> Result<(String, Vec<u8>), String> {
        let rel = uri_path(uri);
        let joined = normalize(&format!("{}{rel}", self.dir));
        let name = rel.rsplit('/').next().unwrap_or(&rel).to_string();
        let found = self
            .entries
            .get(&joined)
            .map(|b| (joined.clone(), b))
            .or_else(|| {
                self.entries
                    .iter()
                    .find(|(k, _)| k.rsplit('/').next() == Some(name.as_str()))
                    .map(|(k, b)| (k.clone(), b))
            });
        found
            .map(|(k, b)| (k, b.clone()))
            .ok_or_else(|| format!("no entry \"{joined}\" in the archive"))
    }
}

/// A URI of `<init_from>` as a relative or absolute path with `/` separators:
/// `file://` dropped, `%XX` escapes decoded, backslashes turned around.
fn uri_path(uri: &str) -> String {
    let s = uri.trim();
    let s = s
        .strip_prefix("file://")
        .or_else(|| s.strip_prefix("file:"))
        .unwrap_or(s);
    // file:///C:/x: the drive letter follows the third slash.
    let s = match s.as_bytes() {
        [b'/', _, b':', ..] => &s[1..],
        _ => s,
    };
    xml::percent_decode(s).replace('\\', "/")
}

/// `a/./b/../c` → `a/c`, for names inside an archive.
fn normalize(path: &str) -> String {
    let mut parts: Vec<&str> = Vec::new();
    for p in path.split('/') {
        match p {
            "" | "." => {}
            ".." => {
                parts.pop();
            }
            _ => parts.push(p),
        }
    }
    parts.join("/")
}

/// Loads a scene file (`.dae`, or a `.zae` archive); messages name the file as
/// `path` displays.
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
    if bytes.starts_with(b"PK\x03\x04") {
        return load_zae(&file, &bytes);
    }
    let text = decode_text(&file, bytes)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_with(&text, &file, &Folder(dir))
}

/// The text of an XML file: UTF-8 (a byte-order mark is dropped), or UTF-16 of
/// either byte order, which the XML standard allows when a byte-order mark says so,
/// or, without one, when the file opens with `<` in UTF-16 (XML 1.0, appendix F).
fn decode_text(file: &str, bytes: Vec<u8>) -> Result<String, LoadError> {
    let utf16 = |big: bool, skip: usize| {
        let units: Vec<u16> = bytes[skip..]
            .chunks_exact(2)
            .map(|c| {
                if big {
                    u16::from_be_bytes([c[0], c[1]])
                } else {
                    u16::from_le_bytes([c[0], c[1]])
                }
            })
            .collect();
        let after = if skip == 2 {
            " after its byte-order mark"
        } else {
            ""
        };
        String::from_utf16(&units).map_err(|_| {
            LoadError::invalid(file, format!("not a text file (invalid UTF-16{after})"))
        })
    };
    match bytes.as_slice() {
        [0xFF, 0xFE, ..] => utf16(false, 2),
        [0xFE, 0xFF, ..] => utf16(true, 2),
        [b'<', 0, ..] => utf16(false, 0),
        [0, b'<', ..] => utf16(true, 0),
        [0xEF, 0xBB, 0xBF, rest @ ..] => utf8(file, rest.to_vec()),
        _ => utf8(file, bytes),
    }
}

fn utf8(file: &str, bytes: Vec<u8>) -> Result<String, LoadError> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        LoadError::invalid(
            file,
            format!("not a text file (invalid UTF-8 at byte {at})"),
        )
    })
}

/// Entries larger than this are not unpacked from a `.zae`.
const MAX_ENTRY_BYTES: u64 = 1 << 30;

/// A `.zae`: a zip archive whose `manifest.xml` names the root `.dae`
/// (`<dae_root>`); without a manifest, its only `.dae`.
fn load_zae(file: &str, bytes: &[u8]) -> Result<Scene, LoadError> {
    let bad = |what: String| LoadError::invalid(file, what);
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| bad(format!("not a readable .zae (zip) archive: {e}")))?;
    let mut entries = std::collections::HashMap::new();
    let mut total = 0u64;
    for i in 0..zip.len() {
        let mut entry = zip
            .by_index(i)
            .map_err(|e| bad(format!("archive entry {i}: {e}")))?;
        if entry.is_dir() {
            continue;
        }
        total += entry.size();
        if entry.size() > MAX_ENTRY_BYTES || total > MAX_FILE_BYTES {
            return Err(bad(format!(
                "archive entry \"{}\" is too large",
                entry.name()
            )));
        }
        let mut data = Vec::with_capacity(entry.size() as usize);
        std::io::Read::read_to_end(&mut entry, &mut data)
            .map_err(|e| bad(format!("archive entry \"{}\": {e}", entry.name())))?;
        entries.insert(normalize(entry.name()), data);
    }
    let root = match entries.get("manifest.xml") {
        Some(m) => {
            let text = decode_text(&format!("{file}/manifest.xml"), m.clone())?;
            let doc = roxmltree::Document::parse(&text)
                .map_err(|e| bad(format!("manifest.xml: not well-formed XML: {e}")))?;
            let root = doc
                .descendants()
                .find(|n| n.has_tag_name("dae_root"))
                .and_then(|n| n.text())
                .ok_or_else(|| bad("manifest.xml: <dae_root>: missing".into()))?;
            normalize(&uri_path(root.split('#').next().unwrap_or(root)))
        }
        None => {
            let mut daes = entries
                .keys()
                .filter(|k| k.to_ascii_lowercase().ends_with(".dae"));
            match (daes.next(), daes.next()) {
                (Some(d), None) => d.clone(),
                _ => return Err(bad("no manifest.xml and not exactly one .dae".into())),
            }
        }
    };
    let label = format!("{file}/{root}");
    let bytes = entries
        .get(&root)
        .cloned()
        .ok_or_else(|| bad(format!("manifest.xml: <dae_root>: no entry \"{root}\"")))?;
    let text = decode_text(&label, bytes)?;
    let dir = match root.rfind('/') {
        Some(k) => root[..=k].to_string(),
        None => String::new(),
    };
    parse_with(&text, &label, &Archive { entries, dir })
}

/// Parses COLLADA text; `file_label` prefixes every message. Images are read
/// relative to the current directory.
pub fn parse(text: &str, file_label: &str) -> Result<Scene, LoadError> {
    parse_with(text, file_label, &Folder(std::path::PathBuf::new()))
}

fn parse_with(text: &str, file_label: &str, resources: &dyn Resources) -> Result<Scene, LoadError> {
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
    let parse = |allow_dtd| {
        let options = roxmltree::ParsingOptions {
            allow_dtd,
            ..Default::default()
        };
        roxmltree::Document::parse_with_options(text, options)
    };
    // A DTD's entities could expand without bound, so only a bare <!DOCTYPE>, which
    // defines none (some tools write `<!DOCTYPE COLLADA>`), is read past.
    let mut bare_doctype = false;
    let doc = match parse(false) {
        Err(roxmltree::Error::DtdDetected) if !has_internal_subset(text) => {
            bare_doctype = true;
            parse(true)
        }
        Err(roxmltree::Error::DtdDetected) => {
            let msg = "<!DOCTYPE>: a document type declaration with an internal subset \
                       ([...]) is not read; delete it";
            return Err(LoadError::invalid(file_label, msg));
        }
        parsed => parsed,
    }
    .map_err(|e| {
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
    let mut scene = builder::build(file_label, &doc, resources)?;
    if bare_doctype {
        let w = format!("{file_label}: <!DOCTYPE>: a document type declaration; ignored");
        scene.warnings.insert(0, w);
    }
    Ok(scene)
}

/// Whether the text's `<!DOCTYPE ...>` has an internal subset (`[...]`), where
/// entities are declared.
fn has_internal_subset(text: &str) -> bool {
    let Some(start) = text.find("<!DOCTYPE") else {
        return true;
    };
    let decl = &text[start..];
    let end = decl.find('>').unwrap_or(decl.len());
    decl[..end].contains('[')
}
