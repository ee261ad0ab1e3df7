//! References from one file to another (a glTF buffer URI, an OBJ `mtllib`, a scene
//! file's `mesh`), resolved by one rule for every loader, and the record of every file
//! a load read.
//!
//! The rule ([`Sources::resolve`]): a reference is resolved against the folder of the
//! file that holds it, its `..` and symbolic links resolved (the path is made
//! canonical), and must stay inside that folder's tree. Refused with
//! [`Error::OutsideReference`], naming the referring file, the element (line, buffer)
//! and the reference as written, unless
//! [`LoadOptions::allow_outside_references`] is set:
//! - an absolute path (`/etc/passwd`, `//host/x`);
//! - a `file:` URI (in formats whose references are URIs: glTF);
//! - a relative path that climbs out with `..` (checked on the text first, so a file
//!   outside is never even looked up) or whose canonical form lies outside (a symbolic
//!   link inside the folder pointing out of it).
//!
//! In URI references, other schemes (`http:`, `https:`...) are refused whatever the
//! option: obscura reads no network. `data:` URIs hold their bytes and are no file
//! reference: the loaders decode them without calling this module. A URI's
//! percent-encoding is decoded before the rule applies (`%2E%2E/x.bin` is `../x.bin`).
//!
//! [`Sources`] also records, canonical and once each, every file the load read (the
//! scene file itself, meshes, material libraries, buffers): [`Scene::source_files`]
//! hands the list to the caller, which can refuse to write over any of them.
//!
//! Checks are made on the canonical path when the reference is resolved; a file
//! replaced by a link between that check and the read is not caught (the scene's
//! author is not racing its reader).
//!
//! [`Scene::source_files`]: crate::scene::Scene::source_files

use std::path::{Component, Path, PathBuf};

use super::LoadOptions;
use crate::{Error, Result};

/// How a format writes its references.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Syntax {
    /// A file path, as OBJ's `mtllib` and scene files' `mesh` (no URI schemes, no
    /// percent-encoding).
    Path,
    /// A URI reference (glTF 2.0, 3.6.1.1): percent-encoded, possibly with a scheme.
    Uri,
}

/// What a load may read, and what it has read.
#[derive(Debug)]
pub(crate) struct Sources<'o> {
    options: &'o LoadOptions,
    read: Vec<PathBuf>,
}

impl<'o> Sources<'o> {
    /// A load with these options that has read nothing yet.
    pub(crate) fn new(options: &'o LoadOptions) -> Self {
        Sources {
            options,
            read: Vec::new(),
        }
    }

    /// The options of the load.
    #[allow(dead_code)] // read by the memory budget's loaders
    pub(crate) fn options(&self) -> &'o LoadOptions {
        self.options
    }

    /// The canonical paths of the files read so far, each once, in the order first read.
    pub(crate) fn into_files(self) -> Vec<PathBuf> {
        self.read
    }

    /// Notes that `path` was read (its canonical form, once).
    pub(crate) fn record(&mut self, path: &Path) {
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| absolute(path));
        if !self.read.contains(&canonical) {
            self.read.push(canonical);
        }
    }

    /// Reads a whole regular file (see [`super::read_file`]) and records it.
    pub(crate) fn read(&mut self, path: &Path) -> Result<Vec<u8>> {
        let bytes = super::read_file(path)?;
        self.record(path);
        Ok(bytes)
    }

    /// Resolves `reference`, written in `referrer` at `element` (e.g. `line 3`,
    /// `buffer 0`), by the module's rule. Returns the path to read: the referrer's
    /// folder joined with the (decoded) reference, or the absolute path when the
    /// options allow one; it exists (its canonical form was found).
    ///
    /// Errors: [`Error::OutsideReference`]; [`Error::Format`] for a URI with another
    /// scheme or malformed percent-encoding; [`Error::Io`] (naming the joined path) when
    /// the file cannot be found, which some callers turn into a warning.
    pub(crate) fn resolve(
        &self,
        referrer: &Path,
        element: &str,
        reference: &str,
        syntax: Syntax,
    ) -> Result<PathBuf> {
        let allow = self.options.allow_outside_references;
        let outside = |reason: &str| Error::OutsideReference {
            path: referrer.to_path_buf(),
            element: element.to_string(),
            reference: reference.to_string(),
            reason: reason.to_string(),
        };
        let malformed = |m: String| Error::format(referrer, element, m);
        let written: PathBuf = match syntax {
            Syntax::Path => PathBuf::from(reference),
            Syntax::Uri => match uri_scheme(reference) {
                Some(s) if s.eq_ignore_ascii_case("file") => {
                    if !allow {
                        return Err(outside("is a file: URI"));
                    }
                    file_uri_path(reference).ok_or_else(|| {
                        malformed(format!(
                            "\"{reference}\" is not a local file: URI (file:///path or \
                             file:/path)"
                        ))
                    })?
                }
                Some(scheme) => {
                    return Err(malformed(format!(
                        "remote files are not read (a {scheme}: URI; obscura reads no \
                         network): download the file into the folder of {} and refer to \
                         it by a relative path",
                        referrer.display()
                    )));
                }
                None => PathBuf::from(percent_decode(reference).ok_or_else(|| {
                    malformed(format!(
                        "URI \"{reference}\" is not valid percent-encoded UTF-8"
                    ))
                })?),
            },
        };
        if written.as_os_str().is_empty() {
            return Err(malformed("the reference is empty".to_string()));
        }
        let absolute_reference = written.has_root()
            || written
                .components()
                .any(|c| matches!(c, Component::Prefix(_)));
        if absolute_reference && !allow {
            return Err(outside("is an absolute path"));
        }
        if !allow && climbs_out(&written) {
            return Err(outside("climbs out of the folder of the file with `..`"));
        }
        let dir = folder_of(referrer);
        let joined = if absolute_reference {
            written
        } else {
            dir.join(&written)
        };
        let canonical = std::fs::canonicalize(&joined).map_err(|e| Error::io(&joined, e))?;
        if !allow {
            let root = std::fs::canonicalize(&dir).map_err(|e| Error::io(&dir, e))?;
            if !canonical.starts_with(&root) {
                return Err(outside(
                    "leads out of the folder of the file through a symbolic link",
                ));
            }
        }
        Ok(joined)
    }
}

/// The folder of a file as it was named (`.` for a bare file name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A path made absolute without touching the file system (for a file that vanished).
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// Whether a relative path, read as text, climbs above its starting folder
/// (`../x`, `a/../../x`).
fn climbs_out(path: &Path) -> bool {
    let mut depth = 0usize;
    for c in path.components() {
        match c {
            Component::Normal(_) => depth += 1,
            Component::ParentDir => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => return true,
            },
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
        }
    }
    false
}

/// The scheme of an absolute URI (`http` in `http://host/x.bin`), if it has one. A
/// relative reference cannot have a colon in its first segment (RFC 3986, 4.2), and a
/// one-letter scheme would be a Windows drive (`C:`), taken as a path.
pub(crate) fn uri_scheme(uri: &str) -> Option<&str> {
    let (scheme, _) = uri.split_once(':')?;
    let mut chars = scheme.chars();
    let valid = chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'));
    (valid && scheme.len() > 1).then_some(scheme)
}

/// The local path of a `file:` URI (`file:///p`, `file://localhost/p`, `file:/p`), its
/// percent-encoding decoded; `None` for another host or a malformed one.
fn file_uri_path(uri: &str) -> Option<PathBuf> {
    let rest = &uri[uri.find(':')? + 1..];
    let path = match rest.strip_prefix("//") {
        Some(authority_and_path) => {
            let slash = authority_and_path.find('/')?;
            let host = &authority_and_path[..slash];
            if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
                return None;
            }
            &authority_and_path[slash..]
        }
        None => rest,
    };
    percent_decode(path).map(PathBuf::from)
}

/// Decodes `%XX` escapes; `None` when an escape is malformed or the result is not UTF-8.
pub(crate) fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut k = 0;
    while k < b.len() {
        if b[k] == b'%' {
            let hex = std::str::from_utf8(b.get(k + 1..k + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            k += 3;
        } else {
            out.push(b[k]);
            k += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn climbing_is_read_from_the_text() {
        for (p, out) in [
            ("x.bin", false),
            ("a/../x.bin", false),
            ("./a/./b/../../x.bin", false),
            ("../x.bin", true),
            ("a/../../x.bin", true),
            ("a/b/../../../x", true),
        ] {
            assert_eq!(climbs_out(Path::new(p)), out, "{p}");
        }
    }

    #[test]
    fn file_uris_give_local_paths_only() {
        assert_eq!(
            file_uri_path("file:///etc/a%20b"),
            Some(PathBuf::from("/etc/a b"))
        );
        assert_eq!(
            file_uri_path("file://localhost/x"),
            Some(PathBuf::from("/x"))
        );
        assert_eq!(file_uri_path("file:/x"), Some(PathBuf::from("/x")));
        assert_eq!(file_uri_path("file://server/x"), None);
        assert_eq!(uri_scheme("C:/x"), None);
        assert_eq!(uri_scheme("HTTP://x"), Some("HTTP"));
        assert_eq!(uri_scheme("a b:x"), None);
    }
}
