//! The XML layer of the Mitsuba importer: files read, `<include>`s spliced
//! in, `<default>`s and `-D` parameters substituted, `<path>`s collected.
//!
//! The result is one owned [`Element`] tree of the scene, every element
//! knowing its file and line ([`Place`]) and the folders that its file
//! names are resolved in. Nothing here knows plugins or properties.
//!
//! Semantics (Mitsuba 3.9.1, `src/core/xml.cpp`):
//! * `<default name value>` defines the parameter `name` unless it is
//!   already defined (by `-D name=value` on the command line or an earlier
//!   default): command-line values win.
//! * `$name` in any attribute value (also `type`, `id`, `filename`) is
//!   replaced by the parameter's value; a `$name` with no value is an
//!   error, `\$` is a literal `$`. As in Mitsuba, names are matched as
//!   substrings, the longest defined name first: with only `x` defined,
//!   `$xy` reads as the value of `x` followed by `y`. A `-D` parameter that
//!   the file never uses is a warning (an error in Mitsuba).
//! * `<include filename>` reads another file whose root is `<scene>` and
//!   puts its children in place of the include (with the same parameters);
//!   an include of a file that is being included is a cycle (error).
//! * `<path value>` adds a folder to the search path of later file names
//!   (relative to the file it appears in).
//! * Plugins' file names (meshes, images) are looked up in the `<path>`
//!   folders (latest first), then the scene file's folder — not the
//!   folder of an included file, as in Mitsuba, which resolves them after
//!   parsing. Included files and `.spd` spectra are looked up in the folder
//!   of the file that names them first ([`Place::resolve_local`]).
//!
//! Limits (bad input must not exhaust memory or the stack): each file at
//! most [`MAX_XML_FILE_BYTES`], [`MAX_NODES`] XML nodes per file, nesting at
//! most [`MAX_DEPTH`] elements, includes at most [`MAX_INCLUDE_DEPTH`] deep
//! and [`MAX_INCLUDES`] in all.

use crate::error::CliError;
use crate::scene_file::source::{located, read_text};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Largest XML file read, bytes (16 MiB).
pub(crate) const MAX_XML_FILE_BYTES: u64 = 16 * 1024 * 1024;
/// Largest number of XML nodes in one file (a million: far above real
/// scene files, whose meshes live in other files).
pub(crate) const MAX_NODES: u32 = 1_000_000;
/// Deepest element nesting (real files nest 4–6 deep).
pub(crate) const MAX_DEPTH: usize = 64;
/// Deepest chain of includes.
pub(crate) const MAX_INCLUDE_DEPTH: usize = 16;
/// Most includes in one scene.
pub(crate) const MAX_INCLUDES: usize = 1024;

/// Where an element is: its file (as shown in messages), line, and the
/// folders its file names are resolved in.
#[derive(Debug, Clone)]
pub(crate) struct Place {
    /// The file, as messages name it.
    pub(crate) file: Rc<str>,
    /// 1-based line.
    pub(crate) line: u32,
    /// Folders that plugins' file names are looked up in, in order (empty
    /// when file references are refused).
    pub(crate) search: Rc<[PathBuf]>,
    /// The folder of the element's own file (`None` when file references
    /// are refused).
    pub(crate) dir: Option<Rc<Path>>,
}

impl Place {
    /// `file:line: message`.
    pub(crate) fn message(&self, message: impl std::fmt::Display) -> String {
        located(&self.file, self.line as usize, "", message)
    }

    /// An input error `file:line: message`.
    pub(crate) fn error(&self, message: impl std::fmt::Display) -> CliError {
        CliError::input(self.message(message))
    }

    /// The file `name` found in the search folders: the first folder where
    /// it exists, else the first folder (the read then reports it missing).
    /// Absolute names are kept. `None` when file references are refused.
    pub(crate) fn resolve(&self, name: &str) -> Option<PathBuf> {
        find(name, self.search.iter().map(PathBuf::as_path))
    }

    /// [`Place::resolve`] with the element's own folder searched first (for
    /// includes and spectrum files, which Mitsuba resolves while parsing).
    pub(crate) fn resolve_local(&self, name: &str) -> Option<PathBuf> {
        let dir = self.dir.as_deref()?;
        find(
            name,
            std::iter::once(dir).chain(self.search.iter().map(PathBuf::as_path)),
        )
    }
}

/// `name` in the first of `folders` where it exists, else in the first
/// folder (the read then reports it missing); absolute names as they are.
/// `None` when there is no folder (file references refused).
fn find<'a>(name: &str, mut folders: impl Iterator<Item = &'a Path>) -> Option<PathBuf> {
    let path = Path::new(name);
    if path.is_absolute() {
        return Some(path.to_path_buf());
    }
    let first = folders.next()?.join(path);
    if first.exists() {
        return Some(first);
    }
    Some(
        folders
            .map(|dir| dir.join(path))
            .find(|p| p.exists())
            .unwrap_or(first),
    )
}

/// An element after substitution and includes.
#[derive(Debug, Clone)]
pub(crate) struct Element {
    /// Tag name.
    pub(crate) tag: String,
    /// Attributes, values substituted, in document order.
    pub(crate) attrs: Vec<(String, String)>,
    /// Child elements (text and comments dropped).
    pub(crate) children: Vec<Element>,
    /// Where it is.
    pub(crate) place: Place,
}

impl Element {
    /// The attribute `name`.
    pub(crate) fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// An input error at the element.
    pub(crate) fn error(&self, message: impl std::fmt::Display) -> CliError {
        self.place.error(message)
    }
}

/// Where the scene comes from.
pub(crate) enum Input<'a> {
    /// A file on disk; includes and file names resolved around it.
    File(&'a Path),
    /// Text named `name` (for messages); every include and file reference
    /// refused (the fuzz entry point reads no file).
    Text {
        /// Shown in messages.
        name: &'a str,
        /// The XML.
        text: &'a str,
    },
}

/// A scene read: its root and the warnings of reading it.
pub(crate) struct ReadScene {
    /// The `<scene>` root with includes spliced in and every `<default>`,
    /// `<include>` and `<path>` consumed.
    pub(crate) root: Element,
    /// One line each.
    pub(crate) warnings: Vec<String>,
}

/// Reads the scene (module docs) with the parameters `defines`
/// (`-D name=value`, which win over `<default>`s).
pub(crate) fn read_scene(
    input: Input<'_>,
    defines: &[(String, String)],
) -> Result<ReadScene, CliError> {
    let shown_input = match input {
        Input::File(path) => path.display().to_string(),
        Input::Text { name, .. } => name.to_string(),
    };
    let mut reader = Reader {
        params: defines.to_vec(),
        used: vec![false; defines.len()],
        search_cache: None,
        paths: Vec::new(),
        including: Vec::new(),
        includes: 0,
        scene_dir: None,
    };
    let root = match input {
        Input::File(path) => {
            let text = read_text(path, MAX_XML_FILE_BYTES)?;
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            reader.scene_dir = Some(dir.clone());
            reader.including.push(canonical(path));
            let shown: Rc<str> = path.display().to_string().into();
            reader.file(&shown, &text, Some(dir))
        }
        Input::Text { name, text } => reader.file(&name.into(), text, None),
    }?;
    let warnings = defines
        .iter()
        .zip(&reader.used)
        .filter(|(_, used)| !**used)
        .map(|((name, _), _)| {
            format!("{shown_input}: -D {name}=…: the file does not use `${name}`")
        })
        .collect();
    Ok(ReadScene { root, warnings })
}

/// The canonical form of `path` for cycle detection (the path itself if it
/// cannot be canonicalised).
fn canonical(path: &Path) -> PathBuf {
    path.canonicalize().unwrap_or_else(|_| path.to_path_buf())
}

struct Reader {
    /// Parameters in definition order (`-D` first).
    params: Vec<(String, String)>,
    /// Whether each `-D` parameter was used.
    used: Vec<bool>,
    /// [`Reader::search`]'s folders until the next `<path>`.
    search_cache: Option<Rc<[PathBuf]>>,
    /// `<path>` folders, in order of appearance.
    paths: Vec<PathBuf>,
    /// Canonical paths of the files being read (include chain).
    including: Vec<PathBuf>,
    includes: usize,
    /// The scene file's folder (`None`: file references refused).
    scene_dir: Option<PathBuf>,
}

/// `text` on one line: control characters written as escapes (`\n`). The
/// XML parser's messages quote the character it did not expect, which may
/// be a line break: `expected '>' not '\n'`.
fn one_line(text: &str) -> String {
    text.chars()
        .fold(String::with_capacity(text.len()), |mut line, c| {
            if c.is_control() {
                line.extend(c.escape_default());
            } else {
                line.push(c);
            }
            line
        })
}

impl Reader {
    /// Parses one file; `dir` is its folder (`None`: no file references).
    fn file(
        &mut self,
        shown: &Rc<str>,
        text: &str,
        dir: Option<PathBuf>,
    ) -> Result<Element, CliError> {
        let options = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: MAX_NODES,
        };
        let document = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
            let pos = e.pos();
            CliError::input(format!(
                "{shown}:{}: malformed XML: {} (column {})",
                pos.row,
                one_line(&e.to_string()),
                pos.col
            ))
        })?;
        let root = document.root_element();
        let line = |node: roxmltree::Node<'_, '_>| document.text_pos_at(node.range().start).row;
        if root.tag_name().name() != "scene" {
            return Err(CliError::input(located(
                shown,
                line(root) as usize,
                "",
                format!(
                    "the root element is <{}>, expected <scene>",
                    root.tag_name().name()
                ),
            )));
        }
        let mut scene = Element {
            tag: "scene".into(),
            attrs: Vec::new(),
            children: Vec::new(),
            place: Place {
                file: shown.clone(),
                line: line(root),
                search: self.search(dir.as_deref()),
                dir: dir.as_deref().map(Rc::from),
            },
        };
        scene.attrs = self.attributes(&scene.place, root)?;
        let file = FileCtx {
            shown,
            dir: dir.as_deref(),
            document: &document,
        };
        self.children(&file, root, &mut scene.children, 1)?;
        Ok(scene)
    }

    /// The search folders of plugins' file names in a file in `dir`
    /// (module docs): the `<path>`s, latest first, then the scene's folder.
    fn search(&mut self, dir: Option<&Path>) -> Rc<[PathBuf]> {
        if dir.is_none() {
            return Rc::from(Vec::new());
        }
        if let Some(cached) = &self.search_cache {
            return cached.clone();
        }
        let mut folders: Vec<PathBuf> = self.paths.iter().rev().cloned().collect();
        if let Some(scene_dir) = &self.scene_dir
            && !folders.contains(scene_dir)
        {
            folders.push(scene_dir.clone());
        }
        let folders: Rc<[PathBuf]> = Rc::from(folders);
        self.search_cache = Some(folders.clone());
        folders
    }

    /// The attributes of `node`, substituted.
    fn attributes(
        &mut self,
        place: &Place,
        node: roxmltree::Node<'_, '_>,
    ) -> Result<Vec<(String, String)>, CliError> {
        node.attributes()
            .map(|a| Ok((a.name().to_string(), self.substitute(place, a.value())?)))
            .collect()
    }

    /// `value` with every `$name` replaced (module docs).
    fn substitute(&mut self, place: &Place, value: &str) -> Result<String, CliError> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(at) = rest.find('$') {
            if rest[..at].ends_with('\\') {
                out.push_str(&rest[..at - 1]);
                out.push('$');
                rest = &rest[at + 1..];
                continue;
            }
            out.push_str(&rest[..at]);
            let after = &rest[at + 1..];
            // The longest parameter name that the text continues with
            // (Mitsuba replaces `$name` substrings, longest name first).
            let found = self
                .params
                .iter()
                .enumerate()
                .filter(|(_, (n, _))| after.starts_with(n.as_str()))
                .max_by_key(|(_, (n, _))| n.len())
                .map(|(i, (n, _))| (i, n.len()));
            let Some((index, len)) = found else {
                let len = after
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .unwrap_or(after.len());
                let name = &after[..len];
                if name.is_empty() {
                    return Err(place.error(format!(
                        "\"{value}\": `$` must be followed by a parameter name (`\\$` for a literal `$`)"
                    )));
                }
                return Err(place.error(format!(
                    "`${name}` has no value: add <default name=\"{name}\" value=\"…\"/> to the file or pass -D {name}=…"
                )));
            };
            if let Some(used) = self.used.get_mut(index) {
                *used = true;
            }
            out.push_str(&self.params[index].1);
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn children(
        &mut self,
        file: &FileCtx<'_, '_>,
        node: roxmltree::Node<'_, '_>,
        out: &mut Vec<Element>,
        depth: usize,
    ) -> Result<(), CliError> {
        for child in node.children().filter(roxmltree::Node::is_element) {
            let place = Place {
                file: file.shown.clone(),
                line: file.document.text_pos_at(child.range().start).row,
                search: self.search(file.dir),
                dir: file.dir.map(Rc::from),
            };
            if depth >= MAX_DEPTH {
                return Err(place.error(format!("elements are nested more than {MAX_DEPTH} deep")));
            }
            let tag = child.tag_name().name();
            let attrs = self.attributes(&place, child)?;
            let attr = |name: &str| {
                attrs
                    .iter()
                    .find(|(n, _)| n == name)
                    .map(|(_, v)| v.as_str())
            };
            match tag {
                "default" => {
                    let (Some(name), Some(value)) = (attr("name"), attr("value")) else {
                        return Err(place.error("<default> needs `name` and `value`"));
                    };
                    if !self.params.iter().any(|(n, _)| n == name) {
                        self.params.push((name.to_string(), value.to_string()));
                    }
                }
                "path" => {
                    let Some(value) = attr("value") else {
                        return Err(place.error("<path> needs `value`"));
                    };
                    if let Some(dir) = file.dir {
                        self.paths.push(dir.join(value));
                        self.search_cache = None;
                    }
                }
                "include" => {
                    let Some(name) = attr("filename") else {
                        return Err(place.error("<include> needs `filename`"));
                    };
                    let included = self.include(&place, name, depth)?;
                    out.extend(included.children);
                }
                _ => {
                    let mut element = Element {
                        tag: tag.to_string(),
                        attrs,
                        children: Vec::new(),
                        place,
                    };
                    self.children(file, child, &mut element.children, depth + 1)?;
                    out.push(element);
                }
            }
        }
        Ok(())
    }

    /// The `<scene>` of the included file `name`.
    fn include(&mut self, place: &Place, name: &str, depth: usize) -> Result<Element, CliError> {
        let Some(path) = place.resolve_local(name) else {
            return Err(place.error(format!(
                "<include filename=\"{name}\">: file references are not available here"
            )));
        };
        self.includes += 1;
        if self.includes > MAX_INCLUDES {
            return Err(place.error(format!("more than {MAX_INCLUDES} includes")));
        }
        if self.including.len() > MAX_INCLUDE_DEPTH || depth >= MAX_DEPTH {
            return Err(place.error(format!(
                "includes are nested more than {MAX_INCLUDE_DEPTH} deep"
            )));
        }
        let key = canonical(&path);
        if self.including.contains(&key) {
            return Err(place.error(format!(
                "<include filename=\"{name}\">: cyclic include ({} is already being read)",
                path.display()
            )));
        }
        let text = read_text(&path, MAX_XML_FILE_BYTES)
            .map_err(|e| place.error(format!("<include>: {e}")))?;
        self.including.push(key);
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let shown: Rc<str> = path.display().to_string().into();
        let scene = self.file(&shown, &text, Some(dir));
        self.including.pop();
        scene
    }
}

/// The file being read.
struct FileCtx<'f, 'd> {
    shown: &'f Rc<str>,
    dir: Option<&'f Path>,
    document: &'f roxmltree::Document<'d>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, defines: &[(&str, &str)]) -> Result<Element, CliError> {
        let defines: Vec<(String, String)> = defines
            .iter()
            .map(|(n, v)| (n.to_string(), v.to_string()))
            .collect();
        read_scene(
            Input::Text {
                name: "t.xml",
                text,
            },
            &defines,
        )
        .map(|r| r.root)
    }

    #[test]
    fn defaults_substitute_and_defines_win() -> Result<(), CliError> {
        let text = r#"<scene version="3.0.0">
            <default name="spp" value="16"/>
            <default name="kind" value="dif"/>
            <bsdf type="${kind}fuse" id="a$spp"/>
            <integer name="n" value="$spp"/>
        </scene>"#
            .replace("${kind}", "$kind");
        let scene = read(&text, &[("spp", "64")])?;
        assert_eq!(scene.children.len(), 2);
        assert_eq!(scene.children[0].attr("type"), Some("diffuse"));
        assert_eq!(scene.children[0].attr("id"), Some("a64"));
        assert_eq!(scene.children[1].attr("value"), Some("64"));
        assert_eq!(scene.children[1].place.line, 5);
        Ok(())
    }

    #[test]
    fn undefined_parameters_and_bad_xml_are_one_line_errors() {
        let e = read(r#"<scene><float name="a" value="$nope"/></scene>"#, &[]);
        let message = e.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            message.starts_with("t.xml:1: `$nope` has no value"),
            "{message}"
        );
        let e = read("<scene>\n<float name=\"a\" value=\"1\">\n</scene>", &[]);
        let message = e.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(message.starts_with("t.xml:3: malformed XML"), "{message}");
        assert!(!message.contains('\n'));
        // The parser quotes the line break it did not expect (found by the
        // fuzz target `scene_xml`): written as an escape.
        let e = read("<scene>\n<float name=\"a\" value=\"1\"/\n></scene>", &[]);
        let message = e.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            message.starts_with("t.xml:2: malformed XML: expected '>' not '\\n'"),
            "{message}"
        );
        assert!(!message.contains('\n'), "{message:?}");
        let e = read("<shape/>", &[]);
        assert!(e.is_err());
    }

    #[test]
    fn includes_are_refused_without_files_and_nesting_is_bounded() {
        let e = read(r#"<scene><include filename="a.xml"/></scene>"#, &[]);
        assert!(e.is_err());
        let deep = format!(
            "<scene>{}{}</scene>",
            "<shape type=\"a\">".repeat(MAX_DEPTH + 1),
            "</shape>".repeat(MAX_DEPTH + 1)
        );
        let message = read(&deep, &[])
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(message.contains("nested more than"), "{message}");
    }
}
