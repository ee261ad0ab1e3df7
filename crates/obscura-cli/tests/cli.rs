//! The `obscura` binary's contract: what it writes and how it refuses bad input.

use std::path::PathBuf;
use std::process::{Command, Output};

fn obscura(args: &[&str], dir: &PathBuf) -> Output {
    Command::new(env!("CARGO_BIN_EXE_obscura"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the binary runs")
}

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("obscura-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Reads a v1 NumPy file: (descr, shape, body).
fn read_npy(path: &PathBuf) -> (String, (usize, usize), Vec<u8>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([b[8], b[9]]) as usize;
    let header = std::str::from_utf8(&b[10..10 + hlen]).unwrap().to_string();
    let descr = header
        .split("'descr': '")
        .nth(1)
        .unwrap()
        .split('\'')
        .next()
        .unwrap()
        .to_string();
    let shape = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let dims: Vec<usize> = shape
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    (descr, (dims[0], dims[1]), b[10 + hlen..].to_vec())
}

#[test]
fn render_default_demo_writes_png_npy_and_json() {
    let dir = tempdir("render");
    let o = obscura(
        &[
            "render",
            "--size",
            "64x48",
            "--ids",
            "ids.npy",
            "--depth",
            "depth.npy",
            "--stats",
            "--stats-json",
            "s.json",
            "--threads",
            "1",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(out.contains("wrote obscura.png"), "{out}");
    assert!(out.contains("faces: back-face culling"), "{out}");
    let png = std::fs::read(dir.join("obscura.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let (descr, shape, body) = read_npy(&dir.join("ids.npy"));
    assert_eq!((descr.as_str(), shape), ("<i4", (48, 64)));
    let ids: Vec<i32> = body
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert!(ids.contains(&-1) && ids.iter().any(|&i| i >= 0));
    let (descr, shape, body) = read_npy(&dir.join("depth.npy"));
    assert_eq!((descr.as_str(), shape), ("<f4", (48, 64)));
    let depth: Vec<f32> = body
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    // background exactly where ids are -1
    for (d, i) in depth.iter().zip(&ids) {
        assert_eq!(d.is_infinite(), *i == -1);
    }
    let json = std::fs::read_to_string(dir.join("s.json")).unwrap();
    for key in [
        "\"load_ms\"",
        "\"render_ms\"",
        "\"stages\"",
        "\"threads\": 1",
        "\"algorithm\": \"zbuffer\"",
    ] {
        assert!(json.contains(key), "{key} missing in {json}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn seed_task_renders_at_its_own_size() {
    let dir = tempdir("seed");
    let o = obscura(&["render", "demo:seed-task", "--ids", "ids.npy"], &dir);
    assert!(o.status.success(), "{}", text(&o));
    let (_, shape, _) = read_npy(&dir.join("ids.npy"));
    assert_eq!(shape, (32, 32));
    std::fs::remove_dir_all(&dir).ok();
}

/// A dense sphere on a wide ground: the uniform grid puts the sphere in a few cells and
/// the CLI says so (with what to use instead); the BVH renders it without a note, and
/// a scene of evenly spread boxes gets no note from the grid either.
#[test]
fn a_grid_with_one_crowded_cell_gets_a_note() {
    let dir = tempdir("grid-note");
    std::fs::write(
        dir.join("stadium.toml"),
        "[camera]\neye = [0, 1, 4]\ntarget = [0, 0, 0]\nnear = 0.1\nfar = 100\n\
         [[object]]\nname = \"ground\"\nprimitive = \"grid\"\nwidth = 1000\n\
         depth = 1000\ntranslate = [0, -1.5, 0]\n\
         [[object]]\nprimitive = \"sphere\"\nsegments = 160\nrings = 80\n",
    )
    .unwrap();
    let note = "note: one cell of the uniform grid holds";
    let run = |scene: &str, algo: &str| {
        let o = obscura(
            &[
                "render", scene, "--algo", algo, "--size", "40x30", "-o", "x.png",
            ],
            &dir,
        );
        assert!(o.status.success(), "{}", text(&o));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let grid = run("stadium.toml", "raycast-grid");
    assert!(grid.contains(note), "{grid}");
    assert!(grid.contains("--algo raycast-bvh"), "{grid}");
    assert!(!run("stadium.toml", "raycast-bvh").contains(note));
    assert!(!run("demo:city", "raycast-grid").contains(note));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn absurd_sizes_and_bad_input_get_clear_errors() {
    let dir = tempdir("errors");
    let cases: [(&[&str], &str); 7] = [
        (&["render", "--size", "20000x10"], "at most 16384"),
        (&["render", "--size", "0x10"], "positive whole numbers"),
        (&["render", "--size", "banana"], "WIDTHxHEIGHT"),
        (&["render", "demo:nope"], "unknown demo scene \"nope\""),
        (&["render", "missing.obj"], "missing.obj"),
        (
            &["render", "--eye", "0,0,0", "--target", "0,0,0"],
            "the eye is on the target",
        ),
        (
            &["render", "--algo", "magic"],
            "unknown algorithm \"magic\"",
        ),
    ];
    for (args, expected) in cases {
        let o = obscura(args, &dir);
        assert!(!o.status.success(), "{args:?} should fail");
        let t = text(&o);
        assert!(
            t.contains(expected),
            "{args:?}: expected {expected:?} in {t}"
        );
        assert!(!t.contains("panicked"), "{args:?} panicked: {t}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn help_shows_examples() {
    let dir = tempdir("help");
    for sub in ["render", "compare", "bench"] {
        let o = obscura(&[sub, "--help"], &dir);
        assert!(o.status.success());
        assert!(
            text(&o).contains("Examples:"),
            "{sub} --help has no examples"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn compare_writes_a_grid_and_a_table() {
    // The z-buffer, an exact algorithm and a coarse octree (4 voxels a side, which
    // must differ): each count of differing pixels is checked against the ids that
    // `render` writes for the same algorithm, compared here pixel by pixel.
    let dir = tempdir("compare");
    let common = [
        "demo:cube",
        "--size",
        "40x30",
        "--octree-depth",
        "2",
        "--threads",
        "1",
    ];
    let mut args = vec!["compare"];
    args.extend(common);
    args.extend(["--algos", "zbuffer,bsp,octree", "--json", "c.json"]);
    let o = obscura(&args, &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(dir.join("compare.png").exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("c.json")).unwrap()).unwrap();
    let rows = json["algorithms"].as_array().expect("an algorithms array");
    let ids_of = |algo: &str| {
        let file = format!("{algo}.npy");
        let mut args = vec!["render"];
        args.extend(common);
        args.extend(["--algo", algo, "--ids", &file, "-o", "r.png"]);
        let o = obscura(&args, &dir);
        assert!(o.status.success(), "{}", text(&o));
        read_npy(&dir.join(&file)).2
    };
    let reference = ids_of("zbuffer");
    let mut names = Vec::new();
    for row in rows {
        let algo = row["algorithm"].as_str().unwrap();
        names.push(algo.to_owned());
        let ids = ids_of(algo);
        let expected = ids
            .chunks(4)
            .zip(reference.chunks(4))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(row["differing_pixels"], expected, "{algo}: {json}");
        let table = String::from_utf8_lossy(&o.stdout);
        assert!(
            table
                .lines()
                .any(|l| l.split_whitespace().next() == Some(algo)
                    && l.split_whitespace().nth(2) == Some(&expected.to_string())),
            "{algo} with {expected} differing pixels in the table: {table}"
        );
        if algo == "octree" {
            assert!(
                expected > 0,
                "a 4-voxel octree matches the z-buffer exactly?"
            );
        }
    }
    assert_eq!(names, ["zbuffer", "bsp", "octree"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs the binary with its standard output a pipe whose reading end is already
/// closed, as in `obscura ... | head -0`.
fn obscura_into_closed_pipe(args: &[&str], dir: &PathBuf) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_obscura"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    drop(child.stdout.take());
    child.wait_with_output().expect("the binary ends")
}

#[test]
fn a_closed_standard_output_ends_the_program_quietly() {
    let dir = tempdir("pipe");
    let cases: [&[&str]; 3] = [
        &["render", "demo:cube", "--size", "8x8", "-o", "r.png"],
        &[
            "compare",
            "demo:cube",
            "--size",
            "8x8",
            "--algos",
            "zbuffer,bsp",
        ],
        &["bench", "--max-faces", "300", "--algos", "zbuffer"],
    ];
    for args in cases {
        let o = obscura_into_closed_pipe(args, &dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
    }
    // The work before the report was done.
    assert!(dir.join("r.png").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// The names of the files in `dir`, sorted.
fn listing(dir: &PathBuf) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn outputs_that_collide_or_cannot_be_written_are_refused_before_any_file_is_touched() {
    let dir = tempdir("outputs");
    let mesh = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(dir.join("victim.obj"), mesh).unwrap();
    let cases: [(&[&str], &[&str]); 8] = [
        (
            &["render", "demo:cube", "-o", "same.png", "--ids", "same.png"],
            &["--ids", "same file as -o"],
        ),
        (
            &["render", "demo:cube", "-o", "picture.jpg"],
            &["-o", "picture.jpg", "writes PNG images"],
        ),
        (
            &["compare", "demo:cube", "-o", "grid.webp"],
            &["-o", "grid.webp", "writes PNG images"],
        ),
        (
            &[
                "render",
                "demo:cube",
                "--ids",
                "x.npy",
                "--depth",
                "./x.npy",
            ],
            &["--depth", "same file as --ids"],
        ),
        (
            &["render", "victim.obj", "-o", "victim.obj"],
            &["-o", "input scene"],
        ),
        (
            &["render", "victim.obj", "--ids", "./victim.obj"],
            &["--ids", "input scene"],
        ),
        (
            &["compare", "demo:cube", "-o", "c.png", "--json", "c.png"],
            &["--json", "same file as -o"],
        ),
        (
            &[
                "render",
                "demo:cube",
                "-o",
                "x3.png",
                "--ids",
                "x3_ids.npy",
                "--stats-json",
                "missing-dir/s.json",
            ],
            &["missing-dir/s.json"],
        ),
    ];
    for (args, expected) in cases {
        let o = obscura(args, &dir);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {t}");
        for e in expected {
            assert!(t.contains(e), "{args:?}: expected {e:?} in {t}");
        }
        // Nothing written, nothing left behind, the input intact.
        assert_eq!(listing(&dir), ["victim.obj"], "{args:?}");
        assert_eq!(
            std::fs::read_to_string(dir.join("victim.obj")).unwrap(),
            mesh
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn outputs_replace_existing_files_and_leave_no_temporary_files() {
    let dir = tempdir("replace");
    std::fs::write(dir.join("r.png"), "old").unwrap();
    let o = obscura(
        &[
            "render",
            "demo:cube",
            "--size",
            "8x8",
            "-o",
            "r.png",
            "--stats-json",
            "s.json",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(listing(&dir), ["r.png", "s.json"]);
    assert_eq!(&std::fs::read(dir.join("r.png")).unwrap()[1..4], b"PNG");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs the binary, killing it (and failing) if it takes more than `seconds`.
fn obscura_within(args: &[&str], dir: &PathBuf, seconds: u64) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_obscura"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed().as_secs() >= seconds {
            child.kill().ok();
            child.wait().ok();
            panic!("{args:?} still running after {seconds} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Runs each case within 20 s and checks it fails with status 2 (a usage error) or 1,
/// with each expected text and no panic.
fn refused(dir: &PathBuf, cases: &[(&[&str], &[&str])]) {
    for (args, expected) in cases {
        let o = obscura_within(args, dir, 20);
        let t = text(&o);
        assert!(
            matches!(o.status.code(), Some(1 | 2)),
            "{args:?} should be refused: {:?} {t}",
            o.status
        );
        assert!(!t.contains("panicked"), "{args:?}: {t}");
        for e in *expected {
            assert!(t.contains(e), "{args:?}: expected {e:?} in {t}");
        }
    }
}

#[test]
fn thread_counts_beyond_the_limit_are_refused() {
    let dir = tempdir("threads");
    refused(
        &dir,
        &[
            (
                &[
                    "render",
                    "demo:cube",
                    "--size",
                    "8x8",
                    "--threads",
                    "100000",
                ],
                &["--threads", "at most 1024"],
            ),
            (
                &["compare", "demo:cube", "--threads", "18446744073709551615"],
                &["--threads", "at most 1024"],
            ),
            (
                &["render", "demo:cube", "--threads", "-1"],
                &["--threads", "\"-1\" is not a whole number"],
            ),
        ],
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bench_refuses_meaningless_budgets_and_face_counts() {
    let dir = tempdir("bench-args");
    let zb = ["bench", "--algos", "zbuffer", "--max-faces"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v = zb.to_vec();
        v.extend_from_slice(extra);
        v
    };
    let cases = [
        (with(&["1000", "--budget=-5"]), "positive number of seconds"),
        (
            with(&["1000", "--budget", "-5"]),
            "positive number of seconds",
        ),
        (
            with(&["1000", "--budget", "NaN"]),
            "positive number of seconds",
        ),
        (
            with(&["1000", "--budget", "0"]),
            "positive number of seconds",
        ),
        (with(&["0"]), "give 1 to 10000000"),
        (with(&["-3"]), "not a whole number of faces"),
        (
            with(&["1000000000", "--budget", "0.001"]),
            "give 1 to 10000000",
        ),
    ];
    for (args, expected) in &cases {
        refused(&dir, &[(args.as_slice(), &[expected])]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bench_runs_each_algorithm_once() {
    let dir = tempdir("bench-dup");
    let o = obscura_within(
        &["bench", "--max-faces", "200", "--algos", "zbuffer,zbuffer"],
        &dir,
        60,
    );
    assert!(o.status.success(), "{}", text(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        table.lines().filter(|l| l.starts_with("zbuffer")).count(),
        1,
        "{table}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `MemAvailable` in bytes, where the system says.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

#[test]
fn compare_refuses_up_front_a_size_whose_frames_cannot_fit() {
    // Every algorithm at the largest size holds 23 frames of 2.75 GiB: more than any
    // machine this runs on, unless it has over 64 GiB free.
    if available_memory().is_none_or(|m| m > 64 << 30) {
        eprintln!("skipped: available memory unknown or above 64 GiB");
        return;
    }
    let dir = tempdir("compare-memory");
    refused(
        &dir,
        &[(
            &["compare", "demo:cube", "--size", "16384x16384"],
            &["--size", "16384x16384", "23 frames need", "fewer --algos"],
        )],
    );
    assert_eq!(listing(&dir), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn compare_runs_each_algorithm_once() {
    let dir = tempdir("compare-dup");
    let o = obscura(
        &[
            "compare",
            "demo:cube",
            "--size",
            "16x16",
            "--algos",
            "bsp,bsp,zbuffer",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        table.lines().filter(|l| l.starts_with("bsp ")).count(),
        1,
        "{table}"
    );
    assert_eq!(
        table.lines().filter(|l| l.starts_with("zbuffer ")).count(),
        1,
        "{table}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn octree_depth_is_checked_by_every_subcommand() {
    let dir = tempdir("octree-depth");
    let expected: &[&str] = &["--octree-depth", "from 0 to 10"];
    refused(
        &dir,
        &[
            (&["render", "demo:cube", "--octree-depth", "11"], expected),
            (&["compare", "demo:cube", "--octree-depth", "11"], expected),
            (
                &["bench", "--algos", "octree,zbuffer", "--octree-depth", "11"],
                expected,
            ),
            (&["compare", "demo:cube", "--octree-depth", "-1"], expected),
        ],
    );
    assert_eq!(listing(&dir), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn negative_values_reach_the_checks_that_name_them() {
    let dir = tempdir("negative");
    refused(
        &dir,
        &[
            (
                &["render", "demo:cube", "--fov", "-10"],
                &["-10", "(0, 180)"],
            ),
            (&["render", "demo:cube", "--ortho", "-1"], &["-1"]),
        ],
    );
    // A negative near is valid for an orthographic view.
    let o = obscura(
        &[
            "render",
            "demo:cube",
            "--size",
            "8x8",
            "--ortho",
            "4",
            "--near",
            "-1",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn camera_and_argument_errors_name_what_the_user_gave() {
    let dir = tempdir("names");
    std::fs::write(
        dir.join("ortho.toml"),
        "[camera]\neye = [0, 0, 0.5]\ntarget = [0, 0, 0]\northo_height = 4\n\n\
         [[object]]\nprimitive = \"box\"\nsize = [2, 2, 2]\n",
    )
    .unwrap();
    // --fov turns the scene's orthographic camera (near < 0, its eye inside the box)
    // into a perspective one: near and far are refitted.
    let o = obscura(
        &["render", "ortho.toml", "--fov", "45", "--size", "8x8"],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    refused(
        &dir,
        &[
            (
                &["render", "demo:cube", "--far", "1"],
                &["--far", "fitted to the scene", "give --near too"],
            ),
            (
                &["render", "demo:cube", "--near", "1e6"],
                &["--near", "give --far too"],
            ),
            (
                &["compare", "demo:cube", "--algos", "zbuffer, bsp,foo"],
                &["--algos", "unknown algorithm \"foo\""],
            ),
        ],
    );
    let o = obscura(
        &[
            "compare",
            "demo:cube",
            "--size",
            "8x8",
            "--algos",
            "zbuffer, bsp",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let bad = std::ffi::OsStr::from_bytes(b"bad\xffname.obj");
        let o = Command::new(env!("CARGO_BIN_EXE_obscura"))
            .arg("render")
            .arg(bad)
            .current_dir(&dir)
            .output()
            .unwrap();
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{t}");
        assert!(t.contains("SCENE") && t.contains("not valid UTF-8"), "{t}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn every_numeric_flag_answers_bad_values_itself_never_with_clap_hints() {
    // Negative, zero and garbage values of each numeric flag, in each subcommand that
    // has it: our parser's message (naming the flag), never clap's "-- -5" hint.
    let dir = tempdir("numeric-flags");
    let flags: [(&str, &[&str], &str); 10] = [
        (
            "--size",
            &["-5x5", "5x-5", "0x5", "-1", "ax3", "-"],
            "positive whole numbers",
        ),
        ("--threads", &["-1", "0", "-0", "x", "-1e3"], "threads"),
        ("--fov", &["-inf", "nan", "-x", "--"], "finite number"),
        ("--near", &["-inf", "-x"], "finite number"),
        ("--far", &["-nan", "-.x"], "finite number"),
        ("--ortho", &["-inf", "-"], "finite number"),
        (
            "--octree-depth",
            &["-3", "-0.5", "11"],
            "whole number from 0 to",
        ),
        ("--eye", &["-1,2", "-x,0,0"], "\""),
        ("--max-faces", &["-5", "0"], "faces"),
        ("--budget", &["-1", "-1e-3", "0", "-inf"], "seconds"),
    ];
    for (flag, values, says) in flags {
        let subs: &[&str] = if matches!(flag, "--max-faces" | "--budget") {
            &["bench"]
        } else {
            &["render", "compare", "bench"]
        };
        for sub in subs {
            for value in values {
                let args = [sub, "demo:cube", flag, value];
                let o = obscura_within(&args, &dir, 20);
                let t = text(&o);
                assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
                assert!(!t.contains("tip:") && !t.contains("-- "), "{args:?}: {t}");
                assert!(t.contains(flag) && t.contains(says), "{args:?}: {t}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn conflicting_or_ignored_flags_are_refused_or_warned() {
    let dir = tempdir("conflicts");
    // --ortho and --fov choose two projections: refused, in either order.
    for args in [
        ["render", "demo:cube", "--ortho", "3", "--fov", "60"],
        ["render", "demo:cube", "--fov", "60", "--ortho", "3"],
    ] {
        let o = obscura(&args, &dir);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
        assert!(t.contains("--ortho") && t.contains("--fov"), "{t}");
    }
    // Tuning flags of an algorithm that does not run: a warning that names the flag.
    let cases: [(&[&str], &str); 4] = [
        (
            &["render", "--algo", "zbuffer", "--octree-depth", "3"],
            "--octree-depth 3",
        ),
        (
            &["render", "--algo", "bsp", "--bounds", "obb"],
            "--bounds obb",
        ),
        (
            &[
                "render",
                "--algo",
                "octree",
                "--bsp-traversal",
                "back-to-front",
            ],
            "--bsp-traversal",
        ),
        (
            &["compare", "--algos", "bsp", "--octree-depth", "3"],
            "--octree-depth 3",
        ),
    ];
    for (args, flag) in cases {
        let mut all = args.to_vec();
        all.extend(["demo:cube", "--size", "8x8", "-o", "x.png"]);
        let o = obscura(&all, &dir);
        let t = text(&o);
        assert!(o.status.success(), "{all:?}: {t}");
        assert!(
            t.contains(&format!("warning: {flag}")) && t.contains("no effect"),
            "{all:?}: {t}"
        );
    }
    // Used, they give no such warning.
    let o = obscura(
        &[
            "render",
            "demo:cube",
            "--algo",
            "octree",
            "--octree-depth",
            "3",
            "--size",
            "8x8",
            "-o",
            "y.png",
        ],
        &dir,
    );
    assert!(
        o.status.success() && !text(&o).contains("no effect"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn messages_print_extreme_numbers_briefly() {
    // A float echoed in a message is at most a few significant digits, in exponent
    // form when far from 1: never hundreds of digits.
    let dir = tempdir("numbers");
    let runs: [&[&str]; 3] = [
        &[
            "bench",
            "demo:cube",
            "--algos",
            "zbuffer",
            "--max-faces",
            "20",
            "--budget",
            "1e-300",
        ],
        &[
            "render",
            "demo:cube",
            "--size",
            "8x8",
            "-o",
            "a.png",
            "--near",
            "1e300",
        ],
        &[
            "render",
            "demo:cube",
            "--size",
            "8x8",
            "-o",
            "b.png",
            "--far",
            "1e-300",
        ],
    ];
    for args in runs {
        let t = text(&obscura(args, &dir));
        let longest = t
            .split(|c: char| !(c.is_ascii_digit() || c == '.'))
            .map(str::len)
            .max()
            .unwrap_or(0);
        assert!(
            longest <= 20,
            "{args:?}: a number of {longest} characters in {t}"
        );
        assert!(t.contains("e300") || t.contains("e-300"), "{args:?}: {t}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A triangle OBJ with a material library, and a scene file placing it, in `dir`.
fn write_triangle_scene(dir: &std::path::Path) -> (&'static str, &'static str, &'static str) {
    let mtl = "newmtl red\nKd 1 0 0\n";
    let obj = "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
    let toml = "[[object]]\nmesh = \"tri.obj\"\n";
    std::fs::write(dir.join("tri.mtl"), mtl).unwrap();
    std::fs::write(dir.join("tri.obj"), obj).unwrap();
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    (mtl, obj, toml)
}

/// No output may be a file the load read (a mesh of a scene file, a material library),
/// whatever its spelling, a symbolic link or a hard link to it; nothing is left behind
/// and the inputs are unchanged.
#[cfg(unix)]
#[test]
fn outputs_that_are_files_the_scene_reads_are_refused() {
    let dir = tempdir("inputs");
    let (mtl, obj, toml) = write_triangle_scene(&dir);
    std::fs::hard_link(dir.join("tri.obj"), dir.join("hard.npy")).unwrap();
    std::os::unix::fs::symlink("tri.mtl", dir.join("link.json")).unwrap();
    let before = listing(&dir);
    let cases: [(&[&str], &[&str]); 6] = [
        (
            &["render", "tri.obj", "--stats-json", "tri.mtl"],
            &["--stats-json", "tri.mtl", "expected", ".json"],
        ),
        (
            &[
                "render",
                "tri.obj",
                "--stats-json",
                "./tri.mtl",
                "--force-extension",
            ],
            &["--stats-json", "tri.mtl", "refusing to overwrite an input"],
        ),
        (
            &[
                "render",
                "scene.toml",
                "--ids",
                "tri.obj",
                "--force-extension",
            ],
            &[
                "--ids",
                "tri.obj",
                "scene.toml",
                "refusing to overwrite an input",
            ],
        ),
        (
            &["render", "scene.toml", "--ids", "hard.npy"],
            &[
                "--ids",
                "hard.npy",
                "tri.obj",
                "refusing to overwrite an input",
            ],
        ),
        (
            &[
                "compare",
                "tri.obj",
                "--json",
                "link.json",
                "--algos",
                "bsp",
            ],
            &[
                "--json",
                "link.json",
                "tri.mtl",
                "refusing to overwrite an input",
            ],
        ),
        (
            &[
                "bench",
                "scene.toml",
                "--json",
                "hard.npy",
                "--force-extension",
            ],
            &["--json", "hard.npy", "refusing to overwrite an input"],
        ),
    ];
    for (args, expected) in cases {
        let mut args = args.to_vec();
        args.extend(["--size", "8x8"]);
        let o = obscura(&args, &dir);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {t}");
        for e in expected {
            let e = e.replace("expected", "name the file");
            assert!(t.contains(&e), "{args:?}: expected {e:?} in {t}");
        }
        assert_eq!(listing(&dir), before, "{args:?}");
        assert_eq!(std::fs::read_to_string(dir.join("tri.mtl")).unwrap(), mtl);
        assert_eq!(std::fs::read_to_string(dir.join("tri.obj")).unwrap(), obj);
        assert_eq!(
            std::fs::read_to_string(dir.join("scene.toml")).unwrap(),
            toml
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Each output wants its format's extension (any case); another, or none, is refused
/// before any work unless --force-extension; devices have no extension to check.
#[cfg(unix)]
#[test]
fn outputs_are_checked_against_their_kind() {
    let dir = tempdir("extensions");
    let refused: [(&[&str], &str, &str); 8] = [
        (&["render", "-o", "x.jpg"], "-o", ".png"),
        (&["render", "-o", "picture"], "-o", ".png"),
        (&["render", "--ids", "ids.txt"], "--ids", ".npy"),
        (&["render", "--depth", "d.png"], "--depth", ".npy"),
        (
            &["render", "--stats-json", "s.npy"],
            "--stats-json",
            ".json",
        ),
        (&["compare", "-o", "grid.npy"], "-o", ".png"),
        (&["compare", "--json", "c.csv"], "--json", ".json"),
        (
            &["bench", "--json", "b.txt", "--max-faces", "10"],
            "--json",
            ".json",
        ),
    ];
    for (args, option, want) in refused {
        let mut args = args.to_vec();
        args.extend(["demo:cube", "--size", "8x8"]);
        let o = obscura(&args, &dir);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {t}");
        for e in [
            option,
            &format!("name the file {want}"),
            "--force-extension",
        ] {
            assert!(t.contains(e), "{args:?}: expected {e:?} in {t}");
        }
        assert!(listing(&dir).is_empty(), "{args:?}: {:?}", listing(&dir));
        // Forced, the same name is written, in the option's format.
        args.push("--force-extension");
        let o = obscura(&args, &dir);
        assert!(o.status.success(), "{args:?}: {}", text(&o));
        let name = args[args.iter().position(|a| *a == option).unwrap() + 1];
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let magic: &[u8] = match want {
            ".png" => b"\x89PNG",
            ".npy" => b"\x93NUMPY",
            _ => b"{",
        };
        assert!(bytes.starts_with(magic), "{args:?}: {name}");
        for f in listing(&dir) {
            std::fs::remove_file(dir.join(f)).unwrap();
        }
    }
    // Upper-case extensions are theirs too, and a device is written in place.
    let o = obscura(
        &[
            "render",
            "demo:cube",
            "--size",
            "8x8",
            "-o",
            "UP.PNG",
            "--ids",
            "I.Npy",
            "--stats-json",
            "/dev/null",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(listing(&dir), ["I.Npy", "UP.PNG"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// Files outside the scene's folder are read only with --allow-outside-references, on
/// every subcommand; the message names the file, the line, the reference and the flag.
#[test]
fn references_outside_the_scene_folder_need_the_flag() {
    let dir = tempdir("outside");
    std::fs::create_dir_all(dir.join("s")).unwrap();
    std::fs::write(dir.join("out.mtl"), "newmtl red\nKd 1 0 0\n").unwrap();
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        dir.join("s/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nmtllib ../out.mtl\nusemtl red\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("s/scene.toml"),
        "[[object]]\nmesh = \"../m.obj\"\n",
    )
    .unwrap();
    let cases: [(&[&str], &str, &str); 4] = [
        (&["render", "s/tri.obj"], "s/tri.obj: line 4", "../out.mtl"),
        (
            &["render", "s/scene.toml"],
            "s/scene.toml: line 2",
            "../m.obj",
        ),
        (
            &["compare", "s/scene.toml", "--algos", "bsp"],
            "s/scene.toml: line 2",
            "../m.obj",
        ),
        (
            &["bench", "s/tri.obj", "--algos", "zbuffer"],
            "s/tri.obj",
            "../out.mtl",
        ),
    ];
    for (args, at, reference) in cases {
        let mut args = args.to_vec();
        args.extend(["--size", "8x8"]);
        let o = obscura(&args, &dir);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {t}");
        for e in [
            at,
            &format!("\"{reference}\""),
            "--allow-outside-references",
        ] {
            assert!(t.contains(e), "{args:?}: expected {e:?} in {t}");
        }
        assert!(
            !t.contains("LoadOptions"),
            "a library name in a CLI message: {t}"
        );
        args.push("--allow-outside-references");
        let o = obscura(&args, &dir);
        assert!(o.status.success(), "{args:?}: {}", text(&o));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Interrupted (SIGTERM, SIGINT), a run removes its temporary files, ends with 128 +
/// the signal's number and leaves an earlier output as it was.
#[cfg(unix)]
#[test]
fn an_interrupted_run_leaves_no_temporary_files() {
    for (signal, code) in [("TERM", 143), ("INT", 130)] {
        let dir = tempdir(&format!("signal-{signal}"));
        std::fs::write(dir.join("slow.png"), "earlier output").unwrap();
        // Brute-force ray casting of a million triangles: minutes of work (no time
        // limit, which would refuse it up front).
        let mut child = Command::new(env!("CARGO_BIN_EXE_obscura"))
            .args([
                "render",
                "demo:sphere",
                "--algo",
                "raycast",
                "--size",
                "400x400",
                "--threads",
                "1",
                "--time-limit",
                "none",
                "-o",
                "slow.png",
                "--ids",
                "slow.npy",
            ])
            .current_dir(&dir)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("the binary runs");
        let temporaries = |dir: &PathBuf| {
            listing(dir)
                .into_iter()
                .filter(|n| n.contains(".obscura-") && n.ends_with(".tmp"))
                .count()
        };
        let start = std::time::Instant::now();
        while temporaries(&dir) < 2 {
            assert!(
                start.elapsed().as_secs() < 30,
                "no temporary files after 30 s: {:?}",
                listing(&dir)
            );
            assert!(child.try_wait().unwrap().is_none(), "the run ended early");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        // Into the load or the rendering.
        std::thread::sleep(std::time::Duration::from_millis(300));
        let killed = Command::new("kill")
            .args(["-s", signal, &child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(killed.success());
        let start = std::time::Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            if start.elapsed().as_secs() >= 20 {
                child.kill().ok();
                panic!("SIG{signal}: still running after 20 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        };
        assert_eq!(status.code(), Some(code), "SIG{signal}: {status:?}");
        assert_eq!(listing(&dir), ["slow.png"], "SIG{signal}");
        assert_eq!(
            std::fs::read_to_string(dir.join("slow.png")).unwrap(),
            "earlier output"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}

/// Writes `n` large random triangles (a linear congruential generator, so the file is
/// the same every run) as an OBJ: they cut each other everywhere.
fn write_random_large_triangles(path: &PathBuf, n: usize) {
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 20.0 - 10.0
    };
    let mut s = String::new();
    for _ in 0..3 * n {
        s += &format!("v {} {} {}\n", next(), next(), next());
    }
    for t in 0..n {
        s += &format!("f {} {} {}\n", 3 * t + 1, 3 * t + 2, 3 * t + 3);
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn compare_skips_an_algorithm_over_the_memory_budget_and_writes_the_others() {
    let dir = tempdir("compare-budget");
    write_random_large_triangles(&dir.join("tris.obj"), 600);
    let o = obscura_within(
        &[
            "compare",
            "tris.obj",
            "--size",
            "64x48",
            "--algos",
            "scanline,bsp,raycast-bvh",
            "--memory-limit",
            "2M",
            "--json",
            "c.json",
        ],
        &dir,
        60,
    );
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    let bsp = t
        .lines()
        .find(|l| l.starts_with("bsp "))
        .unwrap_or_else(|| panic!("no bsp row in {t}"));
    assert!(
        bsp.contains("skipped") && bsp.contains("BSP fragments") && bsp.contains("--memory-limit"),
        "{bsp}"
    );
    assert!(!bsp.contains("memory_limit"), "{bsp}");
    // The others ran and agree with the z-buffer.
    for a in ["zbuffer ", "scanline ", "raycast-bvh "] {
        let row = t.lines().find(|l| l.starts_with(a)).unwrap();
        assert!(!row.contains("skipped") && !row.contains("error"), "{row}");
    }
    assert!(dir.join("compare.png").exists());
    let json: String = std::fs::read_to_string(dir.join("c.json")).unwrap();
    assert!(
        json.contains("\"skipped\"") && json.contains("BSP fragments"),
        "{json}"
    );
    assert_eq!(json.matches("\"differing_pixels\"").count(), 3, "{json}");
    // The same budget stops `render` with the structure and the flag named.
    refused(
        &dir,
        &[(
            &[
                "render",
                "tris.obj",
                "--size",
                "64x48",
                "--algo",
                "bsp",
                "--memory-limit",
                "2M",
            ],
            &["BSP fragments", "--memory-limit"],
        )],
    );
    // Sizes are checked at parsing.
    refused(
        &dir,
        &[
            (
                &["render", "--memory-limit", "lots"],
                &["--memory-limit", "lots"],
            ),
            (&["render", "--memory-limit", "0"], &["--memory-limit"]),
        ],
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn compare_skips_what_passes_the_time_limit_and_shows_the_rest() {
    let dir = tempdir("compare-time");
    // 3,000 triangles at 640x480: brute-force ray casting would test 9.2e8 pairs,
    // about 1.4 s on the reference machine, over a limit of 1 s.
    write_random_large_triangles(&dir.join("tris.obj"), 3000);
    let o = obscura_within(
        &[
            "compare",
            "tris.obj",
            "--size",
            "640x480",
            "--algos",
            "zbuffer,raycast,raycast-bvh",
            "--time-limit",
            "1",
            "--json",
            "c.json",
        ],
        &dir,
        60,
    );
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    let row = t
        .lines()
        .find(|l| l.starts_with("raycast "))
        .unwrap_or_else(|| panic!("no raycast row in {t}"));
    assert!(
        row.contains("skipped")
            && row.contains("ray-triangle tests")
            && row.contains("--time-limit"),
        "{row}"
    );
    assert!(!row.contains("time_limit"), "{row}");
    let bvh = t.lines().find(|l| l.starts_with("raycast-bvh ")).unwrap();
    assert!(!bvh.contains("skipped") && !bvh.contains("error"), "{bvh}");
    // Rows keep the order asked for, though the cheap ones ran first.
    let pos = |name: &str| t.find(&format!("\n{name} ")).unwrap();
    assert!(
        pos("zbuffer") < pos("raycast") && pos("raycast") < pos("raycast-bvh"),
        "{t}"
    );
    // `render` refuses the same work with the estimate and the flag; `none` lifts it
    // (not run: seconds), and bad values are refused with the flag named.
    refused(
        &dir,
        &[
            (
                &[
                    "render",
                    "tris.obj",
                    "--size",
                    "640x480",
                    "--algo",
                    "raycast",
                    "--time-limit",
                    "1",
                    "-o",
                    "r.png",
                ],
                &[
                    "tris.obj: raycast",
                    "ray-triangle tests",
                    "--time-limit",
                    "on the reference machine",
                ],
            ),
            (
                &["render", "demo:cube", "--time-limit", "soon", "-o", "r.png"],
                &["--time-limit", "number"],
            ),
            (
                &["render", "demo:cube", "--time-limit", "-3", "-o", "r.png"],
                &["--time-limit", "positive"],
            ),
            (
                &[
                    "render",
                    "demo:cube",
                    "--time-limit",
                    "5 parsecs",
                    "-o",
                    "r.png",
                ],
                &["--time-limit", "unit"],
            ),
        ],
    );
    assert!(!dir.join("r.png").exists());
    for limit in ["none", "2m", "0.5h", "30s"] {
        let o = obscura_within(
            &[
                "render",
                "demo:cube",
                "--size",
                "32x24",
                "--time-limit",
                limit,
                "-o",
                "ok.png",
            ],
            &dir,
            30,
        );
        assert!(o.status.success(), "{limit}: {}", text(&o));
    }
}

/// Every key each algorithm reports, in the order `--stats` prints them, written out
/// here on its own (not taken from the library), so that a stat removed, renamed or
/// moved fails this test. `--stats-json` and `compare --json` add `time_ms`.
const STAT_KEYS: [(&str, &[&str]); 11] = [
    (
        "zbuffer",
        &[
            "polygons",
            "polygons_drawn",
            "pixels_tested",
            "pixels_written",
            "big_polygons",
            "setup_and_small_ms",
            "binning_ms",
            "tiles_ms",
        ],
    ),
    (
        "scanline",
        &[
            "polygons",
            "edges",
            "max_active_edges",
            "max_active_faces",
            "spans",
            "spans_without_comparison",
            "spans_decided_at_ends",
            "spans_by_kept_nearest",
            "faces_hidden_on_entering",
            "spans_by_coherence",
            "spans_per_pixel",
            "depth_comparisons",
            "comparisons_skipped_by_coherence",
            "order_checks",
            "orders_proven",
            "crossing_corrections",
            "span_fallbacks",
            "table_ms",
            "enter_ms",
            "sweep_ms",
            "sort_ms",
            "walk_ms",
        ],
    ),
    (
        "depth-sort",
        &[
            "polygons",
            "polygons_sorted",
            "comparisons",
            "decided_depth",
            "decided_same_face",
            "decided_test1_x",
            "decided_test2_y",
            "decided_test3",
            "decided_test4",
            "decided_test5",
            "decided_coplanar",
            "decided_overlap_depth",
            "swaps",
            "swap_test3",
            "swap_test4",
            "swap_overlap_depth",
            "cycles",
            "splits",
            "unresolved",
            "unsorted",
            "polygons_painted",
            "pixels_written",
        ],
    ),
    (
        "depth-sort-matrix",
        &[
            "polygons",
            "polygons_sorted",
            "comparisons",
            "decided_same_face",
            "decided_test1_x",
            "decided_test2_y",
            "decided_planes_both_orders",
            "decided_test5",
            "decided_coplanar",
            "decided_overlap_depth",
            "relations",
            "cycles_broken",
            "splits",
            "unresolved",
            "unsorted",
            "polygons_painted",
            "pixels_written",
        ],
    ),
    (
        "bsp",
        &[
            "bsp_nodes",
            "bsp_fragments",
            "bsp_splits",
            "bsp_depth",
            "build_ms",
            "front_to_back",
            "view_ms",
            "fragments_visited",
            "fragments_culled",
            "fragments_outside",
            "subtrees_hidden",
            "subtrees_outside",
            "fragments_painted",
            "pixels_written",
            "early_exit",
            "visited_fraction",
        ],
    ),
    (
        "warnock",
        &[
            "polygons",
            "windows",
            "rule1",
            "rule2",
            "rule3",
            "rule4",
            "rule5",
            "pixel_decisions",
            "classifications",
            "depth_comparisons",
            "max_depth",
        ],
    ),
    (
        "raycast",
        &[
            "triangles",
            "front_triangles",
            "rays",
            "hits",
            "triangle_tests",
            "trace_ms",
            "mrays_per_s",
            "triangle_tests_per_ray",
            "triangles_ms",
        ],
    ),
    (
        "raycast-bounds",
        &[
            "triangles",
            "front_triangles",
            "rays",
            "hits",
            "triangle_tests",
            "trace_ms",
            "mrays_per_s",
            "bounds_build_ms",
            "objects",
            "bound_tests",
            "bound_hits",
            "triangle_tests_brute_force",
            "triangle_tests_saved",
            "saved_fraction",
            "triangles_ms",
        ],
    ),
    (
        "raycast-bvh",
        &[
            "triangles",
            "front_triangles",
            "rays",
            "hits",
            "triangle_tests",
            "trace_ms",
            "mrays_per_s",
            "packet_node_visits_per_ray",
            "build_ms",
            "binary_nodes",
            "binary_depth",
            "nodes",
            "leaves",
            "depth",
            "sah_cost",
            "node_visits_per_ray",
            "triangle_tests_per_ray",
            "triangles_ms",
        ],
    ),
    (
        "raycast-grid",
        &[
            "triangles",
            "front_triangles",
            "rays",
            "hits",
            "triangle_tests",
            "trace_ms",
            "mrays_per_s",
            "build_ms",
            "cells",
            "resolution_x",
            "resolution_y",
            "resolution_z",
            "refs",
            "refs_per_cell",
            "empty_cells",
            "largest_cell",
            "cells_per_ray",
            "triangle_tests_per_ray",
            "mailbox_hits",
            "hits_outside_cell",
            "far_rays",
            "triangles_ms",
        ],
    ),
    (
        "octree",
        &[
            "depth",
            "voxels_per_side",
            "triangles",
            "nodes",
            "nodes_before_merge",
            "leaves_empty",
            "leaves_full",
            "leaves_partial",
            "bytes_per_node",
            "memory_bytes",
            "sat_tests",
            "components",
            "inside_queries",
            "triangles_ms",
            "subdivide_ms",
            "classify_ms",
            "merge_ms",
            "build_ms",
            "trace_ms",
            "rays",
            "nodes_visited",
            "nodes_visited_per_ray",
            "pixels_covered",
            "near_faces",
        ],
    ),
];

/// The keys of a JSON object, sorted (the order is checked on `--stats`' rows).
fn sorted_keys(v: &serde_json::Value) -> Vec<String> {
    let mut k: Vec<String> = v
        .as_object()
        .unwrap_or_else(|| panic!("an object: {v}"))
        .keys()
        .cloned()
        .collect();
    k.sort();
    k
}

/// `expected` with `time_ms`, sorted.
fn with_time(expected: &[&str]) -> Vec<String> {
    let mut k: Vec<String> = expected.iter().map(|s| (*s).to_owned()).collect();
    k.push("time_ms".to_owned());
    k.sort();
    k
}

#[test]
fn every_algorithm_reports_its_full_list_of_stats() {
    let dir = tempdir("stat-keys");
    let common = ["demo:default", "--size", "48x36", "--threads", "1"];
    for (algo, expected) in STAT_KEYS {
        let mut args = vec!["render"];
        args.extend(common);
        args.extend([
            "--algo",
            algo,
            "--stats",
            "--stats-json",
            "s.json",
            "-o",
            "r.png",
        ]);
        let o = obscura(&args, &dir);
        assert!(o.status.success(), "{algo}: {}", text(&o));
        // `--stats`: one indented row per stat after the algorithm's row, in order.
        let out = String::from_utf8_lossy(&o.stdout);
        let rows: Vec<(&str, f64)> = out
            .lines()
            .skip_while(|l| !l.starts_with("visibility: "))
            .skip(1)
            .take_while(|l| l.starts_with("  "))
            .map(|l| {
                let mut w = l.split_whitespace();
                let key = w.next().unwrap();
                let value = w.next().unwrap().parse::<f64>();
                (key, value.unwrap_or_else(|e| panic!("{algo}: {l}: {e}")))
            })
            .collect();
        let keys: Vec<&str> = rows.iter().map(|r| r.0).collect();
        assert_eq!(keys, expected, "{algo}: --stats rows\n{out}");
        // `--stats-json`: the same keys and values, and `time_ms` (also `algorithm_ms`).
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
        let stats = &json["stats"];
        assert_eq!(sorted_keys(stats), with_time(expected), "{algo}: {json}");
        for (key, value) in &rows {
            // (serde_json's reading of a decimal may be off by an ulp.)
            let json = stats[*key].as_f64().unwrap_or(f64::NAN);
            assert!(
                (json - value).abs() <= 1e-12 * value.abs(),
                "{algo}: {key} {json} in JSON, {value} in --stats"
            );
        }
        assert_eq!(stats["time_ms"], json["algorithm_ms"], "{algo}");
    }
    // `compare --json`: every algorithm's stats with the same keys; the table's
    // structure column shows the first five.
    let names: Vec<&str> = STAT_KEYS.iter().map(|(a, _)| *a).collect();
    let list = names.join(",");
    let mut args = vec!["compare"];
    args.extend(common);
    args.extend(["--algos", &list, "--json", "c.json", "-o", "c.png"]);
    let o = obscura(&args, &dir);
    assert!(o.status.success(), "{}", text(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("c.json")).unwrap()).unwrap();
    let rows = json["algorithms"].as_array().expect("an algorithms array");
    assert_eq!(rows.len(), STAT_KEYS.len(), "{json}");
    let table = String::from_utf8_lossy(&o.stdout);
    for (row, (algo, expected)) in rows.iter().zip(STAT_KEYS) {
        assert_eq!(row["algorithm"], algo, "{json}");
        assert_eq!(sorted_keys(&row["stats"]), with_time(expected), "{algo}");
        let line = table
            .lines()
            .find(|l| l.split_whitespace().next() == Some(algo))
            .unwrap_or_else(|| panic!("no row of {algo}: {table}"));
        let shown: Vec<&str> = line
            .split_whitespace()
            .skip(4)
            .map(|kv| kv.split('=').next().unwrap())
            .collect();
        assert_eq!(shown, expected[..5], "{algo}: {line}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn library_parameter_errors_are_named_by_their_cli_flags() {
    // The library names its parameters (`RenderOptions::bounds`...); the CLI's
    // messages name the flag the user gave.
    let dir = tempdir("parameter-flags");
    for (args, flag, library) in [
        (
            ["render", "demo:cube", "--bounds", "cone"],
            "--bounds",
            "RenderOptions::bounds",
        ),
        (
            ["render", "demo:cube", "--bsp-traversal", "sideways"],
            "--bsp-traversal",
            "BspOptions::traversal",
        ),
    ] {
        let o = obscura(&args, &dir);
        assert!(!o.status.success());
        let t = text(&o);
        assert!(t.contains(flag) && !t.contains(library), "{args:?}: {t}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
