//! Files a scene refers to (glTF buffers, OBJ `mtllib`, scene-file meshes): read only
//! inside the referring file's folder tree unless `allow_outside_references` is set, and
//! every file read listed by `Scene::source_files`. Every file is written here, in a
//! folder `scene/` beside the "outside" files a hostile scene would reach for.
//! (Unix only: the tests make symbolic links.)
// Files referring to files: built with every file format (the default features).
#![cfg(all(
    feature = "obj",
    feature = "gltf",
    feature = "stl",
    feature = "ply",
    feature = "toml-scene"
))]
#![cfg(unix)]

use std::path::{Path, PathBuf};

mod common;

use common::TempDir;
use obscura::scene::load::{LoadOptions, load_file, load_file_with};
use obscura::{Error, Scene};

/// A fresh directory `ROOT` (canonical) with `ROOT/scene` inside, removed when dropped.
struct Dirs {
    root: PathBuf,
    _dir: TempDir,
}

impl Dirs {
    fn new(tag: &str) -> Self {
        let dir = TempDir::new(tag);
        std::fs::create_dir_all(dir.join("scene")).unwrap();
        Dirs {
            root: std::fs::canonicalize(&dir.0).unwrap(),
            _dir: dir,
        }
    }

    fn scene(&self) -> PathBuf {
        self.root.join("scene")
    }

    /// Writes `name` under the root (`scene/x.obj` for the scene's folder).
    fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let p = self.root.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, contents).unwrap();
        p
    }
}

fn allowed() -> LoadOptions {
    LoadOptions::default().with_allow_outside_references(true)
}

/// The 36 bytes of a triangle's three float32 positions (x, y, z).
fn triangle_bin(corners: [[f32; 3]; 3]) -> Vec<u8> {
    corners
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect()
}

const TRIANGLE: [[f32; 3]; 3] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];

/// A glTF with one triangle whose 36-byte buffer has the URI `uri` (JSON-escaped
/// already).
fn gltf(uri: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}},
  "buffers": [{{"byteLength": 36, "uri": "{uri}"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
    "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}], "scene": 0}}"#
    )
}

/// Checks that `e` refuses `reference` written in `path` at `element`, for `reason`, and
/// names the option that allows it.
fn assert_outside(e: &Error, path: &Path, element: &str, reference: &str, reason: &str) {
    let text = e.to_string();
    match e {
        Error::OutsideReference {
            path: p,
            element: el,
            reference: r,
            reason: why,
        } => {
            assert_eq!(p, path, "{text}");
            assert!(el.starts_with(element), "{text}: element {el:?}");
            assert_eq!(r, reference, "{text}");
            assert!(why.contains(reason), "{text}: reason {why:?}");
        }
        other => panic!("expected an outside reference, got {other:?}"),
    }
    assert!(
        text.starts_with(&format!("{}: {element}", path.display())),
        "{text}"
    );
    assert!(text.contains(&format!("\"{reference}\"")), "{text}");
    assert!(text.contains("allow_outside_references"), "{text}");
    assert!(text.contains("LoadOptions"), "{text}");
}

fn load_err(path: &Path) -> Error {
    match load_file(path) {
        Ok(s) => panic!(
            "{} should be refused, loaded {}",
            path.display(),
            s.face_count()
        ),
        Err(e) => e,
    }
}

fn load_allowed(path: &Path) -> Scene {
    load_file_with(path, &allowed())
        .unwrap_or_else(|e| panic!("{} should load when allowed: {e}", path.display()))
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap()
}

#[test]
fn gltf_buffers_outside_the_folder_are_refused_unless_allowed() {
    let d = Dirs::new("gltf");
    let outside = d.write("outside.bin", triangle_bin(TRIANGLE));
    let abs = outside.display().to_string();
    std::os::unix::fs::symlink(&outside, d.scene().join("link.bin")).unwrap();
    std::os::unix::fs::symlink(&d.root, d.scene().join("up")).unwrap();
    std::fs::create_dir(d.scene().join("a")).unwrap();
    let cases = [
        ("climb.gltf", "../outside.bin".to_string(), "`..`"),
        ("deep.gltf", "a/../../outside.bin".to_string(), "`..`"),
        ("encoded.gltf", "%2E%2E/outside.bin".to_string(), "`..`"),
        ("absolute.gltf", abs.clone(), "absolute path"),
        ("file.gltf", format!("file://{abs}"), "file: URI"),
        ("file1.gltf", format!("file:{abs}"), "file: URI"),
        (
            "filehost.gltf",
            format!("FILE://localhost{abs}"),
            "file: URI",
        ),
        ("link.gltf", "link.bin".to_string(), "symbolic link"),
        (
            "dirlink.gltf",
            "up/outside.bin".to_string(),
            "symbolic link",
        ),
    ];
    for (name, uri, reason) in &cases {
        let p = d.write(&format!("scene/{name}"), gltf(uri));
        assert_outside(&load_err(&p), &p, "buffer 0", uri, reason);
        // Allowed, the file is read and listed.
        let s = load_allowed(&p);
        assert_eq!(s.face_count(), 1, "{name}");
        assert_eq!(s.source_files(), [canonical(&p), outside.clone()], "{name}");
    }
    // Remote URIs are refused whatever the option.
    for uri in [
        "http://example.com/x.bin",
        "https://h/x.bin",
        "ftp://h/x.bin",
    ] {
        let p = d.write("scene/remote.gltf", gltf(uri));
        for options in [LoadOptions::default(), allowed()] {
            let e = load_file_with(&p, &options).expect_err(uri);
            let text = e.to_string();
            assert!(matches!(e, Error::Format { .. }), "{text}");
            assert!(text.contains("remote files are not read"), "{text}");
            assert!(text.contains(uri), "{text}");
        }
    }
}

#[test]
fn gltf_buffers_inside_the_folder_and_data_uris_load() {
    let d = Dirs::new("gltf-inside");
    let bin = d.write("scene/sub/in.bin", triangle_bin(TRIANGLE));
    std::os::unix::fs::symlink("sub/in.bin", d.scene().join("inlink.bin")).unwrap();
    for uri in [
        "sub/in.bin",
        "./sub/../sub/in.bin",
        "sub/%69n.bin",
        "inlink.bin",
    ] {
        let p = d.write("scene/in.gltf", gltf(uri));
        let s = load_file(&p).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(s.face_count(), 1, "{uri}");
        assert_eq!(s.source_files(), [canonical(&p), bin.clone()], "{uri}");
    }
    // A `data:` URI holds its bytes: nothing but the glTF is read.
    let b64 = base64(&triangle_bin(TRIANGLE));
    let p = d.write(
        "scene/data.gltf",
        gltf(&format!("data:application/octet-stream;base64,{b64}")),
    );
    let s = load_file(&p).unwrap();
    assert_eq!(s.face_count(), 1);
    assert_eq!(s.source_files(), [canonical(&p)]);
    // A folder whose own path goes through a symbolic link: references are checked
    // against its real location.
    std::os::unix::fs::symlink(d.scene(), d.root.join("scene-link")).unwrap();
    let p = d.root.join("scene-link/in.gltf");
    d.write("scene/in.gltf", gltf("sub/in.bin"));
    assert_eq!(load_file(&p).unwrap().face_count(), 1);
    let p = d.write("scene/escape.gltf", gltf("../scene-link/sub/in.bin"));
    assert_outside(
        &load_err(&p),
        &p,
        "buffer 0",
        "../scene-link/sub/in.bin",
        "`..`",
    );
}

/// Standard base64 (for a `data:` URI).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

const TRI_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn obj_material_libraries_outside_the_folder_are_refused_unless_allowed() {
    let d = Dirs::new("obj");
    let mtl = d.write("out.mtl", "newmtl red\nKd 1 0 0\n");
    let abs = mtl.display().to_string();
    std::os::unix::fs::symlink(&mtl, d.scene().join("link.mtl")).unwrap();
    for (lib, reason) in [
        ("../out.mtl", "`..`"),
        (abs.as_str(), "absolute path"),
        ("/etc/passwd", "absolute path"),
        ("link.mtl", "symbolic link"),
    ] {
        // Refused with or without a material in use (unused, it would not be read,
        // but the file says to read it).
        for usemtl in ["usemtl red\n", ""] {
            let p = d.write(
                "scene/m.obj",
                format!("{TRI_OBJ}mtllib {lib}\n{usemtl}f 1 2 3\n"),
            );
            assert_outside(&load_err(&p), &p, "line 4", lib, reason);
        }
        if lib == "/etc/passwd" {
            continue;
        }
        let p = d.write(
            "scene/m.obj",
            format!("{TRI_OBJ}mtllib {lib}\nusemtl red\nf 1 2 3\n"),
        );
        let s = load_allowed(&p);
        assert_eq!(s.objects()[0].face_color(0), [1.0, 0.0, 0.0], "{lib}");
        assert_eq!(s.source_files(), [canonical(&p), mtl.clone()], "{lib}");
    }
    // Inside: read and listed; a missing library is still only a warning.
    let inside = d.write("scene/mats/in.mtl", "newmtl red\nKd 1 0 0\n");
    let p = d.write(
        "scene/ok.obj",
        format!("{TRI_OBJ}mtllib mats/in.mtl missing.mtl\nusemtl red\nf 1 2 3\n"),
    );
    let s = load_file(&p).unwrap();
    assert_eq!(s.objects()[0].face_color(0), [1.0, 0.0, 0.0]);
    assert_eq!(s.source_files(), [canonical(&p), inside]);
    assert!(
        s.report()
            .warnings()
            .iter()
            .any(|w| w.contains("missing.mtl") && w.contains("not read")),
        "{:?}",
        s.report().warnings()
    );
}

#[test]
fn scene_file_meshes_outside_the_folder_are_refused_unless_allowed() {
    let d = Dirs::new("toml");
    let mesh = d.write("m.obj", format!("{TRI_OBJ}f 1 2 3\n"));
    let abs = mesh.display().to_string();
    std::os::unix::fs::symlink(&mesh, d.scene().join("link.obj")).unwrap();
    for (reference, reason) in [
        ("../m.obj", "`..`"),
        (abs.as_str(), "absolute path"),
        ("link.obj", "symbolic link"),
    ] {
        let p = d.write(
            "scene/s.toml",
            format!("# a scene\n[[object]]\nmesh = \"{reference}\"\n"),
        );
        assert_outside(&load_err(&p), &p, "line 3", reference, reason);
        let s = load_allowed(&p);
        assert_eq!(s.face_count(), 1, "{reference}");
        assert_eq!(
            s.source_files(),
            [canonical(&p), mesh.clone()],
            "{reference}"
        );
    }
}

/// A mesh's own references are resolved against the mesh's folder, not the scene's:
/// a glTF in `scene/sub/` may not climb to `scene/`, though the scene file could.
#[test]
fn references_of_a_referenced_file_stay_in_its_own_folder() {
    let d = Dirs::new("nested");
    let bin = d.write("scene/x.bin", triangle_bin(TRIANGLE));
    let g = d.write("scene/sub/a.gltf", gltf("../x.bin"));
    let p = d.write("scene/s.toml", "[[object]]\nmesh = \"sub/a.gltf\"\n");
    let e = load_err(&p);
    assert_outside(&e, &g, "buffer 0", "../x.bin", "`..`");
    assert!(e.to_string().contains("referenced from"), "{e}");
    assert!(e.to_string().contains(&format!("{}:2", p.display())), "{e}");
    let s = load_allowed(&p);
    assert_eq!(s.source_files(), [canonical(&p), canonical(&g), bin]);
}

/// Every file the load read is listed, once, canonical, whatever its spelling.
#[test]
fn source_files_list_every_file_read_once() {
    let d = Dirs::new("sources");
    let mtl = d.write("scene/m/t.mtl", "newmtl red\nKd 1 0 0\n");
    let obj = d.write(
        "scene/m/t.obj",
        format!("{TRI_OBJ}mtllib t.mtl\nusemtl red\nf 1 2 3\n"),
    );
    let stl = d.write(
        "scene/s.stl",
        "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
         vertex 0 1 0\nendloop\nendfacet\nendsolid s\n",
    );
    let p = d.write(
        "scene/all.toml",
        "[[object]]\nmesh = \"m/t.obj\"\n[[object]]\nmesh = \"./m/../m/t.obj\"\n\
         [[object]]\nmesh = \"s.stl\"\n[[object]]\nprimitive = \"box\"\n",
    );
    let s = load_file(&p).unwrap();
    assert_eq!(s.source_files(), [canonical(&p), obj, mtl, stl]);
    // Loaded by a relative spelling, the scene file is listed canonical.
    let rel = Path::new("./scene/all.toml");
    let cwd_scene = d.root.join(rel);
    assert_eq!(
        load_file(&cwd_scene).unwrap().source_files()[0],
        canonical(&p)
    );
    // A scene built in memory lists nothing.
    assert!(Scene::demo("cube").unwrap().source_files().is_empty());
}

/// Values decoded from an external buffer (another file's bytes) never appear in a
/// message: the element is named instead.
#[test]
fn errors_do_not_quote_values_read_from_a_buffer_file() {
    let d = Dirs::new("quote");
    let secret = 123_456.79_f32;
    for (name, corners, needle) in [
        (
            "nan.gltf",
            [[0., 0., 0.], [secret, f32::NAN, 0.], [0., 1., 0.]],
            "element 1 is not finite",
        ),
        (
            "big.gltf",
            [[0., 0., 0.], [secret, 4e30, 0.], [0., 1., 0.]],
            "element 1 is beyond the largest coordinate",
        ),
    ] {
        d.write("scene/v.bin", triangle_bin(corners));
        let p = d.write(&format!("scene/{name}"), gltf("v.bin"));
        let text = load_err(&p).to_string();
        assert!(text.contains(needle), "{text}");
        for quoted in ["123456", "1.23", "4e30", "4000000"] {
            assert!(!text.contains(quoted), "{text}");
        }
    }
    // Placed by a scene file far out: the scene's error names the object, not the
    // buffer's values.
    d.write(
        "scene/v.bin",
        triangle_bin([[0., 0., 0.], [secret, 0., 0.], [0., 1., 0.]]),
    );
    d.write("scene/t.gltf", gltf("v.bin"));
    let p = d.write(
        "scene/far.toml",
        "[[object]]\nmesh = \"t.gltf\"\nscale = 1e28\n",
    );
    let text = load_err(&p).to_string();
    assert!(text.contains("beyond the largest coordinate"), "{text}");
    assert!(!text.contains("123456") && !text.contains("1.23"), "{text}");
}
