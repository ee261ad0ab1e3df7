//! The files a command writes: checked before any work, replaced all together at the end.
//!
//! [`Outputs::stage`] runs before the scene is loaded. It refuses an output that is the
//! input scene file or the same file as another output (paths are compared after
//! resolving `.`, `..` and symbolic links, so `./a.png` and `a.png` are one file), and
//! an output that is a directory. It then creates an empty temporary file beside each
//! output (`.NAME.obscura-PID.tmp`), which proves the directory is writable before
//! minutes of rendering. The command writes each output to its temporary file and
//! [`Outputs::commit`] renames them all into place, so a failure (a full disk, an error
//! in a later output) leaves the previous files untouched and no half-written ones; the
//! temporary files are removed on every error and when standard output is closed. An
//! output that exists and is not a regular file (`/dev/null`, a named pipe) is written
//! in place. An existing output keeps its permissions; a symbolic link keeps pointing to
//! the file that is replaced.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use obscura::{Error, Result};

/// Temporary files not yet renamed into place, removed if the program ends early.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file not yet committed (before an early exit).
pub fn discard_pending() {
    let mut pending = PENDING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    for t in pending.drain(..) {
        let _ = fs::remove_file(t);
    }
}

/// One output file.
struct Staged {
    /// The option that names it, e.g. `--ids`.
    option: &'static str,
    /// The path as given: named in messages.
    given: PathBuf,
    /// The file that ends up replaced (the given path with symbolic links resolved).
    target: PathBuf,
    /// Where it is written first; `None` for a device or pipe, written in place.
    temp: Option<PathBuf>,
    /// Whether the command wrote it.
    written: bool,
}

/// The checked outputs of one command.
pub struct Outputs {
    files: Vec<Staged>,
}

/// The file a path names, for comparing paths: canonical where it exists, else its
/// canonical directory and its name (following a dangling symbolic link to the file it
/// would create).
fn identity(path: &Path) -> PathBuf {
    identity_within(path, 40)
}

fn identity_within(path: &Path, links: u32) -> PathBuf {
    if let Ok(p) = fs::canonicalize(path) {
        return p;
    }
    if links > 0
        && let Ok(to) = fs::read_link(path)
    {
        let to = match path.parent() {
            Some(dir) if to.is_relative() => dir.join(to),
            _ => to,
        };
        return identity_within(&to, links - 1);
    }
    let name = path.file_name();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (fs::canonicalize(dir), name) {
        (Ok(d), Some(n)) => d.join(n),
        _ => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

impl Outputs {
    /// Checks the outputs (each `(option, path)`, `None` when not asked for) against each
    /// other and against the input scene, and creates their temporary files.
    pub fn stage(input: Option<&str>, outputs: &[(&'static str, Option<&Path>)]) -> Result<Self> {
        let given: Vec<(&'static str, &Path)> = outputs
            .iter()
            .filter_map(|&(o, p)| p.map(|p| (o, p)))
            .collect();
        let ids: Vec<PathBuf> = given.iter().map(|(_, p)| identity(p)).collect();
        let input = input
            .filter(|s| !s.starts_with("demo:"))
            .map(|s| (s, identity(Path::new(s))));
        for (k, &(option, path)) in given.iter().enumerate() {
            if let Some((spec, id)) = &input
                && *id == ids[k]
            {
                return Err(Error::option(
                    option,
                    format!(
                        "{} is the input scene {spec}: refusing to overwrite it",
                        path.display()
                    ),
                ));
            }
            if let Some(j) = (0..k).find(|&j| ids[j] == ids[k]) {
                return Err(Error::option(
                    option,
                    format!(
                        "{} is the same file as {} {}: give each output its own file",
                        path.display(),
                        given[j].0,
                        given[j].1.display()
                    ),
                ));
            }
        }
        // The picture is always PNG: a name promising another format would hold PNG
        // data under a misleading extension (`-o out.jpg`).
        for &(option, path) in &given {
            if option == "-o"
                && let Some(ext) = path.extension()
                && !ext.eq_ignore_ascii_case("png")
            {
                return Err(Error::option(
                    option,
                    format!(
                        "{}: obscura writes PNG images; name the file .png",
                        path.display()
                    ),
                ));
            }
        }
        let mut staged = Outputs { files: Vec::new() };
        for (&(option, path), id) in given.iter().zip(ids) {
            staged.files.push(stage_one(option, path, id)?);
        }
        Ok(staged)
    }

    /// Writes the output of `option` with `write`, given the path to write to; an error
    /// about that path names the output as given.
    pub fn write(&mut self, option: &str, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let f = self
            .files
            .iter_mut()
            .find(|f| f.option == option)
            .expect("an output that was staged");
        let path = f.temp.as_deref().unwrap_or(&f.target);
        match write(path) {
            Ok(()) => {
                f.written = true;
                Ok(())
            }
            Err(Error::Io { path: p, source }) if p == path => Err(Error::io(&f.given, source)),
            Err(e) => Err(e),
        }
    }

    /// Renames every written output into place.
    pub fn commit(mut self) -> Result<()> {
        for f in &mut self.files {
            if let (Some(temp), true) = (&f.temp, f.written) {
                fs::rename(temp, &f.target).map_err(|e| Error::io(&f.given, e))?;
                unregister(temp);
                f.temp = None;
            }
        }
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        for t in self.files.iter().filter_map(|f| f.temp.as_ref()) {
            let _ = fs::remove_file(t);
            unregister(t);
        }
    }
}

fn unregister(temp: &Path) {
    let mut pending = PENDING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    pending.retain(|p| p != temp);
}

/// Checks one output and creates its temporary file.
fn stage_one(option: &'static str, path: &Path, id: PathBuf) -> Result<Staged> {
    let existing = fs::metadata(path).ok();
    let mut staged = Staged {
        option,
        given: path.to_path_buf(),
        target: path.to_path_buf(),
        temp: None,
        written: false,
    };
    match &existing {
        Some(m) if m.is_dir() => {
            return Err(Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
            ));
        }
        Some(m) if !m.is_file() => return Ok(staged),
        _ => staged.target = id,
    }
    let name = staged
        .target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let pid = std::process::id();
    let temp_name = if name.len() <= 200 {
        format!(".{name}.obscura-{pid}.tmp")
    } else {
        format!(".obscura-{pid}-{option}.tmp")
    };
    let temp = staged.target.with_file_name(temp_name);
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(|e| Error::io(path, e))?;
    PENDING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .push(temp.clone());
    if let Some(m) = existing {
        let _ = fs::set_permissions(&temp, m.permissions());
    }
    staged.temp = Some(temp);
    Ok(staged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tempdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("obscura-outputs-{name}-{}", std::process::id()));
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn the_same_file_under_two_spellings_is_refused() {
        let d = tempdir("same");
        let a = d.join("a.png");
        let b = d.join(".").join("sub").join("..").join("a.png");
        fs::create_dir_all(d.join("sub")).unwrap();
        let e = Outputs::stage(None, &[("-o", Some(&a)), ("--ids", Some(&b))])
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("--ids") && e.contains("same file as -o"), "{e}");
        assert!(!a.exists());
        fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn nothing_is_replaced_until_commit_and_errors_leave_no_files() {
        let d = tempdir("commit");
        let a = d.join("a.txt");
        fs::write(&a, "old").unwrap();
        let mut o = Outputs::stage(None, &[("--json", Some(&a))]).unwrap();
        o.write("--json", |p| {
            fs::write(p, "new").map_err(|e| Error::io(p, e))
        })
        .unwrap();
        assert_eq!(fs::read_to_string(&a).unwrap(), "old");
        drop(o);
        assert_eq!(fs::read_to_string(&a).unwrap(), "old");
        assert_eq!(
            fs::read_dir(&d).unwrap().count(),
            1,
            "a temporary file is left"
        );
        let mut o = Outputs::stage(None, &[("--json", Some(&a))]).unwrap();
        o.write("--json", |p| {
            fs::write(p, "new").map_err(|e| Error::io(p, e))
        })
        .unwrap();
        o.commit().unwrap();
        assert_eq!(fs::read_to_string(&a).unwrap(), "new");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
        fs::remove_dir_all(&d).ok();
    }
}
