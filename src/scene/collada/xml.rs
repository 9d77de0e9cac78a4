//! XML plumbing shared by the COLLADA readers: `#id` resolution, element
//! labels for error messages, and number lists parsed without a per-number
//! allocation.

use super::LoadError;
use roxmltree::{Document, Node};
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::fmt::Display;
use std::str::FromStr;

/// Profiles whose `<extra><technique>` carries the CGL extension data (spec §1).
const EXTENSION_PROFILES: [&str; 2] = ["CGL", "CMU462"];

/// The parsed document plus what every reader needs: the file label for
/// messages, the id table, and the warnings gathered so far.
pub(crate) struct Ctx<'a, 'i> {
    pub file: &'a str,
    /// The course wrote the file (`camera::course_placement`): its effects mean what
    /// spec §6 says, so what a Lambertian surface cannot show is not warned about.
    pub course_file: bool,
    /// Blender 2.80 or later wrote the file (`camera::writes_watts`) without the
    /// course's extension: its point and spot lights give power in watts.
    pub light_watts: bool,
    doc: &'a Document<'i>,
    ids: HashMap<&'a str, Node<'a, 'i>>,
    warnings: Vec<String>,
    seen_warnings: HashSet<String>,
    /// The first element whose numbers were written with a decimal comma
    /// (`1,5`), once the whole file was found to write every number that way.
    /// Held as the element's label, for the one warning `into_warnings` adds.
    decimal_comma: RefCell<Option<String>>,
    /// Warnings from readers that hold the context shared (`note`).
    notes: RefCell<Vec<String>>,
}

impl<'a, 'i> Ctx<'a, 'i> {
    pub fn new(file: &'a str, doc: &'a Document<'i>) -> Self {
        let mut ids = HashMap::new();
        for n in doc.descendants().filter(Node::is_element) {
            if let Some(id) = n.attribute("id") {
                // COLLADA ids are unique; on a duplicate the first one wins.
                ids.entry(id).or_insert(n);
            }
        }
        Ctx {
            file,
            course_file: true,
            light_watts: false,
            doc,
            ids,
            warnings: Vec::new(),
            seen_warnings: HashSet::new(),
            decimal_comma: RefCell::new(None),
            notes: RefCell::new(Vec::new()),
        }
    }

    /// An error about `node`, in the one-line form `FILE: <element>: what`.
    pub fn err(&self, node: Node, what: impl Display) -> LoadError {
        LoadError::Invalid {
            file: self.file.to_string(),
            msg: format!("{}: {what}", describe(node)),
        }
    }

    /// A non-fatal problem about `node`, in the one-line form `FILE: <element>: what`.
    /// Repeats are kept once so that a large mesh cannot flood the list.
    pub fn warn(&mut self, node: Node, what: impl Display) {
        let w = format!("{}: {}: {what}", self.file, describe(node));
        if self.seen_warnings.insert(w.clone()) {
            self.warnings.push(w);
        }
    }

    /// A warning given once per file for `key`, naming the first element it concerns
    /// (for things that recur in every mesh of a file, such as lines).
    pub fn warn_once(&mut self, key: &str, node: Node, what: impl Display) {
        if self.seen_warnings.insert(format!("\u{0}{key}")) {
            self.warn(node, what);
        }
    }

    /// `warn` for readers that hold the context shared; added after the others.
    pub fn note(&self, node: Node, what: impl Display) {
        self.notes
            .borrow_mut()
            .push(format!("{}: {}: {what}", self.file, describe(node)));
    }

    pub fn into_warnings(mut self) -> Vec<String> {
        for w in self.notes.take() {
            if self.seen_warnings.insert(w.clone()) {
                self.warnings.push(w);
            }
        }
        if let Some(label) = self.decimal_comma.take() {
            self.warnings.push(format!(
                "{}: {label}: numbers are written with decimal commas (as under a comma \
                 locale); read as decimal points throughout the file",
                self.file
            ));
        }
        self.warnings
    }

    /// The `<image>` whose id is `id` (without `#`; some exporters write one).
    pub fn image_by_id(&self, id: &str) -> Option<Node<'a, 'i>> {
        let id = id.strip_prefix('#').unwrap_or(id);
        self.by_id(id).filter(|n| n.has_tag_name("image"))
    }

    /// The element with id `id`, whatever it is. A URL fragment may escape
    /// characters (`#Cube%20mesh` for `id="Cube mesh"`), so an id not found as
    /// written is looked up decoded.
    pub fn by_id(&self, id: &str) -> Option<Node<'a, 'i>> {
        let found = self.ids.get(id).copied();
        found.or_else(|| {
            let decoded = percent_decode(id);
            (decoded != id)
                .then(|| self.ids.get(decoded.as_str()).copied())
                .flatten()
        })
    }

    /// The element named by `node@attr` (a `#id` URL), which must be a `<tag>`.
    pub fn resolve(
        &self,
        node: Node<'a, 'i>,
        attr: &str,
        tag: &str,
    ) -> Result<Node<'a, 'i>, LoadError> {
        self.resolve_if_present(node, attr, tag)?.ok_or_else(|| {
            let url = node.attribute(attr).unwrap_or_default();
            let what = if self.local_id(url).is_some() {
                "names nothing"
            } else {
                "is not a local #id reference (references into other files are not read)"
            };
            self.err(node, format!("{attr}=\"{}\" {what}", clip(url)))
        })
    }

    /// Like `resolve`, but `None` when the URL names no element of this file (nothing,
    /// or something in another file).
    pub fn resolve_if_present(
        &self,
        node: Node<'a, 'i>,
        attr: &str,
        tag: &str,
    ) -> Result<Option<Node<'a, 'i>>, LoadError> {
        let url = node
            .attribute(attr)
            .ok_or_else(|| self.err(node, format!("missing attribute {attr}")))?;
        // A reference into another file names nothing in this one.
        let Some(target) = self.local_id(url).and_then(|id| self.by_id(id)) else {
            return Ok(None);
        };
        if target.tag_name().name() != tag {
            let msg = format!(
                "{attr}=\"{}\" names a <{}>, expected a <{tag}>",
                clip(url),
                target.tag_name().name()
            );
            return Err(self.err(node, msg));
        }
        Ok(Some(target))
    }

    /// The id a URL names in this document: `#id`, or `file.dae#id` where `file.dae`
    /// is this file's own name (some exporters write the document's name in).
    fn local_id<'u>(&self, url: &'u str) -> Option<&'u str> {
        if let Some(id) = url.strip_prefix('#') {
            return Some(id);
        }
        let (doc, id) = url.rsplit_once('#')?;
        let name = |p: &str| {
            p.rsplit(['/', '\\'])
                .next()
                .unwrap_or(p)
                .to_ascii_lowercase()
        };
        (!doc.is_empty() && name(doc) == name(self.file)).then_some(id)
    }

    /// Appends the whitespace-separated numbers of `node`'s text to `out`.
    /// Non-finite or unparsable entries are errors; nothing is sized from attributes.
    pub fn numbers_into<T: Number>(&self, node: Node, out: &mut Vec<T>) -> Result<(), LoadError> {
        let text = node.text().unwrap_or("");
        // At most one number per two bytes ("1 "), so this bound is safe to reserve.
        out.reserve(text.len() / 2 + 1);
        for (k, word) in text.split_ascii_whitespace().enumerate() {
            match word.parse::<T>() {
                Ok(v) if v.is_finite() => out.push(v),
                _ => match self.decimal_comma_number::<T>(node, word) {
                    Some(v) => out.push(v),
                    None => {
                        return Err(self.err(
                            node,
                            format!("entry {k} \"{}\" is not {}", clip(word), T::WHAT),
                        ))
                    }
                },
            }
        }
        Ok(())
    }

    /// `word` read with its one comma as the decimal point, when `T` is a float and
    /// the file writes no number with a decimal point: then the file was written
    /// under a decimal-comma locale and every comma is unambiguous. A file mixing
    /// both is refused, because there a comma could as well separate two numbers.
    fn decimal_comma_number<T: Number>(&self, node: Node, word: &str) -> Option<T> {
        if !T::FRACTIONAL || word.matches(',').count() != 1 {
            return None;
        }
        let v = word
            .replace(',', ".")
            .parse::<T>()
            .ok()
            .filter(|v| v.is_finite())?;
        if self.decimal_comma.borrow().is_none() {
            if self.has_decimal_point_numbers() {
                return None;
            }
            *self.decimal_comma.borrow_mut() = Some(describe(node));
        }
        Some(v)
    }

    /// Whether any element's text is a list of numbers one of which has a decimal point.
    fn has_decimal_point_numbers(&self) -> bool {
        self.doc
            .descendants()
            .filter(|n| n.is_element() && n.first_element_child().is_none())
            .filter_map(|n| n.text())
            .any(|t| {
                let mut words = t.split_ascii_whitespace().peekable();
                words.peek().is_some()
                    && words
                        .clone()
                        .all(|w| w.replace(',', ".").parse::<f64>().is_ok())
                    && words.any(|w| w.contains('.') && w.parse::<f64>().is_ok())
            })
    }

    pub fn numbers<T: Number>(&self, node: Node) -> Result<Vec<T>, LoadError> {
        let mut v = Vec::new();
        self.numbers_into(node, &mut v)?;
        Ok(v)
    }

    /// Exactly `N` numbers.
    pub fn exact<const N: usize>(&self, node: Node) -> Result<[f64; N], LoadError> {
        let v = self.numbers::<f64>(node)?;
        v.as_slice()
            .try_into()
            .map_err(|_| self.err(node, format!("expected {N} numbers, found {}", v.len())))
    }

    /// The first `N` numbers; more are allowed (e.g. RGBA colours read as RGB).
    pub fn leading<const N: usize>(&self, node: Node) -> Result<[f32; N], LoadError> {
        let v = self.numbers::<f32>(node)?;
        if v.len() < N {
            return Err(self.err(
                node,
                format!("expected at least {N} numbers, found {}", v.len()),
            ));
        }
        let mut a = [0.0; N];
        a.copy_from_slice(&v[..N]);
        Ok(a)
    }

    /// A single number from the text of `node`'s child `<name>`, if present.
    pub fn child_scalar(&self, node: Node, name: &str) -> Result<Option<f32>, LoadError> {
        child(node, name)
            .map(|c| self.leading::<1>(c).map(|[v]| v))
            .transpose()
    }

    /// The first three numbers of `node` as a colour, none of them negative (a
    /// negative radiance or reflectance makes negative pixels).
    pub fn colour(&self, node: Node) -> Result<[f32; 3], LoadError> {
        let c = self.leading::<3>(node)?;
        if let Some(v) = c.iter().find(|&&v| v < 0.0) {
            return Err(self.err(node, format!("colour component {v} is negative")));
        }
        Ok(c)
    }

    /// `colour` of child `<name>`, if present.
    pub fn child_colour(&self, node: Node, name: &str) -> Result<Option<[f32; 3]>, LoadError> {
        child(node, name).map(|c| self.colour(c)).transpose()
    }

    /// A non-negative integer attribute, if present.
    pub fn uint_attr(&self, node: Node, attr: &str) -> Result<Option<u64>, LoadError> {
        node.attribute(attr)
            .map(|s| {
                s.trim().parse::<u64>().map_err(|_| {
                    self.err(
                        node,
                        format!("{attr}=\"{}\" is not a non-negative integer", clip(s)),
                    )
                })
            })
            .transpose()
    }
}

/// Numbers a COLLADA list may hold.
pub(crate) trait Number: FromStr + Copy {
    const WHAT: &'static str;
    /// Whether the type has a fractional part (so a decimal comma can mean one).
    const FRACTIONAL: bool = true;
    fn is_finite(self) -> bool;
}

impl Number for f32 {
    const WHAT: &'static str = "a finite number";
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

impl Number for f64 {
    const WHAT: &'static str = "a finite number";
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl Number for u32 {
    const WHAT: &'static str = "a non-negative integer";
    const FRACTIONAL: bool = false;
    fn is_finite(self) -> bool {
        true
    }
}

impl Number for i64 {
    const WHAT: &'static str = "an integer";
    const FRACTIONAL: bool = false;
    fn is_finite(self) -> bool {
        true
    }
}

/// First element child of `node` with local name `name`.
pub(crate) fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

/// All element children of `node` with local name `name`.
pub(crate) fn children<'a, 'i: 'a>(
    node: Node<'a, 'i>,
    name: &'a str,
) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == name)
}

/// Follows a path of child names from `node`.
pub(crate) fn path<'a, 'i>(node: Node<'a, 'i>, names: &[&str]) -> Option<Node<'a, 'i>> {
    names.iter().try_fold(node, |n, name| child(n, name))
}

/// The first `<extra><technique>` with the CGL or CMU462 profile (spec §1).
pub(crate) fn extension_technique<'a, 'i>(node: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    children(node, "extra")
        .flat_map(|e| children(e, "technique"))
        .find(|t| {
            t.attribute("profile")
                .is_some_and(|p| EXTENSION_PROFILES.contains(&p))
        })
}

/// Label of an element for messages: the nearest ancestor-or-self with an id,
/// then the tag path below it, e.g. `<geometry id="g">/mesh/polylist[1]/p`.
/// Long paths keep their anchor and last few steps: `<visual_scene id="s">/…/node/node`.
pub(crate) fn describe(node: Node) -> String {
    const KEEP: usize = 6;
    let mut steps = Vec::new();
    let mut elided = false;
    let mut anchor = String::new();
    let mut cur = Some(node);
    while let Some(n) = cur.filter(|n| n.is_element()) {
        let name = n.tag_name().name();
        if let Some(id) = n.attribute("id") {
            anchor = format!("<{name} id=\"{}\">", clip(id));
            break;
        }
        let parent = n.parent_element();
        if parent.is_none() {
            anchor = format!("<{name}>");
            break;
        }
        if steps.len() < KEEP {
            steps.push(step_name(n));
        } else {
            elided = true;
        }
        cur = parent;
    }
    if elided {
        steps.push("…".to_string());
    }
    steps.push(anchor);
    steps.reverse();
    steps.join("/")
}

/// `name`, or `name[k]` when the parent has several children of that name.
fn step_name(n: Node) -> String {
    let name = n.tag_name().name();
    let same = |s: &Node| s.tag_name().name() == name;
    let before = std::iter::successors(n.prev_sibling_element(), |s| s.prev_sibling_element())
        .filter(same)
        .count();
    let after = std::iter::successors(n.next_sibling_element(), |s| s.next_sibling_element())
        .any(|s| same(&s));
    if before > 0 || after {
        format!("{name}[{before}]")
    } else {
        name.to_string()
    }
}

/// Shortens untrusted text quoted in a message so a message stays one short line.
pub(crate) fn clip(s: &str) -> String {
    let one_line: String = s
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    if one_line.chars().count() > 40 {
        format!("{}…", one_line.chars().take(40).collect::<String>())
    } else {
        one_line
    }
}

/// Deepest element nesting handed to roxmltree, whose tokenizer recurses once
/// per open element: far deeper input would overflow the stack.
pub(crate) const MAX_XML_DEPTH: usize = 1024;

/// Byte offset of the first element opened deeper than `limit`, found by a
/// linear scan that follows the XML grammar far enough to count elements
/// (comments, CDATA, processing instructions, quoted attribute values).
/// Where the text is malformed the XML parser rejects it before reaching the
/// point at which this count could be wrong.
pub(crate) fn too_deep_at(text: &str, limit: usize) -> Option<usize> {
    let b = text.as_bytes();
    let find = |from: usize, pat: &[u8]| {
        b.get(from..)?
            .windows(pat.len())
            .position(|w| w == pat)
            .map(|k| from + k + pat.len())
    };
    let mut depth = 0usize;
    let mut i = 0;
    while i < b.len() {
        if b[i] != b'<' {
            i = b[i..]
                .iter()
                .position(|&c| c == b'<')
                .map_or(b.len(), |k| i + k);
            continue;
        }
        let rest = &b[i..];
        let next = if rest.starts_with(b"<!--") {
            find(i + 4, b"-->")
        } else if rest.starts_with(b"<![CDATA[") {
            find(i + 9, b"]]>")
        } else if rest.starts_with(b"<?") {
            find(i + 2, b"?>")
        } else if rest.starts_with(b"<!") || rest.starts_with(b"</") {
            if rest[1] == b'/' {
                depth = depth.saturating_sub(1);
            }
            find(i + 2, b">")
        } else {
            let end = open_tag_end(b, i + 1)?;
            if b[end - 2] != b'/' {
                depth += 1;
                if depth > limit {
                    return Some(i);
                }
            }
            Some(end)
        };
        i = next?;
    }
    None
}

/// Index just past the `>` closing a start tag that begins before `from`,
/// skipping quoted attribute values (which may contain `>`).
fn open_tag_end(b: &[u8], mut from: usize) -> Option<usize> {
    let mut quote = None;
    while from < b.len() {
        let c = b[from];
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == b'"' || c == b'\'' => quote = Some(c),
            None if c == b'>' => return Some(from + 1),
            None => {}
        }
        from += 1;
    }
    None
}

/// 1-based line and column of byte `offset`, for messages about raw text.
pub(crate) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |k| k + 1) + 1;
    (line, col)
}

/// `s` with its `%XX` escapes decoded (invalid UTF-8 replaced); other `%` kept.
pub(crate) fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut bytes = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                bytes.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        bytes.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&bytes).into_owned()
}
