//! The one error type of the library.
//!
//! Every error names what it is about: the file and line for text formats, the file
//! and the element (mesh, facet, vertex) for binary ones, the object for scene-level
//! problems. Nothing in the library panics on bad input.

use std::path::PathBuf;

/// Everything that can go wrong in obscura.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A text file has a malformed line (or a value on it is unusable).
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong with the line.
        message: String,
    },
    /// A binary or structured file is malformed; `element` names the part (mesh,
    /// facet, vertex, accessor) where that is known.
    #[error("{}: {element}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// The element of the file that is wrong, e.g. `facet 12` or `mesh "Cube"`.
        element: String,
        /// What is wrong with it.
        message: String,
    },
    /// A file refers to another file outside its own folder tree (an absolute path,
    /// a `file:` URI, a `..` or a symbolic link leading out): refused unless
    /// [`LoadOptions::allow_outside_references`](crate::scene::load::LoadOptions) is set.
    #[error(
        "{}: {element}: reference \"{reference}\" {reason}: a scene reads only files inside \
         the folder of the file that refers to them (set `allow_outside_references` in \
         `LoadOptions` to allow it)",
        path.display()
    )]
    OutsideReference {
        /// The file that holds the reference.
        path: PathBuf,
        /// Where in it: `line 3`, `buffer 0`.
        element: String,
        /// The reference as written in the file.
        reference: String,
        /// Why it leads outside, e.g. `is an absolute path`.
        reason: String,
    },
    /// The file extension is not one obscura can read.
    #[error("{}: unsupported file type (expected .obj, .gltf, .glb, .stl, .ply or .toml)", path.display())]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file's format is one obscura reads, but this build leaves its cargo feature
    /// out (`obj`, `gltf`, `stl`, `ply`, `toml-scene`; all on by default).
    #[error(
        "{}: reading {format} files needs obscura's cargo feature \"{feature}\", which this build leaves out",
        path.display()
    )]
    FormatDisabled {
        /// The file.
        path: PathBuf,
        /// The format, as a user names it (`OBJ`, `glTF`, ...).
        format: &'static str,
        /// The cargo feature that reads it.
        feature: &'static str,
    },
    /// An object of the scene is unusable (non-finite coordinates, bad transform...).
    #[error("object \"{object}\": {message}")]
    InvalidObject {
        /// The object's name.
        object: String,
        /// What is wrong with it.
        message: String,
    },
    /// A cells-and-portals model is wrong: a portal off its cells' boundary, an open
    /// or empty cell, overlapping cells, a leak; the message names the cells and
    /// portals and where the problem is.
    #[error("cells and portals: {message}")]
    InvalidCells {
        /// What is wrong, naming the cells and portals and the place.
        message: String,
    },
    /// The scene has nothing to render.
    #[error("the scene is empty: {0}")]
    EmptyScene(String),
    /// A `demo:NAME` that does not exist.
    #[error("unknown demo scene \"{name}\" (known: {known})")]
    UnknownDemo {
        /// The name asked for.
        name: String,
        /// The names that exist, comma separated.
        known: String,
    },
    /// The camera cannot produce an image (eye on the target, up parallel to the view
    /// direction, near >= far, a field of view outside (0, 180) degrees...).
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// The image size is zero, too large, or would not fit in memory.
    #[error("invalid image size {width}x{height}: {reason}")]
    InvalidViewport {
        /// Requested width in pixels.
        width: u64,
        /// Requested height in pixels.
        height: u64,
        /// Why it is refused.
        reason: String,
    },
    /// An option value that makes no sense (named, with the reason).
    #[error("invalid option {option}: {reason}")]
    InvalidOption {
        /// The option.
        option: String,
        /// Why it is refused.
        reason: String,
    },
    /// A structure whose size depends on the input would exceed the memory budget of
    /// the run (see [`crate::budget`]): estimated before it was allocated, or counted
    /// while it grew.
    #[error("{}", budget_message(at.as_deref(), structure, *count, *bytes, *limit, option))]
    Budget {
        /// The structure, e.g. `BSP fragments` or `octree nodes`.
        structure: String,
        /// How many of its items it reached or would reach.
        count: u64,
        /// The bytes it would take (an estimate or the count so far).
        bytes: u64,
        /// The budget in bytes.
        limit: u64,
        /// The option that raises the budget: `memory_limit` in the library, the flag
        /// in the CLI.
        option: String,
        /// Where the input asks for the structure (a file and line), when known.
        at: Option<String>,
    },
    /// A run would pass, or passed, its time limit (see [`crate::work`]): refused on
    /// an estimate before it started, or stopped while it ran.
    #[error("{}{}", at.as_ref().map(|a| format!("{a}: ")).unwrap_or_default(),
             crate::work::time_limit_message(work, *estimate_s, *limit_s, option))]
    TimeLimit {
        /// The work, e.g. `BSP construction` or `raycast: about 3.4e10 ray-triangle
        /// tests`.
        work: String,
        /// The estimate in seconds on the reference machine, when refused up front.
        estimate_s: Option<f64>,
        /// The time limit (or, for an estimate, the time that was left) in seconds.
        limit_s: f64,
        /// The option that raises the limit: `time_limit` in the library, the flag in
        /// the CLI.
        option: String,
        /// The input the work was for (a file, a scene), when known.
        at: Option<String>,
    },
    /// Another thread raised the run's stop flag (see [`crate::work`]).
    #[error("{work}: stopped on request")]
    Stopped {
        /// What was being done.
        work: String,
    },
}

/// The message of an [`Error::Budget`].
fn budget_message(
    at: Option<&str>,
    structure: &str,
    count: u64,
    bytes: u64,
    limit: u64,
    option: &str,
) -> String {
    let b = crate::budget::readable_bytes;
    let place = at.map(|a| format!("{a}: ")).unwrap_or_default();
    format!(
        "{place}{structure}: {count} would take {} (or more), over the memory budget of {}; \
         raise the budget with {option}, or reduce the input",
        b(bytes),
        b(limit)
    )
}

impl Error {
    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// Shorthand for an [`Error::Parse`].
    pub fn parse(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Parse {
            path: path.into(),
            line,
            message: message.into(),
        }
    }

    /// Shorthand for an [`Error::Format`].
    pub fn format(
        path: impl Into<PathBuf>,
        element: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::Format {
            path: path.into(),
            element: element.into(),
            message: message.into(),
        }
    }

    /// Shorthand for an [`Error::InvalidOption`].
    pub fn option(option: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidOption {
            option: option.into(),
            reason: reason.into(),
        }
    }
}

impl Error {
    /// A budget error naming another option (the CLI's flag instead of the library's
    /// field); other errors unchanged.
    #[must_use]
    pub fn with_budget_option(mut self, flag: &str) -> Self {
        if let Error::Budget { option, .. } = &mut self {
            *option = flag.to_string();
        }
        self
    }

    /// A time-limit error naming another option (the CLI's flag instead of the
    /// library's field); other errors unchanged.
    #[must_use]
    pub fn with_time_option(mut self, flag: &str) -> Self {
        if let Error::TimeLimit { option, .. } = &mut self {
            *option = flag.to_string();
        }
        self
    }

    /// A budget, time-limit or BSP fragment-cap error of a render placed in the input
    /// it rendered (a file or scene name) where it names none yet; other errors
    /// unchanged.
    #[must_use]
    pub fn in_input(mut self, input: &str) -> Self {
        match &mut self {
            Error::Budget { at, .. } | Error::TimeLimit { at, .. } if at.is_none() => {
                *at = Some(input.to_string());
            }
            Error::InvalidOption { option, reason } if option == "bsp fragments" => {
                *reason = format!("{input}: {reason}");
            }
            _ => {}
        }
        self
    }

    /// A budget error placed in the input (`file:line`); other errors unchanged.
    #[must_use]
    pub fn budget_at(mut self, place: String) -> Self {
        if let Error::Budget { at, .. } = &mut self {
            *at = Some(place);
        }
        self
    }
}

/// `Result` with obscura's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
