//! Where in the scene file: key paths (`shapes[2].transform.rotate`), their
//! byte spans in the text and line/column, and the one-line `Error::Scene` built
//! from them.
//!
//! serde errors carry a byte span but no key path; our own value checks know the
//! key path but not the span. A `toml_edit` parse of the same text (which, unlike
//! `toml::Value`, keeps the span of every key and value) maps between the two.

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq)]
pub(super) enum Seg {
    Key(String),
    Index(usize),
}

/// A key path such as `shapes[2].transform.rotate`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct KeyPath(pub(super) Vec<Seg>);

impl KeyPath {
    pub(super) fn key(&self, k: &str) -> Self {
        let mut p = self.clone();
        p.0.push(Seg::Key(k.to_string()));
        p
    }
    pub(super) fn index(&self, i: usize) -> Self {
        let mut p = self.clone();
        p.0.push(Seg::Index(i));
        p
    }
}

#[cfg(test)]
pub(super) fn root(k: &str) -> KeyPath {
    KeyPath::default().key(k)
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Seg::Key(k) if i == 0 => write!(f, "{k}")?,
                Seg::Key(k) => write!(f, ".{k}")?,
                Seg::Index(j) => write!(f, "[{j}]")?,
            }
        }
        Ok(())
    }
}

/// A node of the `toml_edit` tree (which keeps byte spans).
#[derive(Clone, Copy)]
enum Node<'d> {
    Item(&'d toml_edit::Item),
    Value(&'d toml_edit::Value),
    Table(&'d toml_edit::Table),
}

impl<'d> Node<'d> {
    fn span(self) -> Option<Range<usize>> {
        match self {
            Node::Item(i) => i.span(),
            Node::Value(v) => v.span(),
            Node::Table(t) => t.span(),
        }
    }

    fn table_like(self) -> Option<&'d dyn toml_edit::TableLike> {
        match self {
            Node::Item(i) => i.as_table_like(),
            Node::Value(v) => v.as_inline_table().map(|t| t as &dyn toml_edit::TableLike),
            Node::Table(t) => Some(t as &dyn toml_edit::TableLike),
        }
    }

    /// Children with their path segment and key span (none for array elements).
    fn children(self) -> Vec<(Seg, Option<Range<usize>>, Node<'d>)> {
        if let Some(t) = self.table_like() {
            return t
                .iter()
                .map(|(k, item)| {
                    let key_span = t.get_key_value(k).and_then(|(key, _)| key.span());
                    (Seg::Key(k.to_string()), key_span, Node::Item(item))
                })
                .collect();
        }
        let indexed = |nodes: Vec<Node<'d>>| {
            nodes
                .into_iter()
                .enumerate()
                .map(|(i, n)| (Seg::Index(i), None, n))
                .collect()
        };
        match self {
            Node::Item(toml_edit::Item::ArrayOfTables(a)) => {
                indexed(a.iter().map(Node::Table).collect())
            }
            Node::Item(toml_edit::Item::Value(v)) => Node::Value(v).children(),
            Node::Value(toml_edit::Value::Array(a)) => indexed(a.iter().map(Node::Value).collect()),
            _ => Vec::new(),
        }
    }

    fn child(self, seg: &Seg) -> Option<(Option<Range<usize>>, Node<'d>)> {
        self.children()
            .into_iter()
            .find(|(s, _, _)| s == seg)
            .map(|(_, k, n)| (k, n))
    }
}

/// Parsing context: the file, its directory and the span tree.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a Path,
    base: PathBuf,
    text: &'a str,
    /// Parsed only when an error needs a location (loading a valid file skips it).
    doc: std::cell::OnceCell<Option<toml_edit::ImDocument<&'a str>>>,
    /// Every asset resolved so far, in the order the file names them: the scene's
    /// inputs besides the file itself ([`super::Scene::sources`]).
    pub(super) assets: std::cell::RefCell<Vec<PathBuf>>,
}

impl<'a> Ctx<'a> {
    /// `path` names the file in messages; its directory is the base of asset paths.
    pub(super) fn new(text: &'a str, path: &'a Path) -> Self {
        Self {
            file: path,
            base: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            text,
            doc: std::cell::OnceCell::new(),
            assets: Default::default(),
        }
    }

    fn doc(&self) -> Option<&toml_edit::ImDocument<&'a str>> {
        self.doc
            .get_or_init(|| toml_edit::ImDocument::parse(self.text).ok())
            .as_ref()
    }

    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut end = offset.min(self.text.len());
        while !self.text.is_char_boundary(end) {
            end -= 1;
        }
        let before = &self.text[..end];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        (line, col)
    }

    /// Byte offset of `path`: its value, else its key, else the deepest ancestor
    /// that exists in the text (a missing key is reported at its table).
    fn offset_of(&self, path: &KeyPath) -> Option<usize> {
        self.offset_in(path, false)
    }

    /// As [`Ctx::offset_of`]; with `key_first` the last segment's key is
    /// preferred to its value (an unknown key is reported where it is written).
    fn offset_in(&self, path: &KeyPath, key_first: bool) -> Option<usize> {
        let doc = self.doc()?;
        let mut node = Node::Table(doc.as_table());
        let mut best = None;
        for (i, seg) in path.0.iter().enumerate() {
            let Some((key_span, child)) = node.child(seg) else {
                break;
            };
            let span = if key_first && i + 1 == path.0.len() {
                key_span.or(child.span())
            } else {
                child.span().or(key_span)
            };
            best = span.map(|s| s.start).or(best);
            node = child;
        }
        best
    }

    /// An error about the key at the end of `path` itself (not its value).
    pub(super) fn key_err(&self, path: &KeyPath, message: impl Into<String>) -> crate::Error {
        crate::Error::Scene {
            path: self.file.to_path_buf(),
            location: self.location(path, self.offset_in(path, true)),
            message: message.into(),
        }
    }

    /// The deepest key path whose key or value span contains `offset`.
    fn path_at(&self, offset: usize) -> KeyPath {
        fn walk(node: Node<'_>, path: &KeyPath, offset: usize, best: &mut (usize, KeyPath)) {
            for (seg, key_span, child) in node.children() {
                let mut p = path.clone();
                p.0.push(seg);
                let hit = |s: Option<Range<usize>>| s.is_some_and(|s| s.contains(&offset));
                if (hit(key_span) || hit(child.span())) && p.0.len() > best.0 {
                    *best = (p.0.len(), p.clone());
                }
                walk(child, &p, offset, best);
            }
        }
        let mut best = (0, KeyPath::default());
        if let Some(doc) = self.doc() {
            walk(
                Node::Table(doc.as_table()),
                &KeyPath::default(),
                offset,
                &mut best,
            );
        }
        best.1
    }

    fn location(&self, path: &KeyPath, offset: Option<usize>) -> String {
        match (path.0.is_empty(), offset.map(|o| self.line_col(o))) {
            (false, Some((l, c))) => format!("{path} (line {l}, column {c})"),
            (true, Some((l, c))) => format!("line {l}, column {c}"),
            (false, None) => path.to_string(),
            (true, None) => "top level".into(),
        }
    }

    pub(super) fn err(&self, path: &KeyPath, message: impl Into<String>) -> crate::Error {
        crate::Error::Scene {
            path: self.file.to_path_buf(),
            location: self.location(path, self.offset_of(path)),
            message: message.into(),
        }
    }

    pub(super) fn toml_err(&self, e: &toml::de::Error) -> crate::Error {
        let offset = e.span().map(|s| s.start);
        let path = offset.map(|o| self.path_at(o)).unwrap_or_default();
        let mut message = e.message().trim().replace('\n', "; ");
        if message.is_empty() {
            // toml reports some syntax errors (`key =` with no value) without text.
            message = "invalid TOML here: expected a value (a key needs `= value`)".into();
        }
        crate::Error::Scene {
            path: self.file.to_path_buf(),
            location: self.location(&path, offset),
            message,
        }
    }

    /// Resolves an asset path relative to the scene file; a missing file, a
    /// folder or a device is an error at `at` naming the resolved path.
    pub(super) fn asset(&self, at: &KeyPath, file: &str) -> crate::Result<PathBuf> {
        let p = self.base.join(file);
        match std::fs::metadata(&p) {
            Ok(m) if m.is_file() => {
                self.assets.borrow_mut().push(p.clone());
                Ok(p)
            }
            Ok(m) => Err(self.err(
                at,
                format!(
                    "{} is {}, not a regular file; expected a file",
                    p.display(),
                    crate::error::file_kind(&m)
                ),
            )),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                Err(self.err(at, format!("file not found: {}", p.display())))
            }
            Err(e) => Err(self.err(at, format!("cannot access {}: {e}", p.display()))),
        }
    }

    /// An error about an asset (OBJ, MTL, image) as an error of the scene key
    /// `at` that names it: one message with the scene file, key, line and asset.
    pub(super) fn in_scene(&self, at: &KeyPath, e: crate::Error) -> crate::Error {
        match e {
            crate::Error::Asset { path, message } => {
                self.err(at, format!("{}: {message}", path.display()))
            }
            crate::Error::Io { path, source } => self.err(
                at,
                format!("{}: cannot read file: {source}", path.display()),
            ),
            other => other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_paths_map_to_lines_and_back() {
        let text = "[camera]\nfrom = [0, 0, 5]\n\n[[shapes]]\ntype = \"sphere\"\n\n[[shapes]]\nradius = -1\ntransform = { rotate = [0, 1, 0, 30] }\n";
        let ctx = Ctx::new(text, Path::new("t.toml"));
        let p = root("shapes").index(1).key("radius");
        assert_eq!(p.to_string(), "shapes[1].radius");
        let o = ctx.offset_of(&p).unwrap();
        assert_eq!(ctx.line_col(o), (8, 10));
        assert_eq!(ctx.path_at(o), p);
        let r = root("shapes").index(1).key("transform").key("rotate");
        let o = ctx.offset_of(&r).unwrap();
        assert_eq!(ctx.line_col(o).0, 9);
        assert_eq!(ctx.path_at(o + 1), r.index(0));
        // A missing key is reported at its table.
        let missing = root("shapes").index(0).key("radius");
        assert_eq!(ctx.line_col(ctx.offset_of(&missing).unwrap()).0, 4);
    }
}
