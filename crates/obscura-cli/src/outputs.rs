//! The files a command writes: checked before any work, replaced all together at the end.
//!
//! Files are compared by identity, not by spelling: an existing file by its device and
//! inode (so `./a.png`, `a.png`, a symbolic link to it and a hard link to it are one
//! file), a file yet to be created by its path with `.`, `..` and symbolic links
//! resolved (by canonical path alone where there are no inodes).
//!
//! [`Outputs::stage`] runs before the scene is loaded. It refuses an output that is the
//! input scene file or the same file as another output, an output whose extension is
//! not its format's (`-o` wants `.png`, `--ids` and `--depth` `.npy`, `--stats-json` and
//! `--json` `.json`; `--force-extension` lifts this, and devices and pipes such as
//! `/dev/stdout` have no extension to check), and an output that is a directory. It
//! then creates an empty temporary file beside each output (`.NAME.obscura-PID.tmp`),
//! which proves the directory is writable before minutes of rendering. Once the scene
//! is loaded, [`Outputs::check_inputs`] refuses an output that is any file the load
//! read (a mesh of a scene file, a material library, a glTF buffer), before rendering.
//! The command writes each output to its temporary file and [`Outputs::commit`]
//! renames them all into place, so a failure (a full disk, an error in a later output)
//! leaves the previous files untouched and no half-written ones; the temporary files
//! are removed on every error, when standard output is closed, and on SIGINT (Ctrl-C),
//! SIGTERM or SIGHUP ([`remove_temporaries_on_signal`]). An output that exists and is
//! not a regular file (`/dev/null`, a named pipe) is written in place. An existing
//! output keeps its permissions; a symbolic link keeps pointing to the file that is
//! replaced.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use clap::Args;
use obscura::{Error, Result};

/// Temporary files not yet renamed into place, removed if the program ends early. A
/// temporary file is created, renamed and removed with this lock held, so the signal
/// thread, which takes it and never gives it back, sees each one either pending (and
/// removes it) or gone.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Removes every temporary file not yet committed (before an early exit).
pub fn discard_pending() {
    for t in pending().drain(..) {
        let _ = fs::remove_file(t);
    }
}

/// Starts a thread that, on SIGINT (Ctrl-C), SIGTERM or SIGHUP, removes the temporary
/// files not yet renamed into place and ends the program with status 128 + the
/// signal's number (130, 143, 129), as shells report a program killed by it. Outputs
/// already renamed stay; the ones not yet renamed keep their previous contents.
///
/// The signal handler itself (signal-hook's) only writes to a pipe; the removal runs
/// on this ordinary thread, where locking and file calls are allowed. Where signals
/// cannot be caught (not Unix, or registration fails), they keep their default action.
pub fn remove_temporaries_on_signal() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let watcher = std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                if let Some(signal) = signals.forever().next() {
                    // Held until the process ends: no temporary file is created or
                    // renamed after these are removed.
                    let mut pending = pending();
                    for t in pending.drain(..) {
                        let _ = fs::remove_file(t);
                    }
                    std::process::exit(128 + signal);
                }
            });
        drop(watcher);
    }
}

/// How outputs may be named.
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct OutputArgs {
    /// Write outputs under any name. By default each output's extension must be its
    /// format's: -o .png (.svg for `lines`), --png .png, --ids and --depth .npy,
    /// --stats-json and --json .json (a name like mesh.obj is taken for a slip, not a
    /// wish to replace the mesh).
    #[arg(long)]
    pub force_extension: bool,
}

/// The extension each output option wants, and what it writes.
fn expected_extension(option: &str) -> Option<(&'static str, &'static str)> {
    match option {
        "-o" => Some(("png", "PNG images")),
        "--png" => Some(("png", "PNG images")),
        "--ids" | "--depth" => Some(("npy", "NumPy arrays")),
        "--stats-json" | "--json" => Some(("json", "JSON")),
        _ => None,
    }
}

/// What makes two paths one file: the device and inode of an existing file (links and
/// spellings alike), else the path made canonical ([`identity`]).
#[derive(Debug, PartialEq, Eq)]
enum FileId {
    Node(u64, u64),
    Path(PathBuf),
}

fn file_id(path: &Path) -> FileId {
    #[cfg(unix)]
    if let Ok(m) = fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        return FileId::Node(m.dev(), m.ino());
    }
    FileId::Path(identity(path))
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
    /// The scene as given (not `demo:`), named when an output is one of its files.
    input: Option<String>,
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
    /// other, against the input scene and against their kind (unless `naming` forces
    /// any extension), and creates their temporary files.
    pub fn stage(
        input: Option<&str>,
        outputs: &[(&'static str, Option<&Path>)],
        naming: OutputArgs,
    ) -> Result<Self> {
        Outputs::stage_with_extensions(input, outputs, naming, &[])
    }

    /// [`Outputs::stage`] where some options want another extension than the usual
    /// one: each `(option, extension, what it writes)` (`obscura lines` writes SVG
    /// with `-o`).
    pub fn stage_with_extensions(
        input: Option<&str>,
        outputs: &[(&'static str, Option<&Path>)],
        naming: OutputArgs,
        extensions: &[(&'static str, &'static str, &'static str)],
    ) -> Result<Self> {
        let given: Vec<(&'static str, &Path)> = outputs
            .iter()
            .filter_map(|&(o, p)| p.map(|p| (o, p)))
            .collect();
        let ids: Vec<FileId> = given.iter().map(|(_, p)| file_id(p)).collect();
        let input = input
            .filter(|s| !s.starts_with("demo:"))
            .map(|s| (s, file_id(Path::new(s))));
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
        // Each output is written in one format: a name promising another would hold
        // it under a misleading extension (`-o out.jpg`), and a name like `mesh.obj` or
        // `scene.mtl` is more likely a slip than a wish to replace that file. Devices
        // and pipes (`/dev/stdout`) have no extension to check.
        if !naming.force_extension {
            for &(option, path) in &given {
                let wanted = extensions
                    .iter()
                    .find(|(o, _, _)| *o == option)
                    .map(|&(_, e, w)| (e, w))
                    .or_else(|| expected_extension(option));
                let Some((want, what)) = wanted else {
                    continue;
                };
                if fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
                    continue;
                }
                let has = path.extension().map(|e| e.to_string_lossy().into_owned());
                if has.as_deref().is_some_and(|e| e.eq_ignore_ascii_case(want)) {
                    continue;
                }
                let why = match has {
                    Some(e) => format!("a .{e} name"),
                    None => "a name without an extension".to_string(),
                };
                return Err(Error::option(
                    option,
                    format!(
                        "{}: obscura writes {what} there, and this is {why}; name the file \
                         .{want}, or pass --force-extension to keep this name",
                        path.display()
                    ),
                ));
            }
        }
        let mut staged = Outputs {
            files: Vec::new(),
            input: input.map(|(s, _)| s.to_string()),
        };
        for &(option, path) in &given {
            staged.files.push(stage_one(option, path, identity(path))?);
        }
        Ok(staged)
    }

    /// Refuses an output that is one of `inputs`, the files loading the scene read
    /// ([`obscura::Scene::source_files`]): a mesh, a material library, a buffer. Run
    /// after loading and before rendering; an error removes the temporary files.
    pub fn check_inputs(&self, inputs: &[PathBuf]) -> Result<()> {
        if inputs.is_empty() {
            return Ok(());
        }
        let inputs: Vec<(&PathBuf, FileId)> = inputs.iter().map(|p| (p, file_id(p))).collect();
        for f in &self.files {
            let id = file_id(&f.given);
            if let Some((input, _)) = inputs.iter().find(|(_, i)| *i == id) {
                let scene = self.input.as_deref().unwrap_or("the scene");
                return Err(Error::option(
                    f.option,
                    format!(
                        "{} is {}, a file the scene {scene} is read from: refusing to \
                         overwrite an input",
                        f.given.display(),
                        input.display()
                    ),
                ));
            }
        }
        Ok(())
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
                let mut pending = pending();
                fs::rename(temp, &f.target).map_err(|e| Error::io(&f.given, e))?;
                pending.retain(|p| p != temp);
                f.temp = None;
            }
        }
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        let mut pending = pending();
        for t in self.files.iter().filter_map(|f| f.temp.as_ref()) {
            let _ = fs::remove_file(t);
            pending.retain(|p| p != t);
        }
    }
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
    let mut pending = pending();
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(|e| Error::io(path, e))?;
    pending.push(temp.clone());
    drop(pending);
    if let Some(m) = existing {
        let _ = fs::set_permissions(&temp, m.permissions());
    }
    staged.temp = Some(temp);
    Ok(staged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn forced() -> OutputArgs {
        OutputArgs {
            force_extension: true,
        }
    }

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
        let e = Outputs::stage(
            None,
            &[("-o", Some(&a)), ("--ids", Some(&b))],
            OutputArgs::default(),
        )
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
        let mut o = Outputs::stage(None, &[("--json", Some(&a))], forced()).unwrap();
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
        let mut o = Outputs::stage(None, &[("--json", Some(&a))], forced()).unwrap();
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
