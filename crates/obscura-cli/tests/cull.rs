//! `obscura cull`, `render --cull` and `obscura export`: what they print and write, and
//! how they refuse bad input. The expectations come from other commands of the binary
//! (the ids `render` writes are the ground truth of what is visible).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn obscura(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_obscura"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the binary runs")
}

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("obscura-cull-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
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

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", text(o));
    text(o)
}

fn failed(o: &Output) -> String {
    assert!(!o.status.success(), "succeeded: {}", text(o));
    text(o)
}

/// The shape and the 4-byte values of a NumPy file (`<i4` or `<f4`).
fn npy(path: &Path) -> (String, Vec<[u8; 4]>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..6], b"\x93NUMPY");
    let hl = u16::from_le_bytes([b[8], b[9]]) as usize;
    assert_eq!((10 + hl) % 64, 0, "header aligned");
    let header = String::from_utf8(b[10..10 + hl].to_vec()).unwrap();
    let shape = header
        .split("'shape': ")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .unwrap()
        .to_string()
        + ")";
    let values = b[10 + hl..]
        .chunks(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    (shape, values)
}

fn npy_i32(path: &Path) -> (String, Vec<i32>) {
    let (s, v) = npy(path);
    (s, v.into_iter().map(i32::from_le_bytes).collect())
}

/// Width and height of a PNG.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[1..4], b"PNG");
    let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    (be(16), be(20))
}

/// A street-level view of the city: buildings on both sides, many behind the eye.
const STREET: [&str; 8] = [
    "--eye",
    "0,1.5,-30",
    "--target",
    "0,1.5,30",
    "--fov",
    "60",
    "--size",
    "160x90",
];

#[test]
fn cull_prints_a_row_per_method_with_reasons_and_stages() {
    let dir = tempdir("rows");
    let mut args = vec!["cull", "demo:city", "--method", "all", "--stats"];
    args.extend(STREET);
    let out = ok(&obscura(&args, &dir));
    for m in [
        "frustum",
        "portals",
        "screen-portals",
        "occluders",
        "buffer",
    ] {
        assert!(
            out.lines().any(|l| l.trim_start().starts_with(m)),
            "{m}: {out}"
        );
    }
    assert!(out.contains("objects tested/culled/drawn"), "{out}");
    assert!(out.contains("culled objects: frustum"), "{out}");
    assert!(out.contains("stages: frustum"), "{out}");
    // From the middle of the city looking along a street, the frustum culls thousands
    // of the 10,000 buildings: the frustum row's objects culled is not 0.
    let row = out
        .lines()
        .find(|l| l.trim_start().starts_with("frustum "))
        .unwrap();
    let objects: Vec<u64> = row
        .split_whitespace()
        .nth(1)
        .unwrap()
        .split('/')
        .map(|n| n.parse().unwrap())
        .collect();
    assert_eq!(objects[0], 10_001, "{row}");
    assert!(objects[1] > 1000, "{row}");
    assert_eq!(objects[0] - objects[1], objects[2], "{row}");
}

#[test]
fn kept_faces_hold_every_visible_face_sorted_and_unique() {
    let dir = tempdir("kept");
    let mut r = vec!["render", "demo:city", "--ids", "ids.npy", "-o", "city.png"];
    r.extend(STREET);
    ok(&obscura(&r, &dir));
    let (_, ids) = npy_i32(&dir.join("ids.npy"));
    for method in ["frustum", "buffer", "occluders"] {
        let mut c = vec![
            "cull",
            "demo:city",
            "--method",
            method,
            "--kept",
            "kept.npy",
        ];
        c.extend(STREET);
        let out = ok(&obscura(&c, &dir));
        assert!(out.contains("wrote kept.npy"), "{out}");
        let (shape, kept) = npy_i32(&dir.join("kept.npy"));
        assert_eq!(shape, format!("({},)", kept.len()));
        assert!(kept.windows(2).all(|w| w[0] < w[1]), "sorted, unique");
        assert!(kept.iter().all(|&f| (0..60_001).contains(&f)));
        assert!(kept.len() < 60_001, "{method}: the frustum culls some");
        for &id in ids.iter().filter(|&&id| id >= 0) {
            assert!(
                kept.binary_search(&id).is_ok(),
                "{method}: visible face {id} not kept"
            );
        }
    }
}

#[test]
fn render_with_every_cull_method_equals_render_without() {
    let dir = tempdir("render");
    let run = |method: &str, algo: &str| {
        let ids = format!("ids-{method}-{algo}.npy");
        let depth = format!("depth-{method}-{algo}.npy");
        let mut a = vec![
            "render",
            "demo:city",
            "--cull",
            method,
            "--algo",
            algo,
            "--ids",
            &ids,
            "--depth",
            &depth,
            "-o",
            "x.png",
            "--stats",
        ];
        a.extend(STREET);
        let out = ok(&obscura(&a, &dir));
        if method != "none" {
            assert!(out.contains(&format!("culling: {method}")), "{out}");
        }
        (npy(&dir.join(&ids)).1, npy(&dir.join(&depth)).1)
    };
    for algo in ["zbuffer", "raycast-bvh"] {
        let base = run("none", algo);
        for m in [
            "frustum",
            "portals",
            "screen-portals",
            "occluders",
            "buffer",
        ] {
            assert!(
                run(m, algo) == base,
                "{algo} --cull {m} changed the picture"
            );
        }
    }
    let o = failed(&obscura(&["render", "--cull", "everything"], &dir));
    assert!(
        o.contains("unknown culling method") && o.contains("screen-portals"),
        "{o}"
    );
}

#[test]
fn compare_and_bench_accept_cull() {
    let dir = tempdir("compare");
    let o = ok(&obscura(
        &[
            "compare",
            "demo:cube",
            "--cull",
            "buffer",
            "--algos",
            "zbuffer,scanline",
            "--size",
            "48x32",
            "-o",
            "grid.png",
        ],
        &dir,
    ));
    assert!(o.contains("scanline"), "{o}");
    let o = ok(&obscura(
        &[
            "bench",
            "--cull",
            "occluders",
            "--algos",
            "zbuffer",
            "--max-faces",
            "1000",
            "--size",
            "64x36",
        ],
        &dir,
    ));
    assert!(o.contains("cull (occluders)"), "{o}");
}

#[test]
fn a_walk_runs_every_frame_and_its_errors_name_file_and_line() {
    let dir = tempdir("walk");
    std::fs::write(
        dir.join("walk.csv"),
        "eye_x,eye_y,eye_z,target_x,target_y,target_z,fov\n\
         0,1.5,-30,0,1.5,30,60\n\
         # turning\n\
         0,1.5,-20,5,1.5,30,70\n\
         3,1.5,-10,3,1.5,30,50\n",
    )
    .unwrap();
    let out = ok(&obscura(
        &[
            "cull",
            "demo:city",
            "--method",
            "frustum",
            "--walk",
            "walk.csv",
            "--size",
            "96x54",
            "--stats-json",
            "walk.json",
            "--kept",
            "kept.npy",
        ],
        &dir,
    ));
    for f in ["frame 0 (line 2)", "frame 1 (line 4)", "frame 2 (line 5)"] {
        assert!(out.contains(f), "{f}: {out}");
    }
    assert!(out.contains("walk of 3 frames"), "{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("walk.json")).unwrap()).unwrap();
    let frames = json["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    assert_eq!(frames[1]["eye"], serde_json::json!([0.0, 1.5, -20.0]));
    assert_eq!(frames[2]["methods"][0]["method"], "frustum");
    assert!(
        frames[0]["methods"][0]["stats"]["faces_culled"]
            .as_u64()
            .unwrap()
            > 0
    );
    // The union over the walk holds each frame's kept faces: at least the first's.
    let (_, union) = npy_i32(&dir.join("kept.npy"));
    ok(&obscura(
        &[
            "cull",
            "demo:city",
            "--method",
            "frustum",
            "--eye",
            "0,1.5,-30",
            "--target",
            "0,1.5,30",
            "--fov",
            "60",
            "--size",
            "96x54",
            "--kept",
            "one.npy",
        ],
        &dir,
    ));
    let (_, one) = npy_i32(&dir.join("one.npy"));
    assert!(one.len() < union.len());
    assert!(one.iter().all(|f| union.binary_search(f).is_ok()));

    let bad = [
        ("", "empty.csv:1"),
        ("x,y,z\n1,2,3\n", "bad.csv:1: the header"),
        (
            "eye_x,eye_y,eye_z,target_x,target_y,target_z\n0,1,2,3,4,5\n\n0,1,2,3,four,5\n",
            "bad.csv:4: target_y",
        ),
        (
            "eye_x,eye_y,eye_z,target_x,target_y,target_z\n0,1,2,3,4\n",
            "bad.csv:2: 5 values",
        ),
        (
            "eye_x,eye_y,eye_z,target_x,target_y,target_z\n1,1,1,1,1,1\n",
            "bad.csv:2:",
        ),
    ];
    for (content, want) in bad {
        let name = if content.is_empty() {
            "empty.csv"
        } else {
            "bad.csv"
        };
        std::fs::write(dir.join(name), content).unwrap();
        let o = failed(&obscura(
            &["cull", "demo:cube", "--method", "frustum", "--walk", name],
            &dir,
        ));
        assert!(o.contains(want), "{content:?}: want {want}: {o}");
    }
    let o = failed(&obscura(
        &["cull", "demo:cube", "--walk", "missing.csv"],
        &dir,
    ));
    assert!(o.contains("missing.csv"), "{o}");
    let o = failed(&obscura(
        &["cull", "demo:cube", "--walk", "walk.csv", "--eye", "1,2,3"],
        &dir,
    ));
    assert!(o.contains("--eye"), "{o}");
}

#[test]
fn explain_writes_a_picture_of_the_view() {
    let dir = tempdir("explain");
    let out = ok(&obscura(
        &[
            "cull",
            "demo:default",
            "--method",
            "occluders",
            "--size",
            "120x80",
            "--explain",
            "why.png",
        ],
        &dir,
    ));
    assert!(out.contains("wrote why.png"), "{out}");
    assert_eq!(png_size(&dir.join("why.png")), (120, 80));
    // The occlusion buffer's depth, when the method keeps it, doubles the width.
    ok(&obscura(
        &[
            "cull",
            "demo:default",
            "--method",
            "buffer",
            "--size",
            "120x80",
            "--explain",
            "buffer.png",
        ],
        &dir,
    ));
    let (w, h) = png_size(&dir.join("buffer.png"));
    assert!(w == 120 || w == 240, "{w}");
    assert_eq!(h, 80);
    // One method only, and outputs are checked as everywhere.
    let o = failed(&obscura(
        &["cull", "demo:cube", "--method", "all", "--explain", "a.png"],
        &dir,
    ));
    assert!(o.contains("--explain") && o.contains("one --method"), "{o}");
    let o = failed(&obscura(
        &["cull", "demo:cube", "--method", "buffer", "--kept", "k.png"],
        &dir,
    ));
    assert!(o.contains("--kept"), "{o}");
}

/// The same camera for a scene and its export (the demo has a camera, the OBJ none).
const CAMERA: [&str; 12] = [
    "--eye", "4,3.5,6", "--target", "0,0.8,0", "--up", "0,1,0", "--fov", "50", "--near", "0.5",
    "--far", "40",
];

#[test]
fn export_round_trips_the_face_ids() {
    let dir = tempdir("export");
    for demo in ["demo:default", "demo:cube", "demo:blocks"] {
        let out = ok(&obscura(&["export", demo, "-o", "scene.obj"], &dir));
        assert!(out.contains("wrote scene.obj"), "{out}");
        let mut a = vec![
            "render", demo, "--ids", "a.npy", "-o", "a.png", "--size", "160x120",
        ];
        a.extend(CAMERA);
        ok(&obscura(&a, &dir));
        let mut b = vec![
            "render",
            "scene.obj",
            "--ids",
            "b.npy",
            "-o",
            "b.png",
            "--size",
            "160x120",
        ];
        b.extend(CAMERA);
        ok(&obscura(&b, &dir));
        let (_, ia) = npy_i32(&dir.join("a.npy"));
        let (_, ib) = npy_i32(&dir.join("b.npy"));
        assert!(ia.iter().any(|&i| i >= 0), "{demo}: something visible");
        let differ = ia.iter().zip(&ib).filter(|(x, y)| x != y).count();
        assert_eq!(differ, 0, "{demo}: {differ} pixels differ");
    }
    // One `f` line per face id.
    ok(&obscura(&["export", "demo:default", "-o", "d.obj"], &dir));
    let text = std::fs::read_to_string(dir.join("d.obj")).unwrap();
    let faces = text.lines().filter(|l| l.starts_with("f ")).count();
    let stats = ok(&obscura(
        &["render", "demo:default", "--stats", "-o", "s.png"],
        &dir,
    ));
    assert!(
        stats.contains(&format!("{faces} faces")),
        "{faces} f lines: {stats}"
    );
    // Never over an input, and `-o` wants .obj.
    let o = failed(&obscura(&["export", "d.obj", "-o", "d.obj"], &dir));
    assert!(o.contains("refusing to overwrite"), "{o}");
    let o = failed(&obscura(&["export", "demo:cube", "-o", "cube.png"], &dir));
    assert!(o.contains(".obj"), "{o}");
}

#[test]
fn a_prt1_file_gives_the_scene_cells_and_the_picture_stays() {
    use obscura::cull::portals::prt::{parse_prt, write_prt};
    let dir = tempdir("prt");
    let level = obscura::Scene::demo("level").unwrap();
    let text = write_prt(level.cells().unwrap());
    std::fs::write(dir.join("level.prt"), &text).unwrap();
    // An eye inside the hull of a leaf's portals (the middle of its portal vertices),
    // looking along x.
    let g = parse_prt(&text, Path::new("level.prt")).unwrap();
    let eye = (0..g.cells.len())
        .filter(|&c| !g.cells[c].planes.is_empty())
        .map(|c| {
            let pts: Vec<glam::DVec3> = g
                .portals
                .iter()
                .filter(|p| p.cells.contains(&(c as u32)))
                .flat_map(|p| p.polygon.iter().copied())
                .collect();
            pts.iter().sum::<glam::DVec3>() / pts.len() as f64
        })
        .find(|&e| g.locate(e).is_some())
        .unwrap();
    let eye_s = format!("{},{},{}", eye.x, eye.y, eye.z);
    let target_s = format!("{},{},{}", eye.x + 10.0, eye.y, eye.z + 1.0);
    let view = ["--eye", &eye_s, "--target", &target_s, "--size", "160x90"];
    let mut a = vec![
        "cull",
        "demo:level",
        "--prt",
        "level.prt",
        "--method",
        "portals",
        "--stats",
    ];
    a.extend(view);
    let out = ok(&obscura(&a, &dir));
    assert!(
        out.contains("note: level.prt:") && out.contains("leaves without volume"),
        "{out}"
    );
    assert!(!out.contains("outside every cell"), "{out}");
    let render = |cull: &str| {
        let ids = format!("ids-{cull}.npy");
        let depth = format!("depth-{cull}.npy");
        let mut r = vec![
            "render",
            "demo:level",
            "--prt",
            "level.prt",
            "--cull",
            cull,
            "--ids",
            &ids,
            "--depth",
            &depth,
            "-o",
            "x.png",
        ];
        r.extend(view);
        ok(&obscura(&r, &dir));
        (npy(&dir.join(&ids)).1, npy(&dir.join(&depth)).1)
    };
    let base = render("none");
    assert!(
        render("portals") == base,
        "--cull portals with a PRT1 file changed the picture"
    );
    assert!(render("screen-portals") == base);
    // A bad file: the error names it and its line.
    std::fs::write(
        dir.join("bad.prt"),
        "PRT1\n2\n1\n3 0 7 (0 0 0) (1 0 0) (0 1 0)\n",
    )
    .unwrap();
    let o = failed(&obscura(&["cull", "demo:level", "--prt", "bad.prt"], &dir));
    assert!(
        o.contains("bad.prt") && o.contains('4') && o.contains("out of range"),
        "{o}"
    );
}
