//! Options shared by the subcommands: the scene, the image size, the camera, threads.

use std::time::Instant;

use crate::out::errln;
use clap::Args;
use clap::builder::TypedValueParser;
use glam::DVec3;
use obscura::accel::bsp::{BspOptions, BspTraversal};
use obscura::cull::backface::BackfaceMode;
use obscura::cull::occlusion::{CullMethod, CullOptions};
use obscura::geom::BoundsKind;
use obscura::surface::{Algorithm, RenderOptions};
use obscura::{Camera, Error, PrepareOptions, Projection, Result, Scene, Viewport};

/// The scene and how to look at it.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// A mesh file (.obj .gltf .glb .stl .ply), a scene file (.toml) or demo:NAME
    /// (default, seed-task, cube, sphere, city, blocks, triangles, level, level-grid,
    /// cells5). Without it, demo:default.
    #[arg(value_name = "SCENE", value_parser = clap::builder::OsStringValueParser::new().try_map(parse_scene))]
    pub scene: Option<String>,
    /// Image size in pixels, WIDTHxHEIGHT (each side at most 16384).
    #[arg(long, value_name = "WxH", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: Option<(u64, u64)>,
    /// Eye position x,y,z (default: the scene's camera, or one framing its bounds).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point looked at, x,y,z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Up direction, x,y,z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees (perspective).
    #[arg(long, value_name = "DEG", value_parser = parse_number, allow_hyphen_values = true)]
    pub fov: Option<f64>,
    /// Near clipping distance (default: fitted to the scene).
    #[arg(long, value_name = "N", value_parser = parse_number, allow_hyphen_values = true)]
    pub near: Option<f64>,
    /// Far clipping distance (default: fitted to the scene).
    #[arg(long, value_name = "F", value_parser = parse_number, allow_hyphen_values = true)]
    pub far: Option<f64>,
    /// Orthographic projection showing this height of the world (not with --fov, which
    /// is for a perspective projection).
    #[arg(long, value_name = "HEIGHT", value_parser = parse_number, allow_hyphen_values = true,
          conflicts_with = "fov")]
    pub ortho: Option<f64>,
    /// Keep back faces (by default they are culled on closed objects).
    #[arg(long)]
    pub no_backface: bool,
    /// Worker threads, 1 to 1024 (default: all cores; 1 for single-thread figures).
    #[arg(long, value_name = "N", value_parser = parse_threads, allow_hyphen_values = true)]
    pub threads: Option<usize>,
    /// Let the scene read files outside its own folder: absolute paths, `..`, symbolic
    /// links leading out, file: URIs in its glTF buffers, OBJ mtllib lines and scene-file
    /// meshes. By default every file a scene refers to must be inside the folder of the
    /// file that refers to it.
    #[arg(long)]
    pub allow_outside_references: bool,
    /// Cells and portals from a Quake tools' portal file (PRT1, `.prt`) for the portal
    /// methods: each leaf's cell is the convex hull of its portals, and an object goes
    /// in a cell only when its box lies inside one hull (see docs/culling.md). Replaces
    /// the scene's own cells.
    #[arg(long, value_name = "FILE.prt")]
    pub prt: Option<std::path::PathBuf>,
    /// Memory budget of the run: 512M, 4G, 1.5GiB or bytes (default: half of the memory
    /// available). Every structure that grows with the input (frame buffers, bins, BSP
    /// fragments, octree nodes, a scene file's placed faces...) is checked against it
    /// and refused with its name rather than exhausting memory. Given, it also replaces
    /// the BSP's default cap of 2 million fragments (a few seconds of building).
    #[arg(long, value_name = "SIZE", value_parser = obscura::budget::parse_size,
          allow_hyphen_values = true)]
    pub memory_limit: Option<u64>,
    /// Time limit of the run: seconds (30, 2.5s, 2m, 1h) or "none" (default: 8 s).
    /// Work that would pass it by estimate (brute-force and bounding-volume ray
    /// casting, the painter's algorithms, the octree) is refused before it starts, and
    /// every loop whose length the input decides stops when it passes, naming the work;
    /// `compare` skips what does not fit in what is left.
    #[arg(long, value_name = "SECONDS", default_value = "8", value_parser = parse_time_limit,
          allow_hyphen_values = true)]
    pub time_limit: TimeLimit,
}

/// A run's time limit: `None` for no limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeLimit(pub Option<std::time::Duration>);

/// When the process started: the time limit counts from here.
static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();

/// Marks the start of the run (the first call wins).
pub fn mark_start() {
    START.get_or_init(Instant::now);
}

impl ViewArgs {
    /// The time left of `--time-limit` since the run started (`None`: no limit).
    pub fn remaining_time(&self) -> Option<std::time::Duration> {
        let limit = self.time_limit.0?;
        let spent = START.get_or_init(Instant::now).elapsed();
        Some(limit.saturating_sub(spent))
    }
}

/// Parses `--time-limit`: a positive number of seconds with an optional unit (s, m,
/// h), or `none`.
pub fn parse_time_limit(s: &str) -> std::result::Result<TimeLimit, String> {
    let t = s.trim();
    if t.eq_ignore_ascii_case("none") {
        return Ok(TimeLimit(None));
    }
    let (number, unit) = match t
        .char_indices()
        .rev()
        .find(|(_, c)| c.is_ascii_digit() || *c == '.')
    {
        Some((i, _)) => t.split_at(i + 1),
        None => (t, ""),
    };
    let scale = match unit.trim() {
        "" | "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        other => {
            return Err(format!(
                "unknown unit \"{other}\" (seconds: 30, 2.5s, 2m, 1h, or none)"
            ));
        }
    };
    let x = parse_number(number)?;
    let secs = x * scale;
    if !(secs.is_finite() && secs > 0.0 && secs <= 1e9) {
        return Err(format!(
            "{} s: the limit must be a positive number of seconds up to 1e9, or none",
            readable(secs)
        ));
    }
    Ok(TimeLimit(Some(std::time::Duration::from_secs_f64(secs))))
}

/// Options that tune particular algorithms.
#[derive(Args, Debug, Clone)]
pub struct AlgoArgs {
    /// Bounding volume for raycast-bounds: sphere, aabb, obb, kdop.
    #[arg(long, default_value = "aabb", value_parser = parse_bounds)]
    pub bounds: BoundsKind,
    /// Octree depth for the octree algorithm: voxels are 2^DEPTH on a side (0 to 10).
    /// Each level multiplies the octree's memory and build time by about 4: depth 8 on
    /// the 1M-triangle demo:sphere takes 12 MB, but depth 10 on a scene of many large
    /// overlapping triangles (demo:triangles) would take minutes and over 5 GB: a tree
    /// whose estimate passes the memory budget (--memory-limit) is refused up front.
    #[arg(long, value_name = "DEPTH", default_value_t = DEFAULT_OCTREE_DEPTH, value_parser = parse_octree_depth,
          allow_hyphen_values = true)]
    pub octree_depth: u32,
    /// BSP traversal: front-to-back (write each pixel once, stop when the image is
    /// full) or back-to-front (the painter's algorithm).
    #[arg(long, default_value = "front-to-back", value_parser = parse_bsp_traversal)]
    pub bsp_traversal: BspTraversal,
}

impl AlgoArgs {
    /// Warnings for tuning flags changed from their defaults that none of `algos`
    /// reads (e.g. `--octree-depth` without the octree): such a flag would otherwise be
    /// ignored without a word.
    pub fn unused_warnings(&self, algos: &[Algorithm]) -> Vec<String> {
        let runs = |a: Algorithm| algos.contains(&a);
        let mut out = Vec::new();
        let mut unused = |flag: &str, value: String, user: Algorithm| {
            if !runs(user) {
                out.push(format!(
                    "{flag} {value} has no effect: only the {} algorithm uses it, and it does \
                     not run here",
                    user.name()
                ));
            }
        };
        if self.octree_depth != DEFAULT_OCTREE_DEPTH {
            unused(
                "--octree-depth",
                self.octree_depth.to_string(),
                Algorithm::Octree,
            );
        }
        if self.bounds != BoundsKind::Aabb {
            unused(
                "--bounds",
                format!("{:?}", self.bounds).to_lowercase(),
                Algorithm::RaycastBounds,
            );
        }
        if self.bsp_traversal != BspTraversal::FrontToBack {
            unused(
                "--bsp-traversal",
                "back-to-front".to_owned(),
                Algorithm::Bsp,
            );
        }
        out
    }

    /// The library's options from these flags.
    pub fn options(&self) -> RenderOptions {
        RenderOptions::default()
            .with_bounds(self.bounds)
            .with_octree_depth(self.octree_depth)
            .with_bsp(BspOptions::default().with_traversal(self.bsp_traversal))
    }

    /// [`AlgoArgs::options`] with the memory budget of `--memory-limit`, which, given,
    /// bounds the BSP tree by its bytes instead of the default fragment count.
    pub fn options_with_budget(&self, memory_limit: Option<u64>) -> RenderOptions {
        let options = self.options().with_memory_limit(memory_limit);
        if memory_limit.is_some() {
            let bsp = options.bsp.with_max_fragments(usize::MAX);
            options.with_bsp(bsp)
        } else {
            options
        }
    }
}

/// An algorithm name, for `--algo` and each item of `--algos` (clap names the option;
/// the library's message would name `--algo` for both).
pub fn parse_algo(s: &str) -> std::result::Result<Algorithm, String> {
    s.trim().parse().map_err(|_| {
        format!(
            "unknown algorithm \"{}\" (known: {})",
            s.trim(),
            Algorithm::ALL.map(Algorithm::name).join(", ")
        )
    })
}

/// The occlusion-culling stage of a view (`--cull`), for `render`, `compare` and
/// `bench`.
#[derive(Args, Debug, Clone)]
pub struct CullArgs {
    /// Culling stage before the hidden-surface algorithm: none, frustum (objects and
    /// clusters outside the view), portals (cells and portals with a PVS),
    /// screen-portals (Luebke-Georges), occluders (Coorg-Teller shadow volumes) or
    /// buffer (an occlusion buffer). Every method is conservative: the picture is the
    /// same, only faster (see docs/culling.md).
    #[arg(long = "cull", value_name = "METHOD", default_value = "frustum",
          value_parser = parse_cull)]
    pub cull: CullMethod,
}

impl CullArgs {
    /// The library's options for this method.
    pub fn options(&self) -> CullOptions {
        CullOptions::with_method(self.cull)
    }
}

/// A culling method's name (`--cull`, `--method`).
pub fn parse_cull(s: &str) -> std::result::Result<CullMethod, String> {
    CullMethod::from_name(s.trim()).ok_or_else(|| {
        format!(
            "unknown culling method \"{}\" (known: {})",
            s.trim(),
            CullMethod::ALL.map(CullMethod::name).join(", ")
        )
    })
}

/// The scene argument as UTF-8 (the library takes `&str`), refused by name otherwise:
/// clap's own message named no argument.
fn parse_scene(s: std::ffi::OsString) -> std::result::Result<String, String> {
    s.into_string().map_err(|s| {
        format!(
            "\"{}\" is not valid UTF-8; obscura reads only file names in UTF-8: rename or \
             link the file",
            s.to_string_lossy()
        )
    })
}

/// The default of `--octree-depth`.
pub const DEFAULT_OCTREE_DEPTH: u32 = 7;

/// A finite number for a camera flag (`--fov`, `--near`, `--far`, `--ortho`): each flag
/// takes values that start with `-` so that this parser, not clap's `-- -5` hint,
/// answers; the camera's own check then says which range the flag needs.
pub fn parse_number(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("\"{s}\" is not a finite number")),
    }
}

/// The same check for every subcommand, at parsing: `compare` and `bench` only reported
/// a bad depth as one algorithm's error and ended with status 0.
pub fn parse_octree_depth(s: &str) -> std::result::Result<u32, String> {
    let max = obscura::accel::octree::MAX_DEPTH;
    match s.trim().parse::<u32>() {
        Ok(d) if d <= max => Ok(d),
        _ => Err(format!(
            "\"{s}\": give a whole number from 0 to {max} ({} voxels on a side)",
            1u32 << max
        )),
    }
}

pub fn parse_bounds(s: &str) -> std::result::Result<BoundsKind, String> {
    s.parse().map_err(|e| cli_error(e).to_string())
}

pub fn parse_bsp_traversal(s: &str) -> std::result::Result<BspTraversal, String> {
    s.parse().map_err(|e| cli_error(e).to_string())
}

/// The most worker threads `--threads` accepts: far more than any machine's cores (a
/// pool of 100,000 threads takes minutes just to start).
pub const MAX_THREADS: usize = 1024;

/// `--threads`: 1 to [`MAX_THREADS`]. Zero is refused rather than read as "all cores"
/// (which leaving the flag out means), so no message can print "0 threads".
pub fn parse_threads(s: &str) -> std::result::Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a whole number of threads from 1 to {MAX_THREADS}"))?;
    if n == 0 {
        return Err(format!(
            "0 threads: give 1 to {MAX_THREADS}, or leave --threads out to use every core"
        ));
    }
    if n > MAX_THREADS {
        return Err(format!(
            "{n} threads: at most {MAX_THREADS} (this machine has {} cores)",
            std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
        ));
    }
    Ok(n)
}

/// The default image size.
pub const DEFAULT_SIZE: (u64, u64) = (1280, 720);

/// `--size`: WIDTHxHEIGHT, both positive whole numbers. The flag takes values that
/// start with `-`, so a negative size gets this message, not clap's `-- -5` hint.
fn parse_size(s: &str) -> std::result::Result<(u64, u64), String> {
    let rule =
        "the size must be WIDTHxHEIGHT with positive whole numbers of pixels, e.g. 1920x1080";
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("\"{s}\": {rule}"))?;
    let n = |v: &str| match v.trim().parse::<u64>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!("\"{s}\": {rule} (\"{v}\" is not one)")),
    };
    Ok((n(w)?, n(h)?))
}

fn parse_vec3(s: &str) -> std::result::Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("\"{s}\" is not x,y,z"));
    }
    let mut v = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p
            .trim()
            .parse::<f64>()
            .map_err(|_| format!("\"{p}\" is not a number"))?;
        if !v[k].is_finite() {
            return Err(format!("\"{p}\" is not a finite number"));
        }
    }
    Ok(DVec3::from_array(v))
}

/// A loaded scene and how long loading took.
pub struct Loaded {
    /// The spec it was loaded from.
    pub spec: String,
    /// The scene.
    pub scene: Scene,
    /// Reading and building the scene, in milliseconds.
    pub load_ms: f64,
}

impl ViewArgs {
    /// Loads the scene, printing load warnings to stderr.
    pub fn load(&self) -> Result<Loaded> {
        let spec = self
            .scene
            .clone()
            .unwrap_or_else(|| "demo:default".to_string());
        let start = Instant::now();
        // `demo:NAME` is the CLI's spelling of a built-in scene; anything else is a path.
        let scene = match spec.strip_prefix("demo:") {
            Some(name) => Scene::demo(name)?,
            None => Scene::load_with(&spec, &self.load_options())?,
        };
        let load_ms = start.elapsed().as_secs_f64() * 1e3;
        scene.ensure_not_empty(&spec)?;
        for w in scene.report().warnings() {
            errln!("warning: {spec}: {w}");
        }
        let mut scene = scene;
        if let Some(prt) = &self.prt {
            let summary = obscura::cull::portals::prt::attach(&mut scene, prt)?;
            errln!("note: {}: {summary}", prt.display());
        }
        Ok(Loaded {
            spec,
            scene,
            load_ms,
        })
    }

    /// The checked viewport: `--size`, else the scene's own size, else 1280x720.
    pub fn viewport(&self, scene: &Scene) -> Result<Viewport> {
        self.viewport_or(scene, DEFAULT_SIZE)
    }

    /// The checked viewport with another default size.
    pub fn viewport_or(&self, scene: &Scene, default: (u64, u64)) -> Result<Viewport> {
        let (w, h) = self
            .size
            .unwrap_or_else(|| default_size(scene).unwrap_or(default));
        Viewport::new(w, h)
    }

    /// The camera: the scene's (or one framing it), with the given overrides. When the
    /// eye or target is overridden and near/far are not given, they are fitted to the
    /// scene's bounds along the new view direction.
    pub fn camera(&self, scene: &Scene, viewport: Viewport) -> Result<Camera> {
        let moved = self.eye.is_some() || self.target.is_some() || self.up.is_some();
        let base = if moved || self.ortho.is_some() || self.fov.is_some() {
            scene.default_camera(viewport.aspect())
        } else {
            // No camera option given: a scene no camera in range can frame is said to
            // be so, with the scene named, not left to "invalid camera".
            scene
                .automatic_camera(viewport.aspect())
                .map_err(|e| match e {
                    Error::InvalidCamera(m) => Error::InvalidCamera(format!(
                        "{}: {m} (--eye, --target, --near, --far)",
                        self.scene.as_deref().unwrap_or("demo:default")
                    )),
                    e => e,
                })?
        };
        let mut cam = Camera {
            eye: self.eye.unwrap_or(base.eye),
            target: self.target.unwrap_or(base.target),
            up: self.up.unwrap_or(if moved && scene.camera().is_none() {
                scene.up()
            } else {
                base.up
            }),
            ..base
        };
        // An orthographic scene camera's near may be negative (the eye inside the
        // scene), which a perspective view refuses: --fov refits it.
        let to_perspective = self.fov.is_some()
            && matches!(cam.projection, Projection::Orthographic { .. })
            && self.ortho.is_none();
        if let Some(fov) = self.fov {
            cam.projection = Projection::Perspective { fov_y_degrees: fov };
        }
        if let Some(h) = self.ortho {
            cam.projection = Projection::Orthographic { height: h };
        }
        let refit = moved || self.ortho.is_some() || to_perspective;
        if refit {
            cam.fit_depth_range(&scene.bounds());
        }
        if let Some(n) = self.near {
            cam.near = n;
        }
        if let Some(f) = self.far {
            cam.far = f;
        }
        // One of near and far given: say where the other came from.
        let source = if scene.camera().is_some() && !refit {
            "the scene camera's"
        } else {
            "fitted to the scene"
        };
        match (self.near, self.far) {
            (Some(n), None) if n.is_finite() && n >= cam.far => {
                return Err(Error::option(
                    "--near",
                    format!(
                        "near {} is not before the far distance {} ({source}): give --far too",
                        readable(n),
                        readable(cam.far)
                    ),
                ));
            }
            (None, Some(f)) if f.is_finite() && f <= cam.near => {
                return Err(Error::option(
                    "--far",
                    format!(
                        "far {} is not beyond the near distance {} ({source}): give --near too",
                        readable(f),
                        readable(cam.near)
                    ),
                ));
            }
            _ => {}
        }
        cam.validate()?;
        Ok(cam)
    }

    /// Load options from the flags (the memory budget).
    pub fn load_options(&self) -> obscura::scene::load::LoadOptions {
        let mut options = obscura::scene::load::LoadOptions::default()
            .with_allow_outside_references(self.allow_outside_references);
        options.memory_limit = self.memory_limit;
        options
    }

    /// Pipeline options from the flags.
    pub fn prepare_options(&self) -> PrepareOptions {
        let mode = if self.no_backface {
            BackfaceMode::Off
        } else {
            BackfaceMode::Closed
        };
        PrepareOptions::default()
            .with_backface(mode)
            .with_memory_limit(self.memory_limit)
    }

    /// Runs `f` with rayon's current pool of the requested size.
    ///
    /// The first call makes rayon's global pool that size and runs `f` on the calling
    /// thread, which loaded the scene: its caches hold the scene, and a single-thread
    /// run (`--threads 1`) never leaves it. A later call asking for another size gets a
    /// pool of its own.
    pub fn with_threads<T: Send>(&self, f: impl FnOnce() -> T + Send) -> Result<T> {
        let n = self.threads.unwrap_or(0);
        let global = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global();
        if global.is_ok() || (n != 0 && rayon::current_num_threads() == n) {
            return Ok(f());
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::option("--threads", e.to_string()))?;
        Ok(pool.install(f))
    }
}

/// The message of an error for the command line: the library's, except where it names
/// a library option the command line spells as a flag.
pub fn message(e: &Error) -> String {
    match e {
        Error::OutsideReference {
            path,
            element,
            reference,
            reason,
        } => format!(
            "{}: {element}: reference \"{reference}\" {reason}: a scene reads only files \
             inside the folder of the file that refers to them (pass \
             --allow-outside-references to allow it)",
            path.display()
        ),
        e => e.to_string(),
    }
}

/// The CLI's flag for the memory budget, named by budget errors instead of the
/// library's `memory_limit`.
pub const MEMORY_LIMIT_FLAG: &str = "--memory-limit";

/// The CLI's flags for the library parameters that errors name (the library names its
/// own parameters, e.g. `RenderOptions::octree_depth`; the CLI's messages name the flag).
pub const PARAMETER_FLAGS: [(&str, &str); 4] = [
    ("RenderOptions::octree_depth", "--octree-depth"),
    ("RenderOptions::bounds", "--bounds"),
    ("BspOptions::traversal", "--bsp-traversal"),
    ("algorithm", "--algo"),
];

/// An error as the CLI shows it: a budget error names `--memory-limit` instead of the
/// library's `memory_limit`, an invalid library parameter is named by its flag (see
/// [`PARAMETER_FLAGS`]), and the BSP's fragment cap says how the flag lifts it.
pub fn cli_error(e: Error) -> Error {
    let e = match e {
        Error::InvalidOption { option, reason } => {
            let option = PARAMETER_FLAGS
                .iter()
                .find(|(parameter, _)| *parameter == option)
                .map_or(option, |(_, flag)| (*flag).to_string());
            Error::InvalidOption { option, reason }
        }
        other => other,
    };
    match e {
        Error::InvalidOption { option, reason } if option == "bsp fragments" => {
            Error::InvalidOption {
                option,
                reason: format!(
                    "{reason} (in the CLI: give --memory-limit to bound the tree by its bytes \
                 instead of this count)"
                ),
            }
        }
        other => other
            .with_budget_option(MEMORY_LIMIT_FLAG)
            .with_time_option(TIME_LIMIT_FLAG),
    }
}

/// The flag that raises a time limit, named in place of the library's `time_limit`.
pub const TIME_LIMIT_FLAG: &str = "--time-limit";

/// Whether an error is a structure over the memory budget, or the BSP's fragment cap
/// (`compare` and `bench` skip that algorithm and go on).
pub fn is_over_budget(e: &Error) -> bool {
    match e {
        Error::Budget { .. } | Error::TimeLimit { .. } => true,
        Error::InvalidOption { option, .. } => option == "bsp fragments",
        _ => false,
    }
}

/// A number in a message: six significant digits at most, plain at ordinary
/// magnitudes and in exponent form beyond (`1e-300`, not 300 digits). Every message
/// that echoes a float goes through this.
pub fn readable(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    // Rounded to six significant digits, then printed in its shortest form.
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    if rounded != 0.0 && !(1e-4..1e6).contains(&rounded.abs()) {
        format!("{rounded:e}")
    } else {
        format!("{rounded}")
    }
}

/// Scenes that carry a camera made for a size (the seed's 32x32 task) get that size.
fn default_size(scene: &Scene) -> Option<(u64, u64)> {
    match scene.camera() {
        Some(c) if *c == obscura::scene::demo::seed_task_camera() => Some((32, 32)),
        _ => None,
    }
}

/// A progress bar on standard error for one algorithm's run, and the library's progress
/// callback that feeds it (in thousandths). Clear it with `finish_and_clear` when done.
pub fn progress_bar(name: &str) -> (indicatif::ProgressBar, obscura::surface::Progress) {
    let pb = indicatif::ProgressBar::new(1000);
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {msg:<18} [{bar:30}] {percent:>3}% {elapsed}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    pb.set_message(name.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    let bar = pb.clone();
    let feed: obscura::surface::Progress =
        std::sync::Arc::new(move |f| bar.set_position((f * 1000.0) as u64));
    (pb, feed)
}

/// A note for a uniform grid that put many of the scene's triangles in one cell (a
/// small dense object in a large scene, the uniform grid's known weakness), from the
/// stats of `raycast-grid`; `None` for other stats and balanced grids.
pub fn grid_note(stats: &obscura::Stats) -> Option<String> {
    let grid = stats.raycast_grid()?;
    let largest = grid.largest_cell as f64;
    let average = grid.refs_per_cell;
    (largest >= 4096.0 && largest >= 1000.0 * average.max(1.0)).then(|| {
        format!(
            "one cell of the uniform grid holds {largest} triangles ({average:.1} on \
             average): a small dense object in a large scene, which uniform cells handle \
             badly; --algo raycast-bvh adapts to such scenes"
        )
    })
}
